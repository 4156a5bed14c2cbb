"""MATLAB ``.mat`` force records: :func:`read_mat` (``scipy.io.loadmat``; v7.3 files, which
are HDF5, through ``h5py``, an optional extra).

The variables of the file (and the fields of its structs, named ``s.field``) that hold
numbers are read by their names: a vector or matrix of samples is a channel (a matrix's
columns are ``data(:,1)``, ``data(:,2)``...), one named like a time column (``time_s``,
``t``, ``time [ms]``) is the time vector, a scalar named ``fs``, ``rate_Hz``,
``sample_rate`` or ``sampling_rate`` is the sampling rate and one named ``dt`` the step.
A channel named like a force column (``force_N``, ``F_kN``) declares its unit.
"""

from __future__ import annotations

import numpy as np

from .channels import Channel, channel_recording, import_extra, pick_channel
from .columns import FORCE_NAMES, parse_column
from .errors import DataError
from .recording import MIN_SAMPLES, Recording
from .sources import as_source, existing_file

__all__ = ["read_mat"]

_RATE_NAMES = {
    "fs",
    "rate",
    "rate_hz",
    "sr",
    "sample_rate",
    "samplerate",
    "sampling_rate",
    "sample_rate_hz",
    "sampling_rate_hz",
}
_STEP_NAMES = {"dt", "dt_s"}
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _is_hdf5(path) -> bool:
    """MATLAB v7.3: an HDF5 file, its signature at 0 or after a 512-byte (or larger) user block."""
    with open(path, "rb") as fh:
        head = fh.read(4096)
    return any(head[k : k + 8] == _HDF5_SIGNATURE for k in (0, 512, 1024, 2048))


def _variables_v5(path, source: str) -> dict[str, np.ndarray]:
    # lazy: scipy.io costs 0.1–0.2 s at import
    from scipy.io import loadmat
    from scipy.io.matlab import MatReadError

    try:
        raw = loadmat(path, simplify_cells=True)
    except (MatReadError, ValueError, TypeError, OSError) as e:
        raise DataError(f"{source}: cannot read it as a MATLAB .mat file ({e})") from None
    out: dict[str, np.ndarray] = {}

    def walk(prefix: str, value) -> None:
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else k, v)
        elif isinstance(value, (int, float, np.ndarray, np.number)) and not isinstance(value, bool):
            a = np.asarray(value)
            if a.dtype.kind in "iuf":
                out[prefix] = a

    walk("", {k: v for k, v in raw.items() if not k.startswith("__")})
    return out


def _variables_v73(path, source: str) -> dict[str, np.ndarray]:
    h5py = import_extra("h5py", "MATLAB v7.3 (HDF5) .mat files")
    out: dict[str, np.ndarray] = {}
    try:
        with h5py.File(path, "r") as f:

            def visit(name, obj):
                if not isinstance(obj, h5py.Dataset) or name.startswith("#"):
                    return
                if obj.attrs.get("MATLAB_class", b"") in (b"char", "char", b"logical", "logical"):
                    return
                if obj.dtype.kind in "iuf":
                    out[name.replace("/", ".")] = np.asarray(obj[()]).T  # MATLAB is column-major

            f.visititems(visit)
    except OSError as e:
        raise DataError(
            f"{source}: cannot read it as a MATLAB v7.3 (HDF5) .mat file ({e})"
        ) from None
    return out


def _channels(variables: dict[str, np.ndarray], source: str) -> list[Channel]:
    """Channels with the file's time vector or rate attached."""
    rate = time = None
    channels: list[tuple[str, np.ndarray, str | None]] = []
    for name, a in variables.items():
        leaf = name.rsplit(".", 1)[-1]
        if a.size == 1 and leaf.lower() in _RATE_NAMES | _STEP_NAMES:
            v = float(a.reshape(-1)[0])
            if not (np.isfinite(v) and v > 0):
                raise DataError(f"{source}: {name}={v!r} is not a sampling rate (or step)")
            rate = 1.0 / v if leaf.lower() in _STEP_NAMES else v
            continue
        kind, scale = parse_column(leaf)
        if a.ndim > 2 or max(a.shape, default=0) < MIN_SAMPLES:
            continue
        if a.ndim == 2 and min(a.shape) > 1:
            cols = a if a.shape[0] >= a.shape[1] else a.T
            channels += [(f"{name}(:,{j + 1})", cols[:, j], None) for j in range(cols.shape[1])]
        elif kind == "time":
            time = a.reshape(-1) * scale
        elif kind == "time?":
            raise DataError(
                f"{source}: time vector {name!r}: unknown unit {scale!r} (s, ms understood)"
            )
        elif kind == "force" and leaf.lower() not in FORCE_NAMES:  # force_N, F_kN: in newtons
            channels.append((name, a.reshape(-1) * scale, "N"))
        else:  # force_V: in volts; ch1: no unit
            channels.append((name, a.reshape(-1), scale if kind == "force?" else None))
    return [Channel(n, s, u, rate, time) for n, s, u in channels]


def read_mat(
    path,
    *,
    channel: int | str | None = None,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a MATLAB ``.mat`` file (v4 to v7 by scipy, v7.3 by h5py).

    Args:
        path: the .mat file.
        channel: the variable holding the force (a name, ``s.field`` in a struct,
            ``data(:,2)`` for a matrix column) or its number in the listing an error shows;
            needed when the file holds more than one channel.
        rate_Hz: sampling rate, Hz, needed when the file holds neither a rate nor a time vector.
        calibration_N_per_FS: newtons per full scale for integer samples (required then).
        height_m: drop height, m; default from the file name (``hNNN``).
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).

    Returns:
        The :class:`Recording` of the channel (``source`` the file's name).

    Raises:
        DataError: no file at ``path``, not a .mat file, no or an unknown channel (the
            channels are listed), a missing or disagreeing rate, a missing calibration, a
            non-uniform time vector, clipping, too few samples.
        MissingFormatError: a v7.3 file without h5py (``pip install 'rbjax[formats]'``).
    """
    source = as_source(path)
    if existing_file(path).stat().st_size == 0:
        raise DataError(f"{source}: empty file")
    variables = _variables_v73(path, source) if _is_hdf5(path) else _variables_v5(path, source)
    ch = pick_channel(_channels(variables, source), channel, source)
    return channel_recording(
        ch,
        source,
        rate_Hz=rate_Hz,
        calibration_N_per_FS=calibration_N_per_FS,
        height_m=height_m,
        lowpass_Hz=lowpass_Hz,
    )

"""Universal File Format force records: :func:`read_uff` reads the time responses of
dataset 58 through ``pyuff`` (an optional extra, ``pip install 'rbjax[formats]'``).

Each dataset 58 of the file is a channel, named by its first ID line (``id1``) or, when
that is empty, ``node N dir D`` of its response point; the ordinate's unit label (``N``,
``kN``, ``V``...) declares its unit, the abscissa increment its sampling rate.
"""

from __future__ import annotations

import numpy as np

from .channels import Channel, channel_recording, import_extra, pick_channel
from .errors import DataError
from .recording import Recording
from .sources import as_source, existing_file

__all__ = ["read_uff"]

#: dataset 58 ``func_type`` of a time response
_TIME_RESPONSE = 1
#: relative resolution of the abscissa increment, written as E13.5 (6 significant digits)
_INCREMENT_RESOLUTION = 5e-6


def _label(text) -> str | None:
    text = str(text or "").strip()
    return None if text.upper() in ("", "NONE") else text


def _channel(ds: dict, source: str, notes: list[str]) -> Channel:
    name = _label(ds.get("id1")) or f"node {ds.get('rsp_node')} dir {ds.get('rsp_dir')}"
    if ds.get("func_type") != _TIME_RESPONSE:
        raise DataError(
            f"{source}: dataset 58 {name!r} holds function type {ds.get('func_type')}, not a time "
            "response (1)"
        )
    data = np.asarray(ds["data"])
    if np.iscomplexobj(data):
        raise DataError(f"{source}: dataset 58 {name!r} holds complex values, not a force history")
    unit = _label(ds.get("ordinate_axis_units_lab"))
    if ds.get("abscissa_spacing") == 1:
        dx = float(ds["abscissa_inc"])
        if not dx > 0:
            raise DataError(
                f"{source}: dataset 58 {name!r}: abscissa increment {dx!r} s is not a time step"
            )
        rate = 1.0 / dx
        if abs(rate - round(rate)) <= _INCREMENT_RESOLUTION * rate:
            if rate != round(rate):
                notes.append(
                    f"abscissa increment {dx:.6g} s (6 digits in the file) read as {round(rate)} Hz"
                )
            rate = float(round(rate))
        return Channel(name, data, unit, rate)
    x = np.asarray(ds["x"], dtype=np.float64)
    return Channel(
        name, data, unit, time_s=x, time_quantum_s=_INCREMENT_RESOLUTION * float(np.abs(x).max())
    )


def read_uff(
    path,
    *,
    channel: int | str | None = None,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a Universal File Format file (``.uff``, ``.unv``), dataset 58.

    Args:
        path: the UFF file.
        channel: the dataset's ``id1`` (or ``node N dir D``) or its number among the
            file's datasets 58; needed when the file holds more than one.
        rate_Hz: checked against the file's abscissa (to 1e-4) if given.
        calibration_N_per_FS: newtons per unit for a channel in another unit (V...).
        height_m: drop height, m; default from the file name (``hNNN``).
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).

    Returns:
        The :class:`Recording` of the channel (``source`` the file's name).

    Raises:
        DataError: no file at ``path``, not a UFF file or no dataset 58 in it, a dataset
            that is not a real time response, an unknown channel (the channels are listed),
            a ``rate_Hz`` that disagrees with the file, a missing calibration, clipping, too
            few samples.
        MissingFormatError: pyuff is not installed (``pip install 'rbjax[formats]'``).
    """
    source = as_source(path)
    if existing_file(path).stat().st_size == 0:
        raise DataError(f"{source}: empty file")
    pyuff = import_extra("pyuff", "Universal File Format (.uff/.unv) files")
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as e:  # pyuff raises bare Exceptions on malformed files
        raise DataError(f"{source}: cannot read it as a Universal File Format file ({e})") from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    found = [s for s in sets if s.get("type") == 58]
    if not found:
        types = sorted({int(s.get("type", 0)) for s in sets})
        raise DataError(
            f"{source}: no dataset 58 (a function at a node): not a Universal File Format file of "
            f"time responses (dataset types found: {types})"
        )
    notes: list[str] = []
    channels = [_channel(ds, source, notes) for ds in found]
    ch = pick_channel(channels, channel, source)
    return channel_recording(
        ch,
        source,
        rate_Hz=rate_Hz,
        calibration_N_per_FS=calibration_N_per_FS,
        height_m=height_m,
        lowpass_Hz=lowpass_Hz,
        notes=sorted(set(notes)),
    )

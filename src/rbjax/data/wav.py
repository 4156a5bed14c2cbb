"""WAV force records: the RIFF header check, integer PCM codes and their full scale, the
calibration in N per full scale, and :func:`read_wav`."""

from __future__ import annotations

import re
import struct
import warnings
from pathlib import Path

import numpy as np

from .channels import check_calibration, integer_newtons
from .errors import DataError
from .recording import Recording, check_force, file_recording
from .sources import as_source, existing_file

_UNKNOWN_FORMAT_RE = re.compile(r"Unknown wave file format: (\w+)")


def _check_riff_header(path, source: str) -> None:
    """Empty, not RIFF/WAVE, or shorter than its RIFF header declares: DataError."""
    size = Path(path).stat().st_size
    if size == 0:
        raise DataError(f"{source}: empty file")
    with open(path, "rb") as fh:
        head = fh.read(12)
    if len(head) < 12 or head[:4] not in (b"RIFF", b"RIFX", b"RF64") or head[8:12] != b"WAVE":
        raise DataError(f"{source}: not a RIFF/WAVE file: cannot read it as WAV")
    if head[:4] != b"RF64":  # RF64 keeps its sizes in a ds64 chunk
        declared = struct.unpack("<I" if head[:4] == b"RIFF" else ">I", head[4:8])[0] + 8
        if declared > size + 1:  # + 1: a missing pad byte after an odd-sized last chunk
            raise DataError(
                f"{source}: truncated file: the header declares {declared} bytes, only {size} are "
                "present"
            )


def read_wav(
    path,
    *,
    calibration_N_per_FS: float | None = None,
    height_m: float | None = None,
    channel: int | str | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a WAV file (``scipy.io.wavfile``).

    * Integer PCM (8 to 32 bit, plain or WAVE_FORMAT_EXTENSIBLE): samples are divided
      by full scale (2**(bits-1)) and multiplied by ``calibration_N_per_FS``, which is
      then required. Any sample at the most negative or most positive code is
      clipping -> DataError.
    * IEEE float (32 or 64 bit, plain or EXTENSIBLE): samples are newtons, or
      full-scale units multiplied by ``calibration_N_per_FS`` if one is given. A flat
      top (>= 3 consecutive samples at the maximum |value|) is clipping -> DataError.

    Warnings of the WAV reader (unknown chunks skipped, ...) go to ``notes``.

    Args:
        path: WAV file.
        calibration_N_per_FS: newtons per full scale (required for integer PCM).
        height_m: drop height in metres; default: from the file name, else None.
        channel: channel to read from a multi-channel file (0-based; required then).
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).

    Returns:
        The :class:`Recording` of the channel (``source`` the file's name).

    Raises:
        DataError: no file at ``path``; an empty, truncated or not a WAV file, an
            unsupported format, a missing or invalid channel, a missing calibration,
            clipping, non-finite or too few samples.
    """
    from scipy.io import wavfile  # lazy: scipy.io costs 0.1–0.2 s at import (RESULTS.md)

    source = as_source(path)
    _check_riff_header(existing_file(path), source)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", wavfile.WavFileWarning)
        try:
            rate, data = wavfile.read(path)
        except ValueError as e:
            m = _UNKNOWN_FORMAT_RE.search(str(e))
            if m:
                raise DataError(
                    f"{source}: WAV format {m.group(1)} is not supported (PCM or IEEE float)"
                ) from None
            raise DataError(f"{source}: cannot read it as WAV ({e})") from None
    notes = []
    for w in caught:
        if issubclass(w.category, wavfile.WavFileWarning):
            notes.append(f"WAV reader: {w.message}")
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if rate <= 0:
        raise DataError(f"{source}: corrupt fmt chunk (rate={rate})")
    ch = 1 if data.ndim == 1 else data.shape[1]
    if ch > 1 and channel is None:
        raise DataError(f"{source}: {ch} channels: pass channel= (0 to {ch - 1})")
    if isinstance(channel, str) and not channel.isdigit():
        raise DataError(
            f"{source}: channel={channel!r}: WAV channels have no names; pass a number 0 to "
            f"{ch - 1}"
        )
    c = 0 if channel is None else int(channel)
    if not 0 <= c < ch:
        raise DataError(f"{source}: channel={channel} out of range (file has {ch})")
    samples = data if data.ndim == 1 else data[:, c]
    if samples.dtype.kind in "iu":
        force = integer_newtons(samples, calibration_N_per_FS, source, "PCM WAV")
        check_force(force, source, flat_top=False)
    else:
        force = samples.astype(np.float64)
        if calibration_N_per_FS is not None:
            force = force * check_calibration(calibration_N_per_FS, source)
        check_force(force, source)
    return file_recording(
        source,
        force,
        rate,
        height_m,
        calibration_N_per_FS=calibration_N_per_FS,
        lowpass_Hz=lowpass_Hz,
        notes=notes,
    )

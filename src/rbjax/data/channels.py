"""Channels of the files acquisition systems export (MAT, UFF, TDMS, WAV): picking one by
name or number, its time base, and its samples in newtons (units, calibration, integer full
scale and clipping), the same rules for every format."""

from __future__ import annotations

import importlib
import math
from typing import NamedTuple

import numpy as np

from .columns import FORCE_UNITS, infer_rate
from .errors import ClippedRecordError, DataError, MissingFormatError
from .recording import MIN_SAMPLES, Recording, check_force, file_recording

#: The optional dependencies of the formats, installed by ``pip install 'rbjax[formats]'``.
FORMATS_EXTRA = "formats"


class Channel(NamedTuple):
    """One channel of a file: its name, samples and what the file says about them.

    unit: the unit the file declares (``"N"``, ``"kN"``, ``"V"``...), or None.
    rate_Hz: the sampling rate the file declares, or None.
    time_s: the channel's time vector, when the file gives one instead of a rate.
    time_quantum_s: the resolution the times are written with (0: binary, exact).
    """

    name: str
    samples: np.ndarray
    unit: str | None = None
    rate_Hz: float | None = None
    time_s: np.ndarray | None = None
    time_quantum_s: float = 0.0


def import_extra(module: str, what: str):
    """``importlib.import_module(module)``, or MissingFormatError naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise MissingFormatError(
            f"reading {what} needs the package {module!r}, an optional extra: "
            f"pip install 'rbjax[{FORMATS_EXTRA}]'"
        ) from None


def pick_channel(channels: list[Channel], channel: int | str | None, source: str) -> Channel:
    """The channel named (exact name, or the part after the last ``/``) or numbered (0-based).

    Without ``channel`` the file must hold exactly one force channel. A name or number
    that does not exist: DataError listing the channels.
    """
    listing = ", ".join(f"{k}: {c.name!r}" for k, c in enumerate(channels))
    if not channels:
        raise DataError(
            f"{source}: no numeric channel of at least {MIN_SAMPLES} samples in this file"
        )
    if channel is None:
        if len(channels) == 1:
            return channels[0]
        raise DataError(
            f"{source}: {len(channels)} channels ({listing}): pass channel= (a name or a number)"
        )
    if isinstance(channel, (int, np.integer)) and not isinstance(channel, bool):
        if 0 <= int(channel) < len(channels):
            return channels[int(channel)]
        raise DataError(
            f"{source}: channel={channel} out of range 0..{len(channels) - 1} ({listing})"
        )
    name = str(channel)
    hits = [c for c in channels if c.name == name] or [
        c for c in channels if c.name.rsplit("/", 1)[-1] == name
    ]
    if len(hits) == 1:
        return hits[0]
    why = "names more than one" if hits else "is not among the"
    raise DataError(
        f"{source}: channel={name!r} {why} channels ({listing}); pass a full name or a number"
    )


def check_calibration(calibration_N_per_FS, source: str) -> float:
    cal = float(calibration_N_per_FS)
    if not (math.isfinite(cal) and cal != 0):
        raise DataError(
            f"{source}: calibration_N_per_FS={calibration_N_per_FS!r} must be finite and non-zero"
        )
    return cal


def integer_codes(samples: np.ndarray) -> tuple[np.ndarray, float, int, int]:
    """Integer samples -> (codes, full scale, min code, max code).

    8-bit unsigned samples are offset by 128 (WAV's 8-bit PCM); wider ones are signed and
    may be left-justified in their container (24 bit in int32: the low byte of every
    sample is 0), so the largest code is the container's maximum rounded down to the step
    every sample is a multiple of.
    """
    if samples.dtype == np.uint8:
        codes, bits = samples.astype(np.int64) - 128, 8
    else:
        codes, bits = samples.astype(np.int64), 8 * samples.dtype.itemsize
    full = 1 << (bits - 1)
    used = int(np.bitwise_or.reduce(codes))
    step = (used & -used) or 1
    return codes, float(full), -full, full - step


def integer_newtons(
    samples: np.ndarray, calibration_N_per_FS, source: str, what: str
) -> np.ndarray:
    """Integer samples in newtons: codes / full scale × calibration; a code at either end of
    the range is clipping (ClippedRecordError); no calibration: DataError saying what to pass."""
    if calibration_N_per_FS is None:
        raise DataError(
            f"{source}: integer {what}: pass calibration_N_per_FS= "
            "(newtons per full scale) to turn samples into newtons"
        )
    codes, fs, lo, hi = integer_codes(samples)
    clipped = np.flatnonzero((codes <= lo) | (codes >= hi))
    if clipped.size:
        raise ClippedRecordError(
            f"{source}: clipped: {clipped.size} sample(s) at full scale (first at sample "
            f"{int(clipped[0])}); the peak force is not known"
        )
    return codes / fs * check_calibration(calibration_N_per_FS, source)


def channel_newtons(ch: Channel, calibration_N_per_FS, source: str) -> np.ndarray:
    """A channel's samples in newtons, checked (length, finite, clipping).

    Integer samples: full scale × ``calibration_N_per_FS`` (required). Floating-point
    samples in N or kN: as declared (a calibration is then refused as ambiguous); in
    another unit (V, mV...): × ``calibration_N_per_FS``, newtons per that unit (required);
    no unit: newtons, or × the calibration if one is given.
    """
    x = np.asarray(ch.samples)
    if x.dtype.kind in "iu":
        force = integer_newtons(x, calibration_N_per_FS, source, f"samples in channel {ch.name!r}")
        check_force(force, source, flat_top=False)
        return force
    if x.dtype.kind != "f":
        raise DataError(f"{source}: channel {ch.name!r} holds {x.dtype} samples, not numbers")
    unit = None if ch.unit is None or not ch.unit.strip() else ch.unit.strip()
    force = x.astype(np.float64)
    if unit is not None and unit.lower() in FORCE_UNITS:
        if calibration_N_per_FS is not None:
            raise DataError(
                f"{source}: channel {ch.name!r} is already in {unit}: do not pass "
                "calibration_N_per_FS"
            )
        force = force * FORCE_UNITS[unit.lower()]
    elif unit is not None and calibration_N_per_FS is None:
        raise DataError(
            f"{source}: channel {ch.name!r} is in {unit!r}: pass calibration_N_per_FS= "
            f"(newtons per {unit}) to turn it into newtons"
        )
    elif calibration_N_per_FS is not None:
        force = force * check_calibration(calibration_N_per_FS, source)
    check_force(force, source)
    return force


def channel_recording(
    ch: Channel,
    source: str,
    *,
    rate_Hz: float | None,
    calibration_N_per_FS: float | None,
    height_m: float | None,
    lowpass_Hz: float | None,
    notes=(),
) -> Recording:
    """The Recording of one channel: rate from the file (its rate or time vector), checked
    against ``rate_Hz`` if both are known (to 1e-4); samples by :func:`channel_newtons`."""
    force = channel_newtons(ch, calibration_N_per_FS, source)
    notes = list(notes)
    rate = ch.rate_Hz
    if ch.time_s is not None:
        t = np.asarray(ch.time_s, dtype=np.float64).reshape(-1)
        if t.size != force.size:
            raise DataError(
                f"{source}: the time vector has {t.size} samples, channel {ch.name!r} {force.size}"
            )
        rate, _, more = infer_rate(t, ch.time_quantum_s, source)
        notes += more
    if rate is not None and abs(rate - round(rate)) <= 1e-9 * rate:
        rate = float(round(rate))  # 1 / (1 / 44100 s) in floating point
    if rate is not None and rate_Hz is not None and abs(float(rate_Hz) - rate) > 1e-4 * rate:
        raise DataError(f"{source}: rate_Hz={rate_Hz!r} disagrees with the file ({rate:.8g} Hz)")
    if rate is None:
        if rate_Hz is None:
            raise DataError(
                f"{source}: the file gives no sampling rate for channel {ch.name!r}: pass rate_Hz="
            )
        rate = float(rate_Hz)
    return file_recording(
        source,
        force,
        rate,
        height_m,
        calibration_N_per_FS=calibration_N_per_FS,
        lowpass_Hz=lowpass_Hz,
        notes=notes,
    )

"""Force-plate recordings in: reading, checking, conditioning and averaging (NumPy).

This is the data edge of rbjax. Everything here is plain NumPy and returns frozen
dataclasses holding read-only NumPy arrays; the JAX model code takes ``force_N`` /
``rate_Hz`` / ``onset_s`` from a :class:`Recording`.

Reading
    :func:`read_csv`, :func:`read_wav`, :func:`read_npy` read one file each;
    :func:`load` reads many files (or a directory) and resolves each drop height from
    an argument, a manifest CSV or the file name (``h100_d1.csv`` -> 1.00 m).
Checking
    Bad data raise :class:`DataError` (a ``ValueError``) naming the file, or warn with
    :class:`DataWarning`; nothing is silently repaired. Checked: empty or truncated
    files, missing/unknown columns, non-numeric values, NaN/inf, fewer than
    ``MIN_SAMPLES`` samples, a non-uniform time column, clipping, no impact, an impact
    running off the end, mixed sample rates, an unknown drop height.
Conditioning
    :func:`find_impacts` lists every impact of a raw record; :func:`condition` keeps
    one, subtracts the pre-trigger baseline, optionally low-passes, locates the onset
    to a fraction of a sample (:func:`locate_onset`) and cuts a window that starts a
    fixed ``pre_onset_s`` before the onset, so that records of one height line up.
Averaging
    :func:`average` averages repeated drops coherently, in the frequency domain (as in
    the paper's section 3) or in the time domain, after sub-sample onset alignment.

The example recordings shipped with the package are in :func:`examples_dir`.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import os
import re
import struct
import warnings
import wave
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .filters import butter_lowpass_sos, sosfilt_np

__all__ = [
    "DataError",
    "DataWarning",
    "Recording",
    "Impact",
    "MIN_SAMPLES",
    "examples_dir",
    "load_examples",
    "height_from_name",
    "read_csv",
    "read_wav",
    "read_npy",
    "load",
    "estimate_noise_rms_N",
    "find_impacts",
    "locate_onset",
    "condition",
    "fractional_shift",
    "average",
]

MIN_SAMPLES = 100
"""Fewer samples than this in a file is treated as a truncated file."""

EXAMPLES_LOWPASS_HZ = 1250.0
"""Cutoff of the (declared) measuring chain of the shipped emulated recordings, Hz."""

_HEIGHT_RE = re.compile(r"(?<![A-Za-z0-9])h(\d{3})(?!\d)", re.IGNORECASE)


class DataError(ValueError):
    """A recording cannot be used as it is; the message names the file and the problem."""


class DataWarning(UserWarning):
    """A recording is usable but something about it deserves attention."""


# --------------------------------------------------------------------------------------
# Recording
# --------------------------------------------------------------------------------------


def _frozen_array(x) -> np.ndarray:
    a = np.array(x, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


@dataclasses.dataclass(frozen=True, eq=False)
class Recording:
    """One force record of one drop, sampled uniformly.

    Attributes:
      source: file name the record came from (or a description, e.g. for averages).
      height_m: drop height in metres, or ``None`` when unknown.
      rate_Hz: sampling rate in Hz.
      force_N: force samples in newtons, 1-D float64, read-only; sample ``i`` is at
        ``i / rate_Hz`` seconds from the first sample.
      onset_s: sub-sample time of the impact onset (see :func:`locate_onset`), seconds
        from the first sample of ``force_N``; ``None`` until :func:`condition` sets it.
      calibration_N_per_FS: calibration used to scale integer/normalised samples to
        newtons (N per full scale), or ``None``.
      lowpass_Hz: cutoff of the causal low-pass the record went through (measuring chain
        or :func:`condition`), Hz, if known/declared; ``None`` if unknown.
      notes: human-readable warnings and processing notes, oldest first.
    """

    source: str
    height_m: float | None
    rate_Hz: float
    force_N: np.ndarray
    onset_s: float | None = None
    calibration_N_per_FS: float | None = None
    lowpass_Hz: float | None = None
    notes: tuple[str, ...] = ()

    def __post_init__(self):
        rate = float(self.rate_Hz)
        if not (math.isfinite(rate) and rate > 0):
            raise DataError(f"{self.source}: rate_Hz={self.rate_Hz!r} must be positive and finite")
        object.__setattr__(self, "rate_Hz", rate)
        f = _frozen_array(self.force_N)
        if f.ndim != 1 or f.size == 0:
            raise DataError(f"{self.source}: force_N must be a non-empty 1-D array; got shape {f.shape}")
        if not np.all(np.isfinite(f)):
            raise DataError(f"{self.source}: force_N contains NaN or inf")
        object.__setattr__(self, "force_N", f)
        if self.height_m is not None:
            h = float(self.height_m)
            if not (math.isfinite(h) and h > 0):
                raise DataError(f"{self.source}: height_m={self.height_m!r} must be positive and finite")
            object.__setattr__(self, "height_m", h)
        for name in ("onset_s", "calibration_N_per_FS", "lowpass_Hz"):
            v = getattr(self, name)
            if v is not None:
                v = float(v)
                if not math.isfinite(v):
                    raise DataError(f"{self.source}: {name}={v!r} must be finite")
                object.__setattr__(self, name, v)
        object.__setattr__(self, "notes", tuple(str(n) for n in self.notes))

    # ----- derived quantities --------------------------------------------------------
    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.force_N.size)

    @property
    def duration_s(self) -> float:
        """Length of the record, ``n_samples / rate_Hz`` seconds."""
        return self.n_samples / self.rate_Hz

    @property
    def time_s(self) -> np.ndarray:
        """Sample times in seconds from the first sample, ``arange(n) / rate_Hz``."""
        return np.arange(self.n_samples) / self.rate_Hz

    @property
    def peak_N(self) -> float:
        """Largest force sample, N."""
        return float(self.force_N.max())

    @property
    def noise_rms_N(self) -> float:
        """Robust rms of the noise, N (see :func:`estimate_noise_rms_N`)."""
        return estimate_noise_rms_N(self.force_N)

    def replace(self, **changes) -> "Recording":
        """A copy with the given fields changed (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)

    def contact_window(self, *, fraction: float = 0.05) -> tuple[float, float]:
        """``(start_s, end_s)``: times the force crosses ``fraction * peak`` up, then down.

        Times in seconds from the first sample, interpolated to a fraction of a sample
        (rising edge exactly as :func:`locate_onset`; falling edge by cubic
        interpolation too). ``end_s - start_s`` is a contact time at that level. Assumes
        the baseline has been removed (a conditioned record).
        """
        x = self.force_N
        ip = int(np.argmax(x))
        level = fraction * x[ip]
        start = _rising_crossing(x, ip, level, self.source)
        # falling edge: first sample after the peak below the level
        below = np.flatnonzero(x[ip:] < level)
        if below.size == 0:
            raise DataError(f"{self.source}: the force does not fall below {level:.4g} N after the peak")
        j = ip + int(below[0])  # x[j-1] >= level > x[j]
        u = _solve_crossing(x, j, -level, sign=-1.0)
        return start / self.rate_Hz, (j - 1 + u) / self.rate_Hz

    def aligned(self, onset_s: float, *, method: str = "fourier") -> "Recording":
        """The record shifted in time so that its onset lands at ``onset_s`` (same length).

        Sub-sample shift by :func:`fractional_shift` (``"fourier"``: band-limited,
        ``"linear"`` or ``"cubic"`` interpolation); samples shifted in from outside the
        record are zero (meaningful for a baseline-subtracted record).
        """
        if self.onset_s is None:
            raise DataError(f"{self.source}: no onset_s; condition() the recording first")
        shift = (float(onset_s) - self.onset_s) * self.rate_Hz
        y = fractional_shift(self.force_N, shift, method=method)
        return self.replace(force_N=y, onset_s=float(onset_s))


class Impact(NamedTuple):
    """One impact found by :func:`find_impacts` (a plain tuple ``(start, end, peak)``).

    start_index: first sample above the threshold; end_index: one past the last sample
    above the threshold (``== n`` when the force is still above it at the last sample);
    peak_N: largest force of the impact above the record's baseline level, N.
    """

    start_index: int
    end_index: int
    peak_N: float


# --------------------------------------------------------------------------------------
# examples and names
# --------------------------------------------------------------------------------------


def examples_dir() -> Path:
    """Folder of the emulated rubber-ball recordings shipped inside the package.

    ``hHHH_dN.csv`` (drop N from HHH cm, 0.1 s at 44.1 kHz) and
    ``raw_h100_two_impacts.wav`` (1.5 s, float32 newtons, two impacts); see the
    README.md in that folder.
    """
    try:
        from importlib.resources import files

        p = Path(str(files("rbjax") / "examples" / "emulated-rubber-ball"))
    except Exception:  # pragma: no cover - zipped installs etc.
        p = Path(__file__).resolve().parent / "examples" / "emulated-rubber-ball"
    if not p.is_dir():  # pragma: no cover
        p = Path(__file__).resolve().parent / "examples" / "emulated-rubber-ball"
    return p


def load_examples(pattern: str = "h*.csv") -> list[Recording]:
    """The shipped example recordings matching ``pattern`` (default: the 30 CSV drops).

    Heights come from the file names; ``lowpass_Hz`` is set to the declared measuring
    chain cutoff of these files (1250 Hz, 4th-order causal).
    """
    paths = sorted(examples_dir().glob(pattern))
    if not paths:
        raise DataError(f"no example file matches {pattern!r} in {examples_dir()}")
    return load(paths, lowpass_Hz=EXAMPLES_LOWPASS_HZ)


def height_from_name(name: str | os.PathLike) -> float | None:
    """Drop height in metres from a file name containing ``hNNN`` (centimetres), else None.

    ``h100_d1.csv`` -> 1.0, ``raw_h020_x.wav`` -> 0.2. The three digits must not be
    part of a longer number and the ``h`` must not follow a letter or digit.
    """
    m = _HEIGHT_RE.search(Path(name).stem)
    if m is None:
        return None
    return int(m.group(1)) / 100.0


# --------------------------------------------------------------------------------------
# checks shared by the readers
# --------------------------------------------------------------------------------------


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """(length, start) of the longest run of True in a 1-D boolean array."""
    if not mask.any():
        return 0, -1
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1)
    k = int(np.argmax(ends - starts))
    return int(ends[k] - starts[k]), int(starts[k])


def _check_force(force: np.ndarray, source: str, *, flat_top: bool = True) -> None:
    """Length, finiteness, constant signal and (for float data) flat-top clipping."""
    n = force.size
    if n == 0:
        raise DataError(f"{source}: no samples (empty file?)")
    if n < MIN_SAMPLES:
        raise DataError(
            f"{source}: only {n} samples (at least {MIN_SAMPLES} needed); truncated file?"
        )
    bad = ~np.isfinite(force)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"{source}: {int(bad.sum())} sample(s) are NaN or inf (first at sample {i}: {force[i]!r})"
        )
    if np.ptp(force) == 0:
        raise DataError(f"{source}: all {n} samples equal {force[0]!r}: no signal")
    if flat_top:
        amax = float(np.abs(force).max())
        mask = np.abs(force) >= amax * (1 - 1e-9)
        run, start = _longest_run(mask)
        if run >= 3:
            raise DataError(
                f"{source}: clipped: {run} consecutive samples (from sample {start}) sit at the "
                f"maximum |force| {amax:.6g} (a flat top); the peak force is not known"
            )


def _as_source(path) -> str:
    return Path(path).name if isinstance(path, (str, os.PathLike)) else str(path)


def _check_height(height_m, source):
    if height_m is None:
        return None
    h = float(height_m)
    if not (math.isfinite(h) and h > 0):
        raise DataError(f"{source}: drop height {height_m!r} m must be positive and finite")
    return h


# --------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------

_TIME_NAMES = {"time": 1.0, "t": 1.0}
_FORCE_NAMES = {"force": 1.0, "f": 1.0}
_TIME_UNITS = {None: 1.0, "s": 1.0, "sec": 1.0, "ms": 1e-3}
_FORCE_UNITS = {None: 1.0, "n": 1.0, "kn": 1e3}
_COL_RE = re.compile(r"^\s*([a-z]+)\s*(?:[_\s]\s*([a-z]+)|[\[(]\s*([a-z]+)\s*[\])])?\s*$")


def _parse_column(name: str):
    """('time'|'force'|None, scale) for a header field such as ``time_s``, ``F [kN]``."""
    m = _COL_RE.match(name.strip().lower())
    if not m:
        return None, None
    base, unit = m.group(1), m.group(2) or m.group(3)
    if base in _TIME_NAMES:
        if unit not in _TIME_UNITS:
            return "time?", unit
        return "time", _TIME_UNITS[unit]
    if base in _FORCE_NAMES:
        if unit not in _FORCE_UNITS:
            return "force?", unit
        return "force", _FORCE_UNITS[unit]
    return None, None


def _decimals(s: str) -> int | None:
    s = s.strip()
    if "e" in s.lower():
        return None
    if "." not in s:
        return 0
    return len(s.split(".", 1)[1])


def _infer_rate(t: np.ndarray, quantum_s: float, source: str) -> tuple[float, float, list[str]]:
    """Uniform-sampling check of a time column; returns (rate_Hz, t0_s, notes)."""
    dt_steps = np.diff(t)
    if np.any(dt_steps <= 0):
        i = int(np.argmax(dt_steps <= 0))
        raise DataError(
            f"{source}: time column is not strictly increasing (sample {i + 1}: "
            f"{t[i + 1]!r} s after {t[i]!r} s)"
        )
    n = t.size
    i = np.arange(n, dtype=np.float64)
    dt, t0 = np.polyfit(i, t, 1)
    resid = t - (t0 + dt * i)
    tol = 0.5 * quantum_s * 1.01 + 0.01 * dt
    worst = float(np.abs(resid).max())
    if worst > tol:
        k = int(np.argmax(np.abs(resid)))
        raise DataError(
            f"{source}: non-uniform time column: sample {k} is {resid[k] / dt:+.3f} samples off a "
            f"uniform grid of {1 / dt:.6g} Hz (tolerance {tol / dt:.3f} samples); resample first"
        )
    notes = []
    if quantum_s > 0.1 * dt:
        notes.append(
            f"time column resolution {quantum_s:g} s is coarse for {1 / dt:.6g} Hz sampling; "
            "the rate comes from a fit over the whole column"
        )
    rate = 1.0 / dt
    cand = float(round(rate))
    if cand > 0:
        t0c = float(np.mean(t - i / cand))
        if np.abs(t - (t0c + i / cand)).max() <= tol:
            rate, t0 = cand, t0c
    return float(rate), float(t0), notes


def read_csv(
    path,
    *,
    rate_Hz: float | None = None,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a CSV file.

    Columns: a time column (``time_s``, ``time``, ``t``; units ``s`` or ``ms`` in the
    name, e.g. ``time [ms]``) and a force column (``force_N``, ``force``, ``F``; units
    ``N`` or ``kN``), names case-insensitive; or a single force column (with or without
    header), then ``rate_Hz`` is required. A header-less file with two numeric columns is
    read as (time in s, force in N). Delimiter ``,``, ``;`` or tab; lines starting with
    ``#`` are skipped.

    The sampling rate is inferred from the time column, which must be uniform to 1 %
    of a sample beyond its printed resolution; a rate within that tolerance of a whole
    number of Hz is rounded to it (``44100.01`` -> ``44100``). If ``rate_Hz`` is also
    given it must agree with the column to 1e-4.

    Args:
      path: CSV file.
      rate_Hz: sampling rate in Hz, needed without a time column.
      height_m: drop height in metres; default: from the file name (``hNNN``), else None.
      lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).

    Raises:
      DataError: empty or truncated file, missing/unknown columns, non-numeric or
        non-finite values, fewer than ``MIN_SAMPLES`` rows, non-uniform time, clipping.
    """
    source = _as_source(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise DataError(f"{source}: not a text CSV file ({e})") from None
    lines = [(k + 1, ln) for k, ln in enumerate(text.splitlines()) if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise DataError(f"{source}: empty file")
    first = lines[0][1]
    delim = max([",", ";", "\t"], key=first.count)
    if first.count(delim) == 0:
        delim = ","
    rows = list(csv.reader(io.StringIO("\n".join(ln for _, ln in lines)), delimiter=delim))
    linenos = [k for k, _ in lines]

    def _isnum(s):
        try:
            float(s)
            return True
        except ValueError:
            return False

    header = rows[0]
    has_header = not all(_isnum(f) for f in header)
    t_col = f_col = None
    t_scale = f_scale = 1.0
    if has_header:
        kinds = [_parse_column(h) for h in header]
        for k, (kind, val) in enumerate(kinds):
            if kind in ("time?", "force?"):
                raise DataError(
                    f"{source}: column {header[k]!r}: unknown unit {val!r} "
                    f"({'s, ms' if kind == 'time?' else 'N, kN'} understood)"
                )
        t_cols = [k for k, (kind, _) in enumerate(kinds) if kind == "time"]
        f_cols = [k for k, (kind, _) in enumerate(kinds) if kind == "force"]
        if len(t_cols) > 1 or len(f_cols) > 1:
            raise DataError(f"{source}: ambiguous columns {header}: more than one time or force column")
        if not f_cols:
            if len(header) == 1 and not t_cols:
                raise DataError(
                    f"{source}: column {header[0]!r} is not a force column (expected force_N, force or F)"
                )
            raise DataError(
                f"{source}: no force column among {header} (expected force_N, force or F, "
                "case-insensitive, optionally with a unit N or kN)"
            )
        f_col, f_scale = f_cols[0], kinds[f_cols[0]][1]
        if t_cols:
            t_col, t_scale = t_cols[0], kinds[t_cols[0]][1]
        data_rows, data_lines = rows[1:], linenos[1:]
        n_fields = len(header)
    else:
        n_fields = len(header)
        if n_fields == 1:
            f_col = 0
        elif n_fields == 2:
            t_col, f_col = 0, 1
        else:
            raise DataError(
                f"{source}: {n_fields} columns without a header; name them (time_s, force_N)"
            )
        data_rows, data_lines = rows, linenos
    if not data_rows:
        raise DataError(f"{source}: no data rows after the header (empty or truncated file)")

    t_txt, f_txt = [], []
    for row, ln in zip(data_rows, data_lines):
        if len(row) != n_fields or any(not c.strip() for c in row):
            raise DataError(
                f"{source}: line {ln} has {sum(bool(c.strip()) for c in row)} of {n_fields} fields "
                f"({delim.join(row)!r}); truncated file?"
            )
        f_txt.append(row[f_col])
        if t_col is not None:
            t_txt.append(row[t_col])
    try:
        force = np.array(f_txt, dtype=np.float64) * f_scale
        t = np.array(t_txt, dtype=np.float64) * t_scale if t_col is not None else None
    except ValueError:
        cols = [(f_col, f_txt)] + ([(t_col, t_txt)] if t_col is not None else [])
        for col, vals in cols:
            for k, v in enumerate(vals):
                if not _isnum(v):
                    raise DataError(
                        f"{source}: line {data_lines[k]}: non-numeric value {v.strip()!r} in column {col + 1}"
                    ) from None
        raise  # pragma: no cover
    if t is not None:
        bad = ~np.isfinite(t)
        if bad.any():
            k = int(np.argmax(bad))
            raise DataError(f"{source}: line {data_lines[k]}: time {t_txt[k].strip()!r} is not finite")
    _check_force(force, source)

    notes = []
    if t is not None:
        dec = [_decimals(s) for s in t_txt[: min(len(t_txt), 1000)]]
        quantum = 0.0 if any(d is None for d in dec) else 10.0 ** (-max(dec)) * t_scale
        rate_t, t0, more = _infer_rate(t, quantum, source)
        notes += more
        if t0 != 0 and abs(t0) > 0.5 / rate_t:
            notes.append(f"time column starts at {t0:.9g} s; times here count from the first sample")
        if rate_Hz is not None:
            if abs(float(rate_Hz) - rate_t) > 1e-4 * rate_t:
                raise DataError(
                    f"{source}: rate_Hz={rate_Hz!r} disagrees with the time column ({rate_t:.8g} Hz)"
                )
            rate_t = float(rate_Hz)
        rate = rate_t
    else:
        if rate_Hz is None:
            raise DataError(f"{source}: no time column: pass rate_Hz=")
        rate = float(rate_Hz)
    if height_m is None:
        height_m = height_from_name(source)
    return Recording(
        source=source,
        height_m=_check_height(height_m, source),
        rate_Hz=rate,
        force_N=force,
        lowpass_Hz=lowpass_Hz,
        notes=tuple(notes),
    )


# --------------------------------------------------------------------------------------
# WAV
# --------------------------------------------------------------------------------------

_WAVE_FORMAT_PCM = 0x0001
_WAVE_FORMAT_IEEE_FLOAT = 0x0003
_WAVE_FORMAT_EXTENSIBLE = 0xFFFE
_GUID_TAIL = b"\x00\x00\x00\x00\x10\x00\x80\x00\x00\xaa\x00\x38\x9b\x71"


def _parse_riff(data: bytes, source: str) -> tuple[dict, bytes]:
    """Minimal RIFF/WAVE parser: (format dict, raw data chunk bytes)."""
    if len(data) == 0:
        raise DataError(f"{source}: empty file")
    if len(data) < 12 or data[:4] != b"RIFF" or data[8:12] != b"WAVE":
        kind = "RF64/RIFX" if data[:4] in (b"RF64", b"RIFX") else "not a RIFF/WAVE"
        raise DataError(f"{source}: {kind} file: cannot read it as WAV")
    pos = 12
    fmt = None
    chunk = None
    while pos + 8 <= len(data):
        cid, size = data[pos : pos + 4], struct.unpack("<I", data[pos + 4 : pos + 8])[0]
        body = data[pos + 8 : pos + 8 + size]
        if cid == b"fmt ":
            if len(body) < 16:
                raise DataError(f"{source}: truncated fmt chunk")
            tag, ch, rate, _byte_rate, block, bits = struct.unpack("<HHIIHH", body[:16])
            if tag == _WAVE_FORMAT_EXTENSIBLE:
                if len(body) < 40:
                    raise DataError(f"{source}: WAVE_FORMAT_EXTENSIBLE fmt chunk too short")
                sub = body[24:40]
                if sub[2:] != _GUID_TAIL:
                    raise DataError(f"{source}: unknown WAVE_FORMAT_EXTENSIBLE subformat")
                tag = struct.unpack("<H", sub[:2])[0]  # the container size (bits) decides decoding
            fmt = dict(tag=tag, channels=ch, rate=rate, block=block, bits=bits)
        elif cid == b"data":
            if len(body) < size:
                raise DataError(
                    f"{source}: truncated file: the data chunk declares {size} bytes, only "
                    f"{len(body)} are present"
                )
            chunk = body
            if fmt is not None:
                break
        pos += 8 + size + (size & 1)
    if fmt is None:
        raise DataError(f"{source}: no fmt chunk (truncated or not a WAV file)")
    if chunk is None:
        raise DataError(f"{source}: no data chunk (truncated file?)")
    return fmt, chunk


def _decode_int(raw: bytes, width: int) -> tuple[np.ndarray, float, int, int]:
    """Integer PCM bytes -> (int64 values, full scale, min code, max code)."""
    if width == 1:
        v = np.frombuffer(raw, dtype=np.uint8).astype(np.int64) - 128
    elif width == 2:
        v = np.frombuffer(raw, dtype="<i2").astype(np.int64)
    elif width == 3:
        b = np.frombuffer(raw, dtype=np.uint8).reshape(-1, 3).astype(np.int64)
        v = b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16)
        v = np.where(v >= 1 << 23, v - (1 << 24), v)
    elif width == 4:
        v = np.frombuffer(raw, dtype="<i4").astype(np.int64)
    else:
        raise ValueError(width)
    fs = float(1 << (8 * width - 1))
    return v, fs, -(1 << (8 * width - 1)), (1 << (8 * width - 1)) - 1


def read_wav(
    path,
    *,
    calibration_N_per_FS: float | None = None,
    height_m: float | None = None,
    channel: int | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a WAV file.

    * Integer PCM (8/16/24/32 bit, read with the standard library's ``wave``, or with
      a small RIFF parser for WAVE_FORMAT_EXTENSIBLE): samples are divided by full scale
      (2**(bits-1)) and multiplied by ``calibration_N_per_FS``, which is then required.
      Any sample at the most negative or most positive code is clipping -> DataError.
    * IEEE float (format tag 3, or EXTENSIBLE with the float subformat; 32 or 64 bit),
      which ``wave`` cannot read: samples are newtons, or full-scale units multiplied by
      ``calibration_N_per_FS`` if one is given. A flat top (>= 3 consecutive samples at
      the maximum |value|) is clipping -> DataError.

    Args:
      path: WAV file.
      calibration_N_per_FS: newtons per full scale (required for integer PCM).
      height_m: drop height in metres; default: from the file name, else None.
      channel: channel to read from a multi-channel file (0-based; required then).
      lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).
    """
    source = _as_source(path)
    data = Path(path).read_bytes()
    fmt, raw = _parse_riff(data, source)
    tag, ch, rate, bits = fmt["tag"], fmt["channels"], fmt["rate"], fmt["bits"]
    if ch < 1 or rate <= 0 or bits <= 0:
        raise DataError(f"{source}: corrupt fmt chunk (channels={ch}, rate={rate}, bits={bits})")
    if ch > 1 and channel is None:
        raise DataError(f"{source}: {ch} channels: pass channel= (0 to {ch - 1})")
    c = 0 if channel is None else int(channel)
    if not 0 <= c < ch:
        raise DataError(f"{source}: channel={channel} out of range (file has {ch})")
    notes = []
    if tag == _WAVE_FORMAT_PCM:
        width = (bits + 7) // 8
        if width not in (1, 2, 3, 4):
            raise DataError(f"{source}: {bits}-bit integer PCM is not supported (8/16/24/32)")
        if calibration_N_per_FS is None:
            raise DataError(
                f"{source}: integer PCM WAV ({bits} bit): pass calibration_N_per_FS= "
                "(newtons per full scale) to turn samples into newtons"
            )
        frames = None
        try:
            with wave.open(str(path), "rb") as w:
                n = w.getnframes()
                width = w.getsampwidth()
                ch = w.getnchannels()
                rate = w.getframerate()
                frames = w.readframes(n)
            if len(frames) < n * width * ch:
                raise DataError(
                    f"{source}: truncated file: {len(frames) // (width * ch)} of {n} frames present"
                )
        except (wave.Error, EOFError):
            frames = None
        if frames is None:  # EXTENSIBLE etc.: use the chunk found by our parser
            frames = raw
        usable = len(frames) - len(frames) % (width * ch)
        if usable != len(frames):
            notes.append(f"{len(frames) - usable} trailing byte(s) of a partial frame ignored")
        codes, fs, lo, hi = _decode_int(frames[:usable], width)
        codes = codes.reshape(-1, ch)[:, c]
        clipped = np.flatnonzero((codes <= lo) | (codes >= hi))
        if clipped.size:
            raise DataError(
                f"{source}: clipped: {clipped.size} sample(s) at full scale (first at sample "
                f"{int(clipped[0])}); the peak force is not known"
            )
        cal = float(calibration_N_per_FS)
        if not (math.isfinite(cal) and cal != 0):
            raise DataError(f"{source}: calibration_N_per_FS={calibration_N_per_FS!r} must be finite and non-zero")
        force = codes.astype(np.float64) / fs * cal
        _check_force(force, source, flat_top=False)
    elif tag == _WAVE_FORMAT_IEEE_FLOAT:
        if bits not in (32, 64):
            raise DataError(f"{source}: {bits}-bit float WAV is not supported (32/64)")
        width = bits // 8
        usable = len(raw) - len(raw) % (width * ch)
        if usable != len(raw):
            notes.append(f"{len(raw) - usable} trailing byte(s) of a partial frame ignored")
        vals = np.frombuffer(raw[:usable], dtype="<f4" if bits == 32 else "<f8").astype(np.float64)
        force = vals.reshape(-1, ch)[:, c]
        if calibration_N_per_FS is not None:
            cal = float(calibration_N_per_FS)
            if not (math.isfinite(cal) and cal != 0):
                raise DataError(f"{source}: calibration_N_per_FS={calibration_N_per_FS!r} must be finite and non-zero")
            force = force * cal
        _check_force(force, source)
    else:
        raise DataError(f"{source}: WAV format tag {tag:#06x} is not supported (PCM or IEEE float)")
    if height_m is None:
        height_m = height_from_name(source)
    return Recording(
        source=source,
        height_m=_check_height(height_m, source),
        rate_Hz=float(rate),
        force_N=force,
        calibration_N_per_FS=calibration_N_per_FS,
        lowpass_Hz=lowpass_Hz,
        notes=tuple(notes),
    )


# --------------------------------------------------------------------------------------
# NPY
# --------------------------------------------------------------------------------------


def read_npy(
    path_or_array,
    *,
    rate_Hz: float,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
    source: str | None = None,
) -> Recording:
    """A force record (newtons) from a ``.npy`` file or an array, sampled at ``rate_Hz``.

    The array must be 1-D (or ``(n, 1)`` / ``(1, n)``). ``source`` names an array in
    messages (default ``"<array>"``); for a file, its name is used and the drop height
    defaults to the one in the name.
    """
    if isinstance(path_or_array, (str, os.PathLike)):
        src = _as_source(path_or_array)
        p = Path(path_or_array)
        if p.stat().st_size == 0:
            raise DataError(f"{src}: empty file")
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError, EOFError) as e:
            raise DataError(f"{src}: cannot read as .npy ({e}); truncated file?") from None
        if isinstance(arr, np.lib.npyio.NpzFile):
            raise DataError(f"{src}: .npz archives are not supported; save one array with np.save")
        if height_m is None:
            height_m = height_from_name(src)
    else:
        src = source or "<array>"
        arr = path_or_array
    try:
        a = np.asarray(arr, dtype=np.float64)
    except (TypeError, ValueError):
        raise DataError(f"{src}: not a numeric array") from None
    if a.ndim == 2 and 1 in a.shape:
        a = a.reshape(-1)
    if a.ndim != 1:
        raise DataError(f"{src}: expected a 1-D force array, got shape {a.shape}")
    if rate_Hz is None:
        raise DataError(f"{src}: pass rate_Hz= (a bare array has no time base)")
    _check_force(a, src)
    return Recording(
        source=src,
        height_m=_check_height(height_m, src),
        rate_Hz=float(rate_Hz),
        force_N=a,
        lowpass_Hz=lowpass_Hz,
    )


# --------------------------------------------------------------------------------------
# many files
# --------------------------------------------------------------------------------------

_SUFFIXES = (".csv", ".wav", ".npy")


def _read_manifest(manifest) -> dict[str, dict]:
    if isinstance(manifest, Mapping):
        out = {}
        for k, v in manifest.items():
            out[Path(k).name] = dict(v) if isinstance(v, Mapping) else {"height_m": v}
        return out
    src = _as_source(manifest)
    text = Path(manifest).read_text(encoding="utf-8-sig")
    rows = [r for r in csv.reader(io.StringIO(text)) if any(c.strip() for c in r)]
    if not rows:
        raise DataError(f"manifest {src}: empty file")
    header = [h.strip().lower() for h in rows[0]]
    if "file" not in header or "height_m" not in header:
        raise DataError(f"manifest {src}: needs columns file,height_m (found {rows[0]})")
    known = {"file", "height_m", "calibration_n_per_fs", "rate_hz", "lowpass_hz"}
    out = {}
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise DataError(f"manifest {src}: line {k} has {len(r)} fields, expected {len(header)}")
        entry = {}
        for h, v in zip(header, r):
            if h == "file" or h not in known:
                continue
            v = v.strip()
            if v == "":
                continue
            try:
                entry[{"calibration_n_per_fs": "calibration_N_per_FS", "rate_hz": "rate_Hz",
                       "lowpass_hz": "lowpass_Hz"}.get(h, h)] = float(v)
            except ValueError:
                raise DataError(f"manifest {src}: line {k}: {h}={v!r} is not a number") from None
        out[Path(r[header.index("file")].strip()).name] = entry
    return out


def load(
    paths_or_dir,
    *,
    height_m: float | None = None,
    manifest=None,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    lowpass_Hz: float | None = None,
    channel: int | None = None,
) -> list[Recording]:
    """Read many recordings: files and/or directories (``*.csv``, ``*.wav``, ``*.npy``).

    A directory expands to its ``*.csv``/``*.wav``/``*.npy`` files, sorted by name (a
    ``manifest.csv`` inside it is used as the manifest, not read as a recording).

    Drop height of each file, first found: the ``height_m`` argument (all files), the
    manifest (a CSV with columns ``file,height_m`` and optionally
    ``calibration_N_per_FS``, ``rate_Hz``, ``lowpass_Hz``, matched on the file name; or
    a mapping ``{file name: height_m}``), the file name (``h100_d1.csv`` -> 1.00 m:
    ``hNNN`` in centimetres). Manifest values of calibration/rate/lowpass override the
    arguments for that file.

    Raises:
      DataError: a file cannot be read (see the readers), a height cannot be known,
        the files have different sample rates, nothing to read.
    """
    if isinstance(paths_or_dir, (str, os.PathLike)):
        items = [paths_or_dir]
    else:
        items = list(paths_or_dir)
    files: list[Path] = []
    for it in items:
        p = Path(it)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file() and q.suffix.lower() in _SUFFIXES)
            mf = p / "manifest.csv"
            if mf.is_file():
                found = [q for q in found if q.name != "manifest.csv"]
                if manifest is None:
                    manifest = mf
            if not found:
                raise DataError(f"{p}: no *.csv, *.wav or *.npy recording in this directory")
            files += found
        elif p.is_file():
            files.append(p)
        else:
            raise DataError(f"{p}: no such file or directory")
    if not files:
        raise DataError("load(): nothing to read")
    table = _read_manifest(manifest) if manifest is not None else {}
    if manifest is not None and not isinstance(manifest, Mapping):
        files = [f for f in files if f.resolve() != Path(manifest).resolve()]

    recs = []
    for f in files:
        entry = table.get(f.name, {})
        h = height_m if height_m is not None else entry.get("height_m")
        if h is None:
            h = height_from_name(f.name)
        if h is None:
            raise DataError(
                f"cannot know the drop height of {f.name}: pass height_m=, a manifest, "
                "or name it hNNN_... (NNN in centimetres)"
            )
        rate = entry.get("rate_Hz", rate_Hz)
        cal = entry.get("calibration_N_per_FS", calibration_N_per_FS)
        lp = entry.get("lowpass_Hz", lowpass_Hz)
        suf = f.suffix.lower()
        if suf == ".csv":
            r = read_csv(f, rate_Hz=rate, height_m=h, lowpass_Hz=lp)
        elif suf == ".wav":
            r = read_wav(f, calibration_N_per_FS=cal, height_m=h, channel=channel, lowpass_Hz=lp)
        elif suf == ".npy":
            if rate is None:
                raise DataError(f"{f.name}: a .npy file has no time base: pass rate_Hz= or a manifest rate_Hz")
            r = read_npy(f, rate_Hz=rate, height_m=h, lowpass_Hz=lp)
        else:
            raise DataError(f"{f.name}: unknown file type {f.suffix!r} (csv, wav, npy)")
        recs.append(r)
    _require_same_rate(recs)
    return recs


def _require_same_rate(recs) -> None:
    rates = {r.rate_Hz for r in recs}
    if len(rates) > 1:
        listing = ", ".join(f"{r.source}: {r.rate_Hz:g} Hz" for r in recs)
        raise DataError(f"recordings have different sample rates ({listing}); resample them first")


# --------------------------------------------------------------------------------------
# impacts and onsets
# --------------------------------------------------------------------------------------


def _segments_stats(x: np.ndarray):
    n = x.size
    L = int(max(16, min(256, n // 16)))
    m = n // L
    if m == 0:
        seg = x[None, :]
    else:
        seg = x[: m * L].reshape(m, L)
    med = np.median(seg, axis=1)
    sig = 1.4826 * np.median(np.abs(seg - med[:, None]), axis=1)
    return med, sig


def _quiet(x: np.ndarray) -> tuple[float, float]:
    """(baseline level, noise rms) from the quietest segments of the record."""
    med, sig = _segments_stats(np.asarray(x, dtype=np.float64))
    order = np.argsort(sig)
    low = order[: max(1, len(order) // 4)]
    s0 = float(np.median(sig[low]))
    keep = sig <= 2.0 * s0 if s0 > 0 else sig <= s0
    return float(np.median(med[keep])), float(np.median(sig[keep]))


def estimate_noise_rms_N(force_N) -> float:
    """Robust noise rms of a record, N.

    The record is cut into segments (``min(256, n/16)`` samples, at least 16); each
    segment's spread is ``1.4826 * MAD``; the quietest quarter of the segments gives a
    first estimate ``s0``, and the result is the median over all segments with spread
    below ``2 s0`` (so the impact, ringing and drifts do not count).
    """
    return _quiet(force_N)[1]


def _default_threshold(noise_rms_N: float) -> float:
    return max(10.0, 8.0 * noise_rms_N)


def find_impacts(
    force_N,
    rate_Hz: float,
    *,
    threshold_N: float | None = None,
    min_separation_s: float = 0.1,
) -> list[Impact]:
    """Every impact in a raw force record, in time order.

    The force minus the record's baseline level (median of its quietest segments) is
    compared with ``threshold_N`` (default ``max(10 N, 8 * noise rms)``, noise from
    :func:`estimate_noise_rms_N`). Runs of samples above it closer than
    ``min_separation_s`` belong to one impact.

    Returns:
      a list of :class:`Impact` ``(start_index, end_index, peak_N)``: first sample above
      the threshold, one past the last one (``end_index == len(force_N)`` means the
      impact runs off the end), peak force above the baseline level in N. Empty if no
      sample exceeds the threshold.
    """
    x = np.asarray(force_N, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"force_N must be 1-D, got shape {x.shape}")
    level, noise = _quiet(x)
    thr = _default_threshold(noise) if threshold_N is None else float(threshold_N)
    y = x - level
    idx = np.flatnonzero(y > thr)
    if idx.size == 0:
        return []
    gap = max(1, int(round(min_separation_s * float(rate_Hz))))
    breaks = np.flatnonzero(np.diff(idx) > gap)
    starts = idx[np.r_[0, breaks + 1]]
    ends = idx[np.r_[breaks, idx.size - 1]] + 1
    return [Impact(int(s), int(e), float(y[s:e].max())) for s, e in zip(starts, ends)]


def _lagrange4(y4: np.ndarray, u: float) -> float:
    """Cubic through y(-1), y(0), y(1), y(2) evaluated at u."""
    ym1, y0, y1, y2 = y4
    return (
        -u * (u - 1) * (u - 2) / 6 * ym1
        + (u + 1) * (u - 1) * (u - 2) / 2 * y0
        - (u + 1) * u * (u - 2) / 2 * y1
        + (u + 1) * u * (u - 1) / 6 * y2
    )


def _solve_crossing(x: np.ndarray, j: int, level: float, sign: float = 1.0) -> float:
    """u in [0, 1]: sign*x crosses ``level`` between samples j-1 (u=0) and j (u=1).

    Cubic (4-point Lagrange) interpolation on samples j-2..j+1 when available, solved by
    bisection (a root exists since the end values bracket the level); linear otherwise.
    """
    xs = sign * x
    a, b = xs[j - 1], xs[j]
    if j - 2 < 0 or j + 1 >= xs.size:
        return float((level - a) / (b - a))
    y4 = xs[j - 2 : j + 2]
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _lagrange4(y4, mid) < level:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _rising_crossing(x: np.ndarray, ip: int, level: float, source: str, start: int | None = None) -> float:
    """Sub-sample index where x rises through ``level`` on the edge that leads to ``ip``."""
    j = ip if start is None else min(start, ip)
    if x[j] >= level:
        while j > 0 and x[j - 1] >= level:
            j -= 1
    else:
        while j < ip and x[j] < level:
            j += 1
    if j == 0:
        raise DataError(
            f"{source}: the impact is already above the onset level at the first sample: "
            "no pre-trigger, onset unknown"
        )
    return (j - 1) + _solve_crossing(x, j, level)


def locate_onset(
    force_N,
    rate_Hz: float,
    *,
    fraction: float = 0.05,
    impact: Impact | None = None,
    source: str = "<array>",
) -> float:
    """Sub-sample onset time of an impact, seconds from the first sample.

    Definition: the time the rising edge of the (baseline-subtracted) force first
    crosses ``fraction`` of the impact's peak, going back from the first sample above
    the detection threshold. The crossing is found between the two samples that
    bracket the level by cubic (4-point Lagrange) interpolation through the four
    nearest samples, solved by bisection; this is exact for cubics and, for a force
    band-limited by a measuring-chain low-pass well below Nyquist, accurate to far
    better than 0.01 sample without noise (tested: < 0.05 sample).

    With white noise of rms ``sigma_N`` the onset scatters with standard deviation
    about ``sigma_N / (dF/dt at the crossing)`` seconds (the tests check this bound
    with the shipped records' 0.8 N noise).

    Note a causal measuring-chain low-pass delays this onset relative to the instant
    contact begins: a 4th-order Butterworth at 1250 Hz shifts the crossing later by
    about its low-frequency group delay, 2.613 / (2 pi 1250 Hz) = 0.33 ms (~15 samples
    at 44.1 kHz), on top of the time the unfiltered force needs to reach the level
    (~0.07 ms for the ball's steep rise at 5 %). The onset is an alignment mark, not
    the physical contact start; a model compared with it should include the chain
    (:mod:`rbjax.filters`) or a fitted time offset.

    Args:
      force_N: baseline-subtracted force, N.
      rate_Hz: sampling rate, Hz.
      fraction: level as a fraction of the impact's peak (0 < fraction < 1).
      impact: the :class:`Impact` to use (default: the first one found).
      source: name for messages.
    """
    x = np.asarray(force_N, dtype=np.float64)
    if not 0 < fraction < 1:
        raise ValueError(f"fraction={fraction!r} must lie in (0, 1)")
    if impact is None:
        imps = find_impacts(x, rate_Hz)
        if not imps:
            raise DataError(f"{source}: no impact found")
        impact = imps[0]
    s, e, _ = impact
    ip = s + int(np.argmax(x[s:e]))
    level = fraction * x[ip]
    return _rising_crossing(x, ip, level, source, start=s) / float(rate_Hz)


def _describe_impacts(imps, rate) -> str:
    return ", ".join(f"{s / rate:.4f} s (peak {p:.4g} N)" for s, _, p in imps)


def condition(
    recording: Recording,
    *,
    which: str | int = "first",
    baseline: str = "pretrigger",
    align: bool = True,
    lowpass_Hz: float | None = None,
    window_s: float = 0.05,
    pre_onset_s: float = 0.002,
    onset_fraction: float = 0.05,
    threshold_N: float | None = None,
    min_separation_s: float = 0.1,
    shift_method: str = "fourier",
) -> Recording:
    """Condition a raw record for fitting: one impact, no baseline, known onset, fixed window.

    Steps:

    1. :func:`find_impacts`; keep ``which`` (``"first"`` (default), ``"largest"``,
       ``"last"`` or an index). Further impacts are listed in ``notes`` and reported with
       a :class:`DataWarning` naming the file, their number and times.
    2. ``baseline="pretrigger"``: subtract the mean of the samples before the impact
       (from the end of any previous impact + 5 ms up to 1 ms before the first sample
       above threshold); ``"none"``: keep the record's offset.
    3. ``lowpass_Hz``: optionally apply a causal 4th-order Butterworth (like a measuring
       chain; it delays the onset). The result's ``lowpass_Hz`` is the lowest cutoff
       the record went through.
    4. Onset to a fraction of a sample by :func:`locate_onset` with ``onset_fraction``.
    5. Cut ``window_s`` seconds starting ``pre_onset_s`` before the onset. With
       ``align=True`` the record is also shifted by the fractional sample
       (:func:`fractional_shift`, ``shift_method``) so that ``onset_s == pre_onset_s``
       exactly and records of one height line up sample by sample; with ``align=False``
       the window starts on the sample at or before ``onset - pre_onset_s``, and
       ``onset_s`` is in ``[pre_onset_s, pre_onset_s + 1/rate)``.

    The default window (50 ms) fits the shipped 0.1 s records (pre-trigger up to
    ~20 ms) and holds the ~21 ms contact with its ringing.

    Raises:
      DataError: no impact (peak below threshold), the impact runs off the end, the
        window would run past either end of the record or would cut the impact.
    """
    src = recording.source
    rate = recording.rate_Hz
    x = np.array(recording.force_N, dtype=np.float64)
    n = x.size
    level0, noise = _quiet(x)
    thr = _default_threshold(noise) if threshold_N is None else float(threshold_N)
    imps = find_impacts(x, rate, threshold_N=thr, min_separation_s=min_separation_s)
    if not imps:
        raise DataError(
            f"{src}: no impact found: the largest force {float(np.max(x - level0)):.4g} N above the "
            f"baseline is below the threshold {thr:.4g} N (noise rms {noise:.3g} N); "
            "is the force sign compression-positive?"
        )
    if which == "first":
        k = 0
    elif which == "last":
        k = len(imps) - 1
    elif which == "largest":
        k = int(np.argmax([p for _, _, p in imps]))
    elif isinstance(which, (int, np.integer)) and not isinstance(which, bool):
        k = int(which)
        if not -len(imps) <= k < len(imps):
            raise ValueError(f"which={which}: only {len(imps)} impact(s) found in {src}")
        k %= len(imps)
    else:
        raise ValueError(f"which={which!r}: use 'first', 'largest', 'last' or an index")
    s, e, _ = imps[k]
    notes = list(recording.notes)
    others = [imp for i, imp in enumerate(imps) if i != k]
    if others:
        msg = (
            f"{src}: {len(others)} further impact(s) found at {_describe_impacts(others, rate)}; "
            f"kept the one at {s / rate:.4f} s"
        )
        warnings.warn(msg, DataWarning, stacklevel=2)
        notes.append(msg)
    if e >= n:
        raise DataError(
            f"{src}: the impact at {s / rate:.4f} s runs off the end of the record (force still "
            f"above {thr:.4g} N at the last sample)"
        )
    if s == 0:
        raise DataError(f"{src}: the impact starts at the first sample: no pre-trigger")

    # --- baseline
    if baseline == "pretrigger":
        guard = int(round(0.001 * rate))
        b0 = 0
        if k > 0:
            b0 = min(imps[k - 1][1] + int(round(0.005 * rate)), s)
        b1 = max(b0, s - guard)
        if b1 - b0 < 20:
            raise DataError(
                f"{src}: only {b1 - b0} pre-trigger samples before the impact at {s / rate:.4f} s "
                "for the baseline; pass baseline='none' to keep the offset"
            )
        base = float(np.mean(x[b0:b1]))
        x = x - base
        notes.append(f"baseline {base:+.4g} N subtracted (mean of samples {b0}..{b1 - 1})")
    elif baseline != "none":
        raise ValueError(f"baseline={baseline!r}: use 'pretrigger' or 'none'")

    # --- optional causal low-pass
    lp_out = recording.lowpass_Hz
    if lowpass_Hz is not None:
        x = sosfilt_np(butter_lowpass_sos(4, lowpass_Hz, rate), x)
        lp_out = float(lowpass_Hz) if lp_out is None else min(lp_out, float(lowpass_Hz))
        notes.append(f"causal 4th-order Butterworth low-pass at {float(lowpass_Hz):g} Hz applied")
        # the filter delays the pulse: let the peak search run a little past e
        e_search = min(n, e + int(round(0.005 * rate)))
    else:
        e_search = e

    # --- onset
    ip = s + int(np.argmax(x[s:e_search]))
    level = onset_fraction * x[ip]
    if level < 5 * noise:
        notes.append(
            f"onset level {level:.3g} N is below 5x the noise rms ({noise:.3g} N): onset is noisy"
        )
    onset_idx = _rising_crossing(x, ip, level, src, start=s)  # fractional sample index

    # --- window
    m = int(round(window_s * rate))
    pre = pre_onset_s * rate
    start_f = onset_idx - pre
    i0 = int(math.floor(start_f + 1e-9))
    frac = start_f - i0
    if i0 < 0:
        raise DataError(
            f"{src}: the pre-trigger ({onset_idx / rate * 1e3:.3f} ms before the onset) is shorter "
            f"than pre_onset_s={pre_onset_s * 1e3:.3g} ms"
        )
    need_end = i0 + m + (1 if align and frac > 0 else 0)
    if need_end > n:
        raise DataError(
            f"{src}: the window of {window_s * 1e3:.4g} ms would run past the end of the record "
            f"(only {(n - onset_idx) / rate * 1e3:.4g} ms after the onset); pass a smaller window_s"
        )
    if e > i0 + m:
        raise DataError(
            f"{src}: window_s={window_s * 1e3:.4g} ms cuts the impact (force above {thr:.4g} N until "
            f"{(e - onset_idx) / rate * 1e3:.4g} ms after the onset); pass a longer window_s"
        )
    inside = [imp for imp in others if i0 <= imp.start_index < i0 + m]
    if inside:
        msg = f"{src}: the window also contains the impact(s) at {_describe_impacts(inside, rate)}"
        warnings.warn(msg, DataWarning, stacklevel=2)
        notes.append(msg)
    if align:
        pad = min(256, i0, n - need_end)
        seg = x[i0 - pad : i0 + m + 1 + pad] if frac > 0 else x[i0 : i0 + m]
        if frac > 0:
            # advance by frac samples: y[i] = x(i0 + frac + i)
            y = fractional_shift(seg, -frac, method=shift_method)[pad : pad + m]
        else:
            y = seg
        onset_s = float(pre_onset_s)
    else:
        y = x[i0 : i0 + m]
        onset_s = float((onset_idx - i0) / rate)
    notes.append(
        f"window {i0 / rate:.6f} s + {m} samples of the input; onset at {onset_idx / rate:.6f} s "
        f"({onset_fraction:g} of peak)"
    )
    return Recording(
        source=src,
        height_m=recording.height_m,
        rate_Hz=rate,
        force_N=y,
        onset_s=onset_s,
        calibration_N_per_FS=recording.calibration_N_per_FS,
        lowpass_Hz=lp_out,
        notes=tuple(notes),
    )


# --------------------------------------------------------------------------------------
# shifting and averaging
# --------------------------------------------------------------------------------------


def _fft_len(n: int) -> int:
    """Smallest 2^a 3^b 5^c >= n."""
    best = 1 << max(0, (n - 1).bit_length())
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            p = p35
            while p < n:
                p *= 2
            best = min(best, p)
            p35 *= 3
        p5 *= 5
    return best


def fractional_shift(x, shift_samples: float, *, method: str = "fourier") -> np.ndarray:
    """Delay ``x`` by ``shift_samples`` (may be fractional or negative): ``y[i] = x(i - shift)``.

    Samples brought in from outside ``x`` are 0. Methods:

    * ``"fourier"``: band-limited shift, multiply the spectrum of the zero-padded
      record by ``exp(-2 pi i f shift / rate)`` (exact for band-limited signals; a
      record that does not start and end near zero rings near its ends);
    * ``"cubic"``: 4-point Lagrange interpolation;
    * ``"linear"``: linear interpolation (attenuates high frequencies by up to
      ``cos(pi f / rate)`` for half-sample shifts: 0.4 % at 1250 Hz, 44.1 kHz).
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"x must be 1-D, got shape {x.shape}")
    n = x.size
    d = float(shift_samples)
    if not math.isfinite(d):
        raise ValueError(f"shift_samples={shift_samples!r} must be finite")
    if d == 0:
        return x.copy()
    if method == "fourier":
        N = _fft_len(n + int(math.ceil(abs(d))) + 64)  # zero padding: no wrap-around
        k = np.arange(N // 2 + 1)
        ph = np.exp(-2j * np.pi * k * d / N)
        if N % 2 == 0:  # the Nyquist bin must stay real: keep its cosine part
            ph[-1] = math.cos(math.pi * d)
        return np.fft.irfft(np.fft.rfft(x, N) * ph, N)[:n]
    if method in ("linear", "cubic"):
        pos = np.arange(n) - d
        ip = np.floor(pos).astype(np.int64)
        u = pos - ip
        xp = np.concatenate([[0.0, 0.0], x, [0.0, 0.0, 0.0]])  # index k -> xp[k + 2]

        def at(j):
            j = np.clip(j, -2, n + 2)
            return xp[j + 2]

        if method == "linear":
            return (1 - u) * at(ip) + u * at(ip + 1)
        ym1, y0, y1, y2 = at(ip - 1), at(ip), at(ip + 1), at(ip + 2)
        return (
            -u * (u - 1) * (u - 2) / 6 * ym1
            + (u + 1) * (u - 1) * (u - 2) / 2 * y0
            - (u + 1) * u * (u - 2) / 2 * y1
            + (u + 1) * u * (u - 1) / 6 * y2
        )
    raise ValueError(f"method={method!r}: use 'fourier', 'cubic' or 'linear'")


def average(
    recordings: Iterable[Recording],
    *,
    domain: str = "frequency",
    method: str = "fourier",
    onset_s: float | None = None,
) -> Recording:
    """Average repeated drops after aligning their onsets to a fraction of a sample.

    ``domain="frequency"`` (the paper's section 3): each record's complex spectrum
    ``X_k(f)`` (zero-padded FFT) is multiplied by ``exp(+2 pi i f dt_k)``, with
    ``dt_k = onset_k - onset_ref``, which advances it by ``dt_k`` so that all onsets sit
    at ``onset_ref``; the complex spectra are averaged and transformed back. This is a
    *coherent* average: the phase is kept, so the mean is the spectrum of the mean
    force history, random noise falls as 1/sqrt(K) in amplitude, and the result can be
    returned as a time signal. Averaging *power* spectra ``|X_k|^2`` instead (an
    incoherent average) discards the phase: it cannot give a force history, it keeps
    the noise power (adds, rather than averages out, the noise floor) and it hides
    timing jitter; averaging complex spectra *without* the alignment phase would
    instead smear the pulse (a low-pass by the spread of the onsets).

    ``domain="time"``: each record is shifted by ``-dt_k`` with
    :func:`fractional_shift` (``method``: ``"fourier"``, which makes the two domains
    agree to rounding, ``"cubic"`` or ``"linear"``) and the samples are averaged.

    The reference onset is ``onset_s`` if given, else the first record's. Records of
    different lengths are cut to the shortest (noted). Samples shifted in from outside
    a record are zero, so the records should be baseline-subtracted (conditioned).

    Raises:
      DataError: no records, a record without ``onset_s``, different sample rates
        (the message lists files and rates). Heights more than 2 cm apart warn.
    """
    recs = list(recordings)
    if not recs:
        raise DataError("average(): no recordings")
    for r in recs:
        if r.onset_s is None:
            raise DataError(f"{r.source}: no onset_s; condition() the recording first")
    _require_same_rate(recs)
    if domain not in ("frequency", "time"):
        raise ValueError(f"domain={domain!r}: use 'frequency' or 'time'")
    rate = recs[0].rate_Hz
    notes = [f"{domain}-domain average of {len(recs)} recordings: " + ", ".join(r.source for r in recs)]
    heights = [r.height_m for r in recs if r.height_m is not None]
    if heights and max(heights) - min(heights) > 0.02:
        msg = (
            "average(): drop heights differ by more than 2 cm: "
            + ", ".join(f"{r.source}: {r.height_m} m" for r in recs)
        )
        warnings.warn(msg, DataWarning, stacklevel=2)
        notes.append(msg)
    height = float(np.mean(heights)) if len(heights) == len(recs) else None
    m = min(r.n_samples for r in recs)
    if any(r.n_samples != m for r in recs):
        notes.append(f"records cut to the shortest length, {m} samples")
    ref = recs[0].onset_s if onset_s is None else float(onset_s)
    shifts = [(r.onset_s - ref) * rate for r in recs]  # samples to advance each record

    if domain == "frequency":
        N = _fft_len(m + int(math.ceil(max(abs(d) for d in shifts))) + 64)
        f = np.fft.rfftfreq(N, d=1.0 / rate)
        acc = np.zeros(f.size, dtype=np.complex128)
        for r, d in zip(recs, shifts):
            X = np.fft.rfft(r.force_N[:m], N)
            ph = np.exp(+2j * np.pi * f * (d / rate))
            if N % 2 == 0:
                ph[-1] = math.cos(math.pi * d)
            acc += X * ph
        y = np.fft.irfft(acc / len(recs), N)[:m]
    else:
        y = np.mean([fractional_shift(r.force_N[:m], -d, method=method) for r, d in zip(recs, shifts)], axis=0)

    lps = {r.lowpass_Hz for r in recs}
    cals = {r.calibration_N_per_FS for r in recs}
    return Recording(
        source=f"average of {len(recs)}: " + ", ".join(r.source for r in recs),
        height_m=height,
        rate_Hz=rate,
        force_N=y,
        onset_s=ref,
        calibration_N_per_FS=cals.pop() if len(cals) == 1 else None,
        lowpass_Hz=lps.pop() if len(lps) == 1 else None,
        notes=tuple(notes),
    )

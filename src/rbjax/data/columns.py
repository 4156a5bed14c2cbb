"""Names, units and time bases of channels: a column or variable name such as ``time_s`` or
``F [kN]`` read as a role and a scale, and the check that a time vector is uniform (its rate)."""

from __future__ import annotations

import re

import numpy as np

from .errors import DataError

_TIME_NAMES = {"time": 1.0, "t": 1.0}
FORCE_NAMES = {"force": 1.0, "f": 1.0}
_TIME_UNITS = {None: 1.0, "s": 1.0, "sec": 1.0, "ms": 1e-3}
FORCE_UNITS = {None: 1.0, "n": 1.0, "kn": 1e3}
_COL_RE = re.compile(r"^\s*([a-z]+)\s*(?:[_\s]\s*([a-z]+)|[\[(]\s*([a-z]+)\s*[\])])?\s*$")


def parse_column(name: str):
    """('time'|'force'|None, scale) for a header field such as ``time_s``, ``F [kN]``."""
    m = _COL_RE.match(name.strip().lower())
    if not m:
        return None, None
    base, unit = m.group(1), m.group(2) or m.group(3)
    if base in _TIME_NAMES:
        if unit not in _TIME_UNITS:
            return "time?", unit
        return "time", _TIME_UNITS[unit]
    if base in FORCE_NAMES:
        if unit not in FORCE_UNITS:
            return "force?", unit
        return "force", FORCE_UNITS[unit]
    return None, None


def decimal_places(s: str) -> int | None:
    s = s.strip()
    if "e" in s.lower():
        return None
    if "." not in s:
        return 0
    return len(s.split(".", 1)[1])


def infer_rate(t: np.ndarray, quantum_s: float, source: str) -> tuple[float, float, list[str]]:
    """Uniform-sampling check of a time column; returns (rate_Hz, t0_s, notes)."""
    dt_steps = np.diff(t)
    if np.any(dt_steps <= 0):
        k = int(np.argmax(dt_steps <= 0))
        raise DataError(
            f"{source}: time column is not strictly increasing (sample {k + 1}: "
            f"{t[k + 1]!r} s after {t[k]!r} s)"
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

"""Noise floor and threshold crossings of a force record: the robust noise estimate, quiet
stretches and the (sub-sample) crossing of a level that locate an impact in a record."""

from __future__ import annotations

import numpy as np

from .errors import RecordCutOffError
from .shift import lagrange4


def segment_stats(x: np.ndarray):
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


def quiet_level(x: np.ndarray) -> tuple[float, float]:
    """(baseline level, noise rms) from the quietest segments of the record."""
    med, sig = segment_stats(np.asarray(x, dtype=np.float64))
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

    Args:
        force_N: the force samples, N, 1-D.

    Returns:
        The noise rms, N.
    """
    return quiet_level(force_N)[1]


def solve_crossing(x: np.ndarray, j: int, level: float, sign: float = 1.0) -> float:
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
        if lagrange4(y4, mid) < level:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def rising_crossing(
    x: np.ndarray, ip: int, level: float, source: str, start: int | None = None
) -> float:
    """Sub-sample index where x rises through ``level`` on the edge that leads to ``ip``."""
    j = ip if start is None else min(start, ip)
    if x[j] >= level:
        while j > 0 and x[j - 1] >= level:
            j -= 1
    else:
        while j < ip and x[j] < level:
            j += 1
    if j == 0:
        raise RecordCutOffError(
            f"{source}: the impact is already above the onset level at the first sample: "
            "no pre-trigger, onset unknown"
        )
    return (j - 1) + solve_crossing(x, j, level)

"""Faults of real force records mended before conditioning: :func:`clean` flips a force
channel recorded with inverted sign, removes a slow drift of the baseline and mains hum
(50 or 60 Hz and its 2nd and 3rd harmonics), and logs what it did (``Recording.log``).

A record without these faults comes back unchanged: each repair is made only when the fault
stands clear of the noise (thresholds below), so that a clean record is never altered.
The baseline model (a line, plus the hum) is fitted by least squares to the record's quiet
samples, those away from every impact; an offset is left to :func:`~rbjax.data.condition`,
which subtracts the pre-trigger mean.
"""

from __future__ import annotations

import warnings

import numpy as np

from .conditioning import default_threshold, find_impacts
from .crossings import quiet_level, segment_stats
from .errors import DataWarning
from .recording import Recording

__all__ = ["clean", "MAINS_HZ"]

#: Nominal mains frequencies searched for hum, Hz; each within ±``MAINS_TOLERANCE_HZ``.
MAINS_HZ = (50.0, 60.0)
MAINS_TOLERANCE_HZ = 0.5
#: Harmonics of the mains frequency fitted together (1: the fundamental).
HUM_HARMONICS = 3
#: Hum is removed when its fundamental's amplitude exceeds this many times the rms of
#: what remains of the quiet samples and ``HUM_SE_FACTOR`` times its own standard error
#: (white-noise least squares; the chain's low-pass correlates the noise over ~12 samples
#: at 44.1 kHz, hence the margin), and the quiet samples last this many periods in all
#: (a short record's few quiet milliseconds do not determine a hum).
HUM_FACTOR = 2.0
HUM_SE_FACTOR = 10.0
HUM_MIN_PERIODS = 2.0
#: Sampling rate the frequency search thins the quiet samples to (the hum is below 200 Hz).
SEARCH_RATE_HZ = 2000.0
#: A drift is removed when the line's change over the record exceeds this many times the
#: rms of the quiet samples about it.
DRIFT_FACTOR = 3.0
#: Samples kept out of the baseline fit around each impact: before its first sample above
#: the threshold, after its last (the measuring chain's tail and the ball's ringing).
QUIET_BEFORE_S = 0.005
QUIET_AFTER_S = 0.020


def _robust_trend(x: np.ndarray) -> np.ndarray:
    """A line through the medians of the record's quiet segments (impacts do not pull it)."""
    med, sig = segment_stats(x)
    if med.size < 2:
        return np.full(x.size, float(np.median(x)))
    seg = x.size // med.size
    centres = (np.arange(med.size) + 0.5) * seg
    s0 = float(np.median(np.sort(sig)[: max(1, sig.size // 4)]))
    keep = sig <= 2.0 * s0 if s0 > 0 else sig <= s0
    if keep.sum() < 2:
        return np.full(x.size, float(np.median(med)))
    slope, icpt = np.polyfit(centres[keep], med[keep], 1)
    return icpt + slope * np.arange(x.size)


def _quiet_mask(n: int, impacts, rate: float) -> np.ndarray:
    mask = np.ones(n, dtype=bool)
    before, after = int(round(QUIET_BEFORE_S * rate)), int(round(QUIET_AFTER_S * rate))
    for s, e, _ in impacts:
        mask[max(0, s - before) : min(n, e + after)] = False
    return mask


def _hum_columns(t: np.ndarray, f: float) -> np.ndarray:
    w = 2 * np.pi * f * t
    return np.column_stack(
        [g(k * w) for k in range(1, HUM_HARMONICS + 1) for g in (np.cos, np.sin)]
    )


def _fit(base: np.ndarray, y: np.ndarray, extra: np.ndarray | None = None):
    """Least squares by the normal equations (a few well-scaled columns: O(1) in N, s)."""
    a = base if extra is None else np.hstack([base, extra])
    coef, *_ = np.linalg.lstsq(a.T @ a, a.T @ y, rcond=None)
    resid = y - a @ coef
    return coef, float(np.sqrt(np.mean(resid**2)))


def _amplitude_se(base, t, f, rms) -> float:
    """Standard error of the fundamental's amplitude (white noise of ``rms``)."""
    a = np.hstack([base, _hum_columns(t, f)])
    cov = np.linalg.pinv(a.T @ a) * rms**2
    return float(np.sqrt(0.5 * (cov[2, 2] + cov[3, 3])))


def _best_hum(base, y, t, mains):
    """(frequency, coefficients, residual rms) of the best hum near any mains frequency.

    The frequency maximises the periodogram of the residual of the line (on a 0.025 Hz
    grid, then a bounded scalar search), then minimises the residual of the line and the
    hum with its harmonics fitted together (bounded search within one grid step); the
    searches use every k-th quiet sample (about ``SEARCH_RATE_HZ``), the final fit all.
    """
    import scipy.optimize  # lazy: scipy.optimize costs 0.3–0.8 s at import (benchmarks/RESULTS.md)

    coef, _ = _fit(base, y)
    full = (base, y, t)
    k = max(
        1, int(t.size / max(t[-1] - t[0], 1e-9) // SEARCH_RATE_HZ)
    )  # the search on every k-th sample
    base, y, t = base[::k], y[::k], t[::k]
    r = y - base @ coef

    def power(f):
        return -(abs(np.dot(r, np.exp(-2j * np.pi * f * t))) ** 2)

    best = None
    for f0 in mains:
        grid = np.linspace(f0 - MAINS_TOLERANCE_HZ, f0 + MAINS_TOLERANCE_HZ, 41)
        fg = float(grid[int(np.argmin([power(f) for f in grid]))])
        step = float(grid[1] - grid[0])
        lo, hi = max(grid[0], fg - step), min(grid[-1], fg + step)
        f = float(
            scipy.optimize.minimize_scalar(
                power, bounds=(lo, hi), method="bounded", options={"xatol": 1e-4}
            ).x
        )
        # the gap left by the impacts and the harmonics bias the periodogram's peak a little:
        # refine on the residual of the whole model
        f = float(
            scipy.optimize.minimize_scalar(
                lambda f: _fit(base, y, _hum_columns(t, f))[1],
                bounds=(f - step, f + step),
                method="bounded",
                options={"xatol": 1e-5},
            ).x
        )
        hcoef, rms = _fit(full[0], full[1], _hum_columns(full[2], f))
        if best is None or rms < best[2]:
            best = (f, hcoef, rms)
    return best


def clean(
    recording: Recording,
    *,
    mains_Hz=MAINS_HZ,
    threshold_N: float | None = None,
    min_separation_s: float = 0.1,
) -> Recording:
    """Mend the faults of a raw record that the fit must not see; log each one.

    1. **Polarity.** A record whose largest excursion from its baseline is negative (more
       than twice the largest positive one, and above the impact threshold) was recorded
       with inverted sign: it is flipped, with a :class:`DataWarning`.
    2. **Drift and hum.** A line (offset and drift) and, for each mains frequency in
       ``mains_Hz`` searched within ±0.5 Hz, a hum of that frequency and its 2nd and 3rd
       harmonics are fitted by least squares to the quiet samples (5 ms before to 20 ms
       after every impact left out). The hum is removed when its fundamental's amplitude
       exceeds twice the rms of the quiet samples about the fit and ten times its
       standard error, the quiet samples lasting two periods at least; the drift when
       the line changes by more than three times that rms over the record. The drift is
       removed as a line through zero at the first impact, so that the offset there is left
       to :func:`~rbjax.data.condition`'s pre-trigger baseline.

    ``Recording.log`` gains ``polarity`` (``"as recorded"`` or ``"inverted: sign
    flipped"``), ``drift_N_per_s`` (the slope removed, or None) and ``hum`` (``{"frequency_Hz",
    "amplitude_N"}`` of the fundamental removed, or None). A record with no impact is
    returned with the polarity entry only (:func:`~rbjax.data.condition` refuses it).

    Args:
        recording: the raw record.
        mains_Hz: nominal mains frequencies searched for hum, Hz (default 50 and 60).
        threshold_N: impact detection level above the baseline, N, which a negative
            excursion must also exceed to count as inverted; default
            ``max(10 N, 8 * noise rms)`` of the detrended record.
        min_separation_s: runs above the threshold closer than this, s, are one impact.

    Returns:
        A copy of ``recording`` with the mended ``force_N`` and with ``notes`` and ``log``
            extended.

    Warns:
        DataWarning: the record was inverted and has been flipped.
    """
    x = np.array(recording.force_N, dtype=np.float64)
    rate, n = recording.rate_Hz, recording.n_samples
    notes, log = list(recording.notes), list(recording.log)
    detrended = x - _robust_trend(x)
    level, noise = quiet_level(detrended)
    thr = default_threshold(noise) if threshold_N is None else float(threshold_N)
    low, high = -float(np.min(detrended - level)), float(np.max(detrended - level))
    if low >= thr and low > 2.0 * high:
        x, detrended = -x, -detrended
        msg = (
            f"{recording.source}: the force is negative ({-low:.4g} N at most, +{high:.4g} N the "
            "other way): recorded with inverted sign; flipped"
        )
        warnings.warn(msg, DataWarning, stacklevel=2)
        notes.append(msg)
        log.append(("polarity", "inverted: sign flipped"))
    else:
        log.append(("polarity", "as recorded"))
    impacts = find_impacts(detrended, rate, threshold_N=thr, min_separation_s=min_separation_s)
    if not impacts:
        return recording.replace(force_N=x, notes=tuple(notes), log=tuple(log))

    t = np.arange(n) / rate
    t_anchor = impacts[0].start_index / rate
    quiet = _quiet_mask(n, impacts, rate)
    tq, yq = t[quiet], x[quiet]
    base = np.column_stack([np.ones(tq.size), tq - t_anchor]) if tq.size >= 2 else None
    drift = hum = None
    if base is not None:
        coef, rms = _fit(base, yq)
        quiet_s = tq.size / rate
        mains = [f for f in mains_Hz if quiet_s * (f - MAINS_TOLERANCE_HZ) >= HUM_MIN_PERIODS]
        if mains:
            f, hcoef, hrms = _best_hum(base, yq, tq, mains)
            amplitude = float(np.hypot(hcoef[2], hcoef[3]))
            if amplitude > max(HUM_FACTOR * hrms, HUM_SE_FACTOR * _amplitude_se(base, tq, f, hrms)):
                x = x - _hum_columns(t, f) @ hcoef[2:]
                coef, rms = hcoef[:2], hrms
                hum = {"frequency_Hz": f, "amplitude_N": amplitude}
                notes.append(
                    f"mains hum removed: {f:.3f} Hz, {amplitude:.3g} N (with harmonics 2 to "
                    f"{HUM_HARMONICS})"
                )
        if abs(coef[1]) * (n / rate) > DRIFT_FACTOR * rms:
            drift = float(coef[1])
            x = x - drift * (t - t_anchor)
            notes.append(
                f"baseline drift of {drift:+.4g} N/s removed (zero at the first impact, "
                f"{t_anchor:.4f} s)"
            )
    log += [("drift_N_per_s", drift), ("hum", hum)]
    return recording.replace(force_N=x, notes=tuple(notes), log=tuple(log))

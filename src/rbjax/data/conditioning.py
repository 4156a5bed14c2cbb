"""Impacts, onsets and conditioning of raw force records (NumPy).

:func:`find_impacts` lists every impact of a raw record; :func:`locate_onset` finds the
onset of one to a fraction of a sample; :func:`condition` keeps one impact, subtracts
the pre-trigger baseline, optionally low-passes (``scipy.signal.sosfilt``), locates the
onset and cuts a window that starts a fixed ``pre_onset_s`` before it, so that records
of one height line up.
"""

from __future__ import annotations

import math
import warnings
from typing import NamedTuple

import numpy as np

from ..spectrum.filters import butter_lowpass_sos
from .crossings import quiet_level, rising_crossing
from .errors import DataError, DataWarning, NoImpactError, RecordCutOffError
from .recording import Recording
from .shift import fractional_shift

__all__ = ["Impact", "find_impacts", "locate_onset", "condition"]


class Impact(NamedTuple):
    """One impact found by :func:`find_impacts` (a plain tuple ``(start, end, peak)``).

    Attributes:
        start_index: first sample above the threshold.
        end_index: one past the last sample above the threshold (``== n`` when the force
            is still above it at the last sample).
        peak_N: largest force of the impact above the record's baseline level, N.
    """

    start_index: int
    end_index: int
    peak_N: float


# --------------------------------------------------------------------------------------
# noise and impacts
# --------------------------------------------------------------------------------------


def default_threshold(noise_rms_N: float) -> float:
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

    Args:
        force_N: raw force record, N, 1-D.
        rate_Hz: sampling rate, Hz.
        threshold_N: detection level above the baseline level, N; default
            ``max(10 N, 8 * noise rms)``.
        min_separation_s: runs of samples above the threshold closer than this, s, are one
            impact.

    Returns:
        a list of :class:`Impact` ``(start_index, end_index, peak_N)``: first sample above
            the threshold, one past the last one (``end_index == len(force_N)`` means the
            impact runs off the end), peak force above the baseline level in N. Empty if no
            sample exceeds the threshold.

    Raises:
        ValueError: ``force_N`` is not 1-D.
    """
    x = np.asarray(force_N, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"force_N must be 1-D, got shape {x.shape}")
    level, noise = quiet_level(x)
    thr = default_threshold(noise) if threshold_N is None else float(threshold_N)
    y = x - level
    idx = np.flatnonzero(y > thr)
    if idx.size == 0:
        return []
    gap = max(1, int(round(min_separation_s * float(rate_Hz))))
    breaks = np.flatnonzero(np.diff(idx) > gap)
    starts = idx[np.r_[0, breaks + 1]]
    ends = idx[np.r_[breaks, idx.size - 1]] + 1
    return [Impact(int(s), int(e), float(y[s:e].max())) for s, e in zip(starts, ends)]


# --------------------------------------------------------------------------------------
# onsets
# --------------------------------------------------------------------------------------


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
    (:mod:`rbjax.spectrum.filters`) or a fitted time offset.

    Args:
        force_N: baseline-subtracted force, N.
        rate_Hz: sampling rate, Hz.
        fraction: level as a fraction of the impact's peak (0 < fraction < 1).
        impact: the :class:`Impact` to use (default: the first one found).
        source: name for messages.

    Returns:
        The onset time in seconds from the first sample (a float, to a fraction of a
            sample).

    Raises:
        ValueError: ``fraction`` is not in (0, 1).
        NoImpactError: no ``impact`` given and none found.
        RecordCutOffError: the force is already above the level at the first sample
            (no pre-trigger).
    """
    x = np.asarray(force_N, dtype=np.float64)
    if not 0 < fraction < 1:
        raise ValueError(f"fraction={fraction!r} must lie in (0, 1)")
    if impact is None:
        imps = find_impacts(x, rate_Hz)
        if not imps:
            raise NoImpactError(f"{source}: no impact found")
        impact = imps[0]
    s, e, _ = impact
    ip = s + int(np.argmax(x[s:e]))
    level = fraction * x[ip]
    return rising_crossing(x, ip, level, source, start=s) / float(rate_Hz)


# --------------------------------------------------------------------------------------
# conditioning
# --------------------------------------------------------------------------------------


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
    interpolation: str = "fourier",
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
       (:func:`fractional_shift`, ``interpolation``) so that ``onset_s == pre_onset_s``
       exactly and records of one height line up sample by sample; with ``align=False``
       the window starts on the sample at or before ``onset - pre_onset_s``, and
       ``onset_s`` is in ``[pre_onset_s, pre_onset_s + 1/rate)``.

    A raw record from a laboratory should go through :func:`rbjax.data.clean` first
    (inverted sign, drift, mains hum). What was done is appended to ``log``:
    ``impact_s``, ``further_impacts`` (``[{"time_s", "peak_N"}]``, e.g. the rebound),
    ``offset_N``, ``lowpass_Hz``, ``window_start_s``, ``window_s``.

    The default window (50 ms) fits the shipped 0.1 s records (pre-trigger up to
    ~20 ms) and holds the ~21 ms contact with its ringing.

    Args:
        recording: the raw record (mended by :func:`~rbjax.data.clean` first, as a rule).
        which: the impact to keep: ``"first"``, ``"largest"``, ``"last"`` or an index
            (negative counts from the end) into :func:`find_impacts`' list.
        baseline: ``"pretrigger"`` or ``"none"`` (step 2).
        align: shift the record so that ``onset_s == pre_onset_s`` exactly (step 5).
        lowpass_Hz: cutoff of the causal 4th-order Butterworth to apply, Hz; ``None``:
            none (step 3).
        window_s: length of the window kept, s.
        pre_onset_s: time from the window's start to the onset, s.
        onset_fraction: onset level as a fraction of the impact's peak
            (:func:`locate_onset`).
        threshold_N: impact detection level above the baseline, N; default
            ``max(10 N, 8 * noise rms)``.
        min_separation_s: runs above the threshold closer than this, s, are one impact.
        interpolation: :func:`fractional_shift` interpolation of the alignment: ``"fourier"``,
            ``"cubic"`` or ``"linear"``.

    Returns:
        A copy of ``recording`` holding the window: ``force_N`` (``round(window_s *
            rate_Hz)`` samples), ``onset_s``, ``lowpass_Hz``, and ``notes`` and ``log``
            extended.

    Raises:
        NoImpactError: no impact (peak below threshold).
        RecordCutOffError: the impact runs off either end of the record (or starts at its
            first sample), or the window would run past either end.
        DataError: the window would cut the impact; fewer than 20 pre-trigger samples for
            the ``"pretrigger"`` baseline.
        ValueError: an unknown ``which`` or ``baseline``, an index ``which`` out of range,
            an unknown ``interpolation`` (with ``align=True``).

    Warns:
        DataWarning: further impacts in the record, or inside the window.
    """
    src = recording.source
    rate = recording.rate_Hz
    x = np.array(recording.force_N, dtype=np.float64)
    n = x.size
    level0, noise = quiet_level(x)
    thr = default_threshold(noise) if threshold_N is None else float(threshold_N)
    imps = find_impacts(x, rate, threshold_N=thr, min_separation_s=min_separation_s)
    if not imps:
        raise NoImpactError(
            f"{src}: no impact found: the largest force {float(np.max(x - level0)):.4g} N above "
            f"the baseline is below the threshold {thr:.4g} N (noise rms {noise:.3g} N); is the "
            "force sign compression-positive?"
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
    notes, log = list(recording.notes), list(recording.log)
    others = [imp for i, imp in enumerate(imps) if i != k]
    log += [
        ("impact_s", s / rate),
        ("further_impacts", [{"time_s": i.start_index / rate, "peak_N": i.peak_N} for i in others]),
    ]
    if others:
        msg = (
            f"{src}: {len(others)} further impact(s) found at {_describe_impacts(others, rate)}; "
            f"kept the one at {s / rate:.4f} s"
        )
        warnings.warn(msg, DataWarning, stacklevel=2)
        notes.append(msg)
    if e >= n:
        raise RecordCutOffError(
            f"{src}: the impact at {s / rate:.4f} s runs off the end of the record (force still "
            f"above {thr:.4g} N at the last sample)"
        )
    if s == 0:
        raise RecordCutOffError(f"{src}: the impact starts at the first sample: no pre-trigger")

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
        log.append(("offset_N", base))
    elif baseline != "none":
        raise ValueError(f"baseline={baseline!r}: use 'pretrigger' or 'none'")

    # --- optional causal low-pass
    lp_out = recording.lowpass_Hz
    if lowpass_Hz is not None:
        import scipy.signal  # lazy: scipy.signal costs 0.6–1.7 s at import (benchmarks/RESULTS.md)

        x = scipy.signal.sosfilt(butter_lowpass_sos(4, lowpass_Hz, rate), x)
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
    onset_idx = rising_crossing(x, ip, level, src, start=s)  # fractional sample index

    # --- window
    m = int(round(window_s * rate))
    pre = pre_onset_s * rate
    start_f = onset_idx - pre
    i0 = int(math.floor(start_f + 1e-9))
    frac = start_f - i0
    if i0 < 0:
        raise RecordCutOffError(
            f"{src}: the pre-trigger ({onset_idx / rate * 1e3:.3f} ms before the onset) is shorter "
            f"than pre_onset_s={pre_onset_s * 1e3:.3g} ms"
        )
    need_end = i0 + m + (1 if align and frac > 0 else 0)
    if need_end > n:
        raise RecordCutOffError(
            f"{src}: the window of {window_s * 1e3:.4g} ms would run past the end of the record "
            f"(only {(n - onset_idx) / rate * 1e3:.4g} ms after the onset); pass a smaller window_s"
        )
    if e > i0 + m:
        raise DataError(
            f"{src}: window_s={window_s * 1e3:.4g} ms cuts the impact (force above {thr:.4g} N "
            f"until {(e - onset_idx) / rate * 1e3:.4g} ms after the onset); pass a longer window_s"
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
            y = fractional_shift(seg, -frac, interpolation=interpolation)[pad : pad + m]
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
    log += [("lowpass_Hz", lp_out), ("window_start_s", i0 / rate), ("window_s", m / rate)]
    return recording.replace(
        force_N=y, onset_s=onset_s, lowpass_Hz=lp_out, notes=tuple(notes), log=tuple(log)
    )

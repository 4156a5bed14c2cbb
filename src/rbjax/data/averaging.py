"""Coherent averaging of repeated drops after sub-sample onset alignment."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterable

import numpy as np

from .errors import DataError, DataWarning
from .recording import Recording, require_same_rate
from .shift import fractional_shift

__all__ = ["average"]


def average(
    recordings: Iterable[Recording],
    *,
    domain: str = "frequency",
    interpolation: str = "fourier",
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
    :func:`fractional_shift` (``interpolation``: ``"fourier"``, which makes the two domains
    agree to rounding, ``"cubic"`` or ``"linear"``) and the samples are averaged.

    The reference onset is ``onset_s`` if given, else the first record's. Records of
    different lengths are cut to the shortest (noted). Samples shifted in from outside
    a record are zero, so the records should be baseline-subtracted (conditioned).

    Args:
        recordings: the conditioned records (each with ``onset_s``), of one sampling rate.
        domain: ``"frequency"`` or ``"time"``.
        interpolation: :func:`fractional_shift` interpolation for ``domain="time"``: ``"fourier"``,
            ``"cubic"`` or ``"linear"``.
        onset_s: the reference onset, s from the first sample; default: the first
            record's.

    Returns:
        A new :class:`Recording` of the mean force, as long as the shortest record, with
            ``onset_s`` the reference onset; ``height_m`` is the mean height when every record
            has one (else ``None``), and ``calibration_N_per_FS`` and ``lowpass_Hz`` are kept
            when all the records agree on them (else ``None``).

    Raises:
        DataError: no records, a record without ``onset_s``, different sample rates
            (the message lists files and rates).
        ValueError: an unknown ``domain``, or (``domain="time"``) an unknown ``interpolation``.

    Warns:
        DataWarning: drop heights more than 2 cm apart.
    """
    recs = list(recordings)
    if not recs:
        raise DataError("average(): no recordings")
    onsets = []
    for r in recs:
        if r.onset_s is None:
            raise DataError(f"{r.source}: no onset_s; condition() the recording first")
        onsets.append(r.onset_s)
    require_same_rate(recs)
    if domain not in ("frequency", "time"):
        raise ValueError(f"domain={domain!r}: use 'frequency' or 'time'")
    rate = recs[0].rate_Hz
    notes = [
        f"{domain}-domain average of {len(recs)} recordings: " + ", ".join(r.source for r in recs)
    ]
    heights = [r.height_m for r in recs if r.height_m is not None]
    if heights and max(heights) - min(heights) > 0.02:
        msg = "average(): drop heights differ by more than 2 cm: " + ", ".join(
            f"{r.source}: {r.height_m} m" for r in recs
        )
        warnings.warn(msg, DataWarning, stacklevel=2)
        notes.append(msg)
    height = float(np.mean(heights)) if len(heights) == len(recs) else None
    m = min(r.n_samples for r in recs)
    if any(r.n_samples != m for r in recs):
        notes.append(f"records cut to the shortest length, {m} samples")
    ref = onsets[0] if onset_s is None else float(onset_s)
    shifts = [(o - ref) * rate for o in onsets]  # samples to advance each record

    if domain == "frequency":
        from scipy.fft import next_fast_len  # lazy: scipy.fft costs 0.3 s at import (RESULTS.md)

        N = next_fast_len(m + int(math.ceil(max(abs(d) for d in shifts))) + 64, real=True)
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
        y = np.mean(
            [
                fractional_shift(r.force_N[:m], -d, interpolation=interpolation)
                for r, d in zip(recs, shifts)
            ],
            axis=0,
        )

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

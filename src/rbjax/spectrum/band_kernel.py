"""The band kernel of a zero-padded record: band energies of an n-sample pulse in an
N-sample record from one short FFT (``rbjax.spectrum.levels.band_energies_N2s(..., n_record=N)``;
the algebra is in its docstring and in :func:`band_kernel`). NumPy only: built once per
(N, n, rate, band edges) and cached."""

from __future__ import annotations

import functools

import numpy as np

# Band energies of n samples in a record of n_record samples: a short FFT (length >=
# SHORT_FFT_OVERSAMPLING * n) and a band kernel from n_record >= SHORT_PATH_MIN_RATIO * n
# on, the padded FFT otherwise. Measured (2 cores, n = 256 and 512, batches 1 and 1000): the
# padded FFT is faster up to n_record ≈ 2n, the two are even near 3n, the short one is
# faster beyond (4-7x at 8n, two decades at the 1 s record;
# benchmarks/forward.py --only pulse_spectrum).
SHORT_FFT_OVERSAMPLING = 3
SHORT_PATH_MIN_RATIO = 3
# Largest band kernel built, in (bins in the bands) × (short-FFT bins) evaluations (~1 s of
# NumPy); beyond it the padded FFT is used. Elements per block while building one.
KERNEL_MAX_TERMS = 2**23
KERNEL_BLOCK = 2**15


def fast_length(m: int) -> int:
    """The smallest 2^a 3^b 5^c >= m (an FFT length that pocketfft/DUCC handle fast)."""
    best = 1 << max(m - 1, 0).bit_length()
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            p = p35
            while p < m:
                p *= 2
            best = min(best, p)
            p35 *= 3
        p5 *= 5
    return best


def _sin_pi(p, q: int) -> np.ndarray:
    """sin(π p/q) for integers p (array, |2p| + q < 2^63) and q > 0: p = t·q + r is reduced
    exactly in integers to r in [-q/2, q/2) first, sin(πp/q) = (-1)^t sin(πr/q), so large
    arguments are not rounded and values near the zeros keep their relative accuracy."""
    t = (2 * p + q) // (2 * q)
    value = np.sin(np.pi * (p - t * q) / q)
    return np.where(t % 2 == 1, -value, value)


@functools.lru_cache(maxsize=32)
def band_kernel(
    n_record: int,
    n: int,
    n_short: int,
    rate_Hz: float,
    lower_Hz: tuple[float, ...],
    upper_Hz: tuple[float, ...],
) -> np.ndarray | None:
    """G (n_bands, n_short//2 + 1): band b's energy in the zero-padded n_record-point record
    of n samples is Σ_j P_j G_bj, P_j = |rfft(x, n_short)_j|²; None when too large to build.

    With N = n_record, L = n_short >= 2n - 1, ω_k = 2πk/N, θ_j = 2πj/L and the bins
    k of band b (lower_b ≤ k·(rate/N) < upper_b, computed as
    :func:`rbjax.spectrum.levels._rfft_freq_Hz` does):
    G_bj = v_j/(rate·N·L) Σ_{k∈b} w_k (V(ω_k - θ_j) + V(ω_k + θ_j))/2 where v_j = 1 at
    j = 0 and (even L) j = L/2, whose P_j stands for itself, and 2 elsewhere (P_j and its
    mirror P_{L-j}). V is the de la Vallée-Poussin kernel with h_l = 1 for |l| ≤ m1 - 1,
    (m2 - |l|)/(m2 - m1) up to m2 = L - n + 1, m1 = n:
    V(θ) = sin((m2 + m1)θ/2) sin((m2 - m1)θ/2) / ((m2 - m1) sin²(θ/2)), V(0) = m1 + m2,
    evaluated with its phases π·p/(N·L) reduced exactly in integers (p = kL ∓ jN).
    """
    freq_Hz = np.arange(n_record // 2 + 1, dtype=float) * (rate_Hz / n_record)
    first = np.searchsorted(freq_Hz, np.asarray(lower_Hz), side="left")  # f >= lower
    stop = np.searchsorted(freq_Hz, np.asarray(upper_Hz), side="left")  # f < upper
    n_cols = n_short // 2 + 1
    m1, m2 = n, n_short - n + 1
    period = n_record * n_short  # θ/2 = π p / period
    too_large = int(np.sum(stop - first)) * n_cols > KERNEL_MAX_TERMS
    if too_large or (2 * (m1 + m2) + 1) * period >= 2**63:  # the phases (m1 + m2)·p, int64
        return None

    def vallee_poussin(p):
        den = _sin_pi(p, period)
        num = _sin_pi((m2 + m1) * p, period) * _sin_pi((m2 - m1) * p, period)
        return np.where(den == 0, m1 + m2, num / ((m2 - m1) * np.where(den == 0, 1.0, den) ** 2))

    j = np.arange(n_cols, dtype=np.int64)[None, :]
    self_mirror = (j == 0) | ((n_short % 2 == 0) & (2 * j == n_short))
    kernel = np.zeros((len(lower_Hz), n_cols))
    block = max(1, KERNEL_BLOCK // n_cols)
    for b in range(len(lower_Hz)):
        for k0 in range(int(first[b]), int(stop[b]), block):
            k = np.arange(k0, min(k0 + block, int(stop[b])), dtype=np.int64)[:, None]
            w = np.where((k == 0) | (2 * k == n_record), 1.0, 2.0)  # one-sided weights
            pair = vallee_poussin(k * n_short - j * n_record) + vallee_poussin(
                k * n_short + j * n_record
            )
            kernel[b] += np.sum(w * np.where(self_mirror, pair / 2, pair), axis=0)
    kernel /= rate_Hz * n_record * n_short
    kernel.flags.writeable = False
    return kernel

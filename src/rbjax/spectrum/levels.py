"""Force exposure level L_FE in octave and one-third-octave bands, and the force spectrum.

The processing is the one of Schoenwald, Zeitler & Nightingale (2011), §2.4: the blocked
force is recorded (or predicted) as a 1 s record at 44.1 kHz, an FFT is taken of the whole
record (rectangular window, no detrending) and the energy spectrum is "band filtered in the
frequency domain" to give the octave-band force exposure level (paper Eq. 11)::

    L_FE = 10 log10( (1/T0) ∫ F²(t)/F0² dt ),   T0 = 1 s,  F0 = 1 N.

Bands are the base-ten fractional-octave bands of IEC 61260-1:2014 (Clause 5.2: octave
frequency ratio G = 10^(3/10); Clause 5.3: reference frequency f_r = 1000 Hz; Clause 5.4:
exact mid-band frequencies f_m = f_r G^(x/b) for odd b; the band-edge frequencies
f_1,2 = f_m G^(∓1/(2b)) defined with them in Clause 5), labelled with their nominal
mid-band frequencies (IEC 61260-1:2014 Annex E, the R10 preferred numbers of ISO 266).
The filters here are ideal (brick-wall): every rfft bin belongs to exactly one band, with
``lower <= f < upper``, so contiguous bands tile the spectrum and band energies add up to
the total energy exactly (Parseval).

Everything that takes a force array is pure JAX in float64 and differentiable
(``jax.grad``/``jax.jacfwd``), batchable on leading axes (the time axis is the last one),
and usable under ``jit``/``vmap`` with a concrete (Python or NumPy) ``rate_Hz``. The band
tables are plain NumPy. This module knows nothing about solvers.

Short pulses in a long record: the functions that take a force array accept a keyword
``n_record``: the given samples (..., n) are then the first n of a record of ``n_record``
samples whose other samples are zero (the contact, a few hundred samples, in the paper's
1 s record of 44 100 samples at 44.1 kHz). The result is that of the explicitly zero-padded
record, to round-off; the band energies are then computed without the record-long FFT, from a
short FFT of the pulse and a precomputed band kernel (see :func:`band_energies_N2s`).
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .._validate import check_range, is_traced
from .._x64 import require_x64
from .band_kernel import SHORT_FFT_OVERSAMPLING, SHORT_PATH_MIN_RATIO, band_kernel, fast_length
from .bands import (
    OCTAVE_BANDS,
    THIRD_OCTAVE_BANDS,
    band_edges_Hz,
)

__all__ = [
    "energy_spectrum",
    "band_energies_N2s",
    "lfe_dB",
    "lfe_total_dB",
    "lfe_octave_dB",
    "lfe_third_octave_dB",
    "force_spectrum_dB",
    "contact_resonance_Hz",
    "lfe_increase_per_doubling_dB",
]


# Fine-grid spacing for locating the contact resonance (before refinement).
_RESONANCE_GRID_Hz = 0.1
# Newton refinement steps of the resonance (each clipped to one grid step).
_RESONANCE_NEWTON_STEPS = 4
# Frequencies per block when evaluating the DTFT at arbitrary frequencies.
_DTFT_BLOCK = 64
# Values per block of the short FFT: XLA's batched FFT runs several times slower per record
# once its buffers outgrow the cache (measured: batch 10 000 of 256 samples at ~60-100k/s in
# one piece, ~270-540k/s in blocks of ~340 records), so large batches go by lax.map in blocks.
_SHORT_FFT_BLOCK = 2**18


# --------------------------------------------------------------------------------------
# energy spectrum and band energies (JAX)
# --------------------------------------------------------------------------------------


def _as_force(force_N) -> jax.Array:
    require_x64()
    x = jnp.asarray(force_N, dtype=jnp.float64)
    if x.ndim < 1 or x.shape[-1] < 1:
        raise ValueError(
            f"force_N has shape {tuple(x.shape)}; expected (..., n_samples) with n_samples >= 1"
        )
    return x


def _check_rate(rate_Hz) -> None:
    check_range("rate_Hz", rate_Hz, lower=0.0)


def _check_n_record(n_record, n: int) -> int:
    """The record length: ``n`` when None, else an integer >= n (the samples given)."""
    if n_record is None:
        return n
    is_int = isinstance(n_record, (int, np.integer)) and not isinstance(n_record, (bool, np.bool_))
    if not is_int or n_record < n:
        raise ValueError(
            f"n_record={n_record!r} must be an integer in the valid range [{n}, inf): at least "
            f"the n={n} samples given (the record's first samples; the rest are zero)"
        )
    return int(n_record)


def _rfft_freq_Hz(n: int, rate_Hz) -> jax.Array:
    """rfft bin frequencies k · rate/n (computed so that bin k is exactly k·Δf)."""
    return jnp.arange(n // 2 + 1, dtype=jnp.float64) * (rate_Hz / n)


def _one_sided_weights(n: int) -> jax.Array:
    """2 for bins that stand for a ± pair of frequencies, 1 for DC and (even n) Nyquist."""
    w = np.full(n // 2 + 1, 2.0)
    w[0] = 1.0
    if n % 2 == 0:
        w[-1] = 1.0
    return jnp.asarray(w)


def _abs2(z) -> jax.Array:
    """|z|² written as re² + im² (differentiable at z = 0, unlike abs(z)**2)."""
    return jnp.real(z) ** 2 + jnp.imag(z) ** 2


def energy_spectrum(
    force_N, rate_Hz, *, n_record: int | None = None
) -> tuple[jax.Array, jax.Array]:
    """One-sided energy spectral density of a force record, (N²·s)/Hz.

    F(f_k) ≈ DFT_k / rate (the Fourier integral ∫F(t) e^{-2πift} dt by the rectangle
    rule) at the rfft bins f_k = k·rate/n of the record as it is (rectangular window, no
    detrending, paper §2.4); E_k = w_k |F(f_k)|² with w_k = 2, except w = 1 at DC and, for
    even n, at Nyquist. Parseval holds exactly: sum(E)·Δf = sum(F²)/rate = ∫F² dt (the
    integral of paper Eq. 11), Δf = rate/n.

    Args:
      force_N: force record(s), shape (..., n); the last axis is time.
      rate_Hz: sampling rate, Hz.
      n_record: the record's length N >= n when ``force_N`` holds only its first n
        samples and the rest are zero (the spectrum of the zero-padded record, bins
        k·rate/N); None: N = n.

    Returns:
      (freq_Hz, energy_N2s_per_Hz): shapes (N//2 + 1,) and (..., N//2 + 1).
    """
    _check_rate(rate_Hz)
    x = _as_force(force_N)
    return _energy_spectrum(x, rate_Hz, _check_n_record(n_record, x.shape[-1]))


@functools.partial(jax.jit, static_argnames=("n_fft",))
def _energy_spectrum(x, rate_Hz, n_fft: int):
    spectrum_Ns = jnp.fft.rfft(x, n=n_fft, axis=-1) / rate_Hz
    return _rfft_freq_Hz(n_fft, rate_Hz), _one_sided_weights(n_fft) * _abs2(spectrum_Ns)


def _band_mask(freq_Hz, lower_Hz, upper_Hz) -> jax.Array:
    """(n_bands, n_bins) 0/1 matrix: bin f belongs to band i when lower_i <= f < upper_i."""
    lo = jnp.asarray(lower_Hz, dtype=jnp.float64)[:, None]
    hi = jnp.asarray(upper_Hz, dtype=jnp.float64)[:, None]
    return ((freq_Hz[None, :] >= lo) & (freq_Hz[None, :] < hi)).astype(jnp.float64)


def _check_edges(lower_Hz, upper_Hz) -> None:
    lo, hi = np.shape(lower_Hz), np.shape(upper_Hz)
    if len(lo) != 1 or lo != hi:
        raise ValueError(
            f"lower_Hz (shape {lo}) and upper_Hz (shape {hi}) must be 1-D of equal length"
        )
    if not (is_traced(lower_Hz) or is_traced(upper_Hz)):
        lower, upper = np.asarray(lower_Hz, float), np.asarray(upper_Hz, float)
        if np.any(np.isnan(lower)) or np.any(np.isnan(upper)) or np.any(upper <= lower):
            raise ValueError(
                f"band edges lower_Hz={lower.tolist()}, upper_Hz={upper.tolist()} must be "
                "non-NaN with lower_Hz < upper_Hz in every band"
            )


def band_energies_N2s(
    force_N, rate_Hz, lower_Hz, upper_Hz, *, n_record: int | None = None
) -> jax.Array:
    """Force energy ∫F_band² dt in each band by ideal (brick-wall) filtering, N²·s.

    Each rfft bin f_k of :func:`energy_spectrum` is assigned to the band with
    lower ≤ f_k < upper (half-open), so contiguous bands tile the spectrum and their
    energies add up exactly to the total (paper §2.4: "band filtered in the frequency
    domain").

    With ``n_record`` = N > n, ``force_N`` holds the first n samples of an N-sample record
    whose other samples are zero, and the result is that of the zero-padded record (bins
    f_k = k·rate/N, weights w_k = 2 but 1 at DC and, for even N, Nyquist) to round-off. From
    N >= 3n on it is computed without the N-point FFT: S(ω) = |Σ_m x_m e^{-iωm}|² is a
    trigonometric polynomial of degree n - 1, so it is fixed by its values
    P_j = S(2πj/L) on L >= 2n - 1 points, one rfft of length L (here L >= 3n):
    S(ω) = (1/L) Σ_j P_j V(ω - 2πj/L) for any V(θ) = Σ_l h_l e^{ilθ} with h_l = 1 for
    |l| < n and 0 for |l| > L - n. V is the de la Vallée-Poussin kernel (h tapers linearly
    between those lags), whose tails fall off as θ^-2, so a strong bin far from a band
    leaks little into its sum and the result is as accurate as the padded FFT (the same
    algebra in the lag domain, Σ_l R_l K_bl with the autocorrelation R_l, loses about
    eps·E_total/E_b relative in a weak band b: ~1e-11 for a 20 ms pulse). Band b's
    energy Σ_{k∈b} w_k S(2πk/N)/(rate·N) is then Σ_j P_j G_bj with a kernel G built once
    per (N, n, rate, edges) in NumPy and cached. A traced ``rate_Hz`` or traced edges, or a
    kernel too large to build quickly, take the padded FFT (the same numbers).

    Args:
      force_N: force record(s), shape (..., n).
      rate_Hz: sampling rate, Hz.
      lower_Hz, upper_Hz: band edges, shape (n_bands,), Hz.
      n_record: the record's length N >= n (None: N = n, the record as given).

    Returns:
      energies, shape (..., n_bands), N²·s.
    """
    _check_rate(rate_Hz)
    _check_edges(lower_Hz, upper_Hz)
    x = _as_force(force_N)
    n = x.shape[-1]
    n_record = _check_n_record(n_record, n)
    if n_record >= SHORT_PATH_MIN_RATIO * n and not is_traced((rate_Hz, lower_Hz, upper_Hz)):
        n_short = fast_length(SHORT_FFT_OVERSAMPLING * n)
        kernel = band_kernel(
            n_record,
            n,
            n_short,
            float(np.asarray(rate_Hz).item()),
            tuple(np.asarray(lower_Hz, float).tolist()),
            tuple(np.asarray(upper_Hz, float).tolist()),
        )
        if kernel is not None:
            return _short_fft_band_energies(x, kernel, n_short)
    return _band_energies(x, rate_Hz, lower_Hz, upper_Hz, n_record)


@functools.partial(jax.jit, static_argnames=("n_fft",))
def _band_energies(x, rate_Hz, lower_Hz, upper_Hz, n_fft: int):
    freq_Hz, esd = _energy_spectrum(x, rate_Hz, n_fft)
    delta_f_Hz = rate_Hz / n_fft
    return (esd * delta_f_Hz) @ _band_mask(freq_Hz, lower_Hz, upper_Hz).T


@functools.partial(jax.jit, static_argnames=("n_short",))
def _short_fft_band_energies(x, kernel, n_short: int):
    """Σ_j P_j G_bj with P_j = |rfft(x, n_short)_j|² (see ``rbjax.spectrum.band_kernel``), in blocks
    of records for large batches."""

    def energies(y):
        return _abs2(jnp.fft.rfft(y, n=n_short, axis=-1)) @ kernel.T

    rows = x.reshape(-1, x.shape[-1])
    block = max(1, _SHORT_FFT_BLOCK // n_short)
    if rows.shape[0] <= block:
        return energies(x)
    return jax.lax.map(energies, rows, batch_size=block).reshape(x.shape[:-1] + (-1,))


def lfe_dB(energy_N2s, T0_s: float = 1.0, F0_N: float = 1.0) -> jax.Array:
    """Force exposure level L_FE = 10 log10( E / (T0 F0²) ), dB re 1 N (paper Eq. 11).

    ``energy_N2s`` is E = ∫F² dt (over the record, or of one band), N²·s; T0 = 1 s and
    F0 = 1 N are the paper's reference duration and force. Zero energy gives -inf.
    """
    return 10.0 * jnp.log10(jnp.asarray(energy_N2s, dtype=jnp.float64) / (T0_s * F0_N**2))


def lfe_total_dB(force_N, rate_Hz, *, n_record: int | None = None) -> jax.Array:
    """Broadband L_FE of the record(s) (paper Eq. 11), with ∫F² dt = sum(F²)/rate.

    ``n_record`` >= n (the record's length when ``force_N`` holds its first n samples and
    the rest are zero) is checked; zeros add no energy, so it does not change the result.
    """
    _check_rate(rate_Hz)
    x = _as_force(force_N)
    _check_n_record(n_record, x.shape[-1])
    return _lfe_total_dB(x, rate_Hz)


@jax.jit
def _lfe_total_dB(x, rate_Hz):
    return lfe_dB(jnp.sum(x**2, axis=-1) / rate_Hz)


def _band_lfe_dB(
    force_N, rate_Hz, fraction: int, labels: tuple[str, ...], n_record: int | None
) -> jax.Array:
    lower, upper = band_edges_Hz(fraction, float(labels[0]), float(labels[-1]))
    return lfe_dB(band_energies_N2s(force_N, rate_Hz, lower, upper, n_record=n_record))


def lfe_octave_dB(force_N, rate_Hz, *, n_record: int | None = None) -> jax.Array:
    """Octave-band L_FE (paper Eq. 11, §2.4) over :data:`OCTAVE_BANDS` (31.5 Hz–1 kHz),
    dB re 1 N; shape (..., 6). Bands of IEC 61260-1:2014 (5.2, 5.4), ideal filters.
    ``n_record``: as in :func:`band_energies_N2s` (the samples given are the first of a
    zero-padded record of that length, e.g. 44 100 for the paper's 1 s at 44.1 kHz)."""
    return _band_lfe_dB(force_N, rate_Hz, 1, OCTAVE_BANDS, n_record)


def lfe_third_octave_dB(force_N, rate_Hz, *, n_record: int | None = None) -> jax.Array:
    """One-third-octave-band L_FE (paper Eq. 11) over :data:`THIRD_OCTAVE_BANDS`
    (25 Hz–1.25 kHz), dB re 1 N; shape (..., 18). IEC 61260-1:2014 base-ten bands.
    ``n_record``: as in :func:`band_energies_N2s`."""
    return _band_lfe_dB(force_N, rate_Hz, 3, THIRD_OCTAVE_BANDS, n_record)


# --------------------------------------------------------------------------------------
# narrow-band force spectrum and the contact resonance
# --------------------------------------------------------------------------------------


@jax.jit
def _dtft_Ns(x, rate_Hz, freq_Hz) -> jax.Array:
    """F(f) ≈ sum_n x_n e^{-2πi f n/rate} / rate at arbitrary frequencies; shape (..., m)."""
    n_idx = jnp.arange(x.shape[-1], dtype=jnp.float64)

    def at(f_Hz):
        phase = (-2.0 * jnp.pi / rate_Hz) * f_Hz * n_idx
        return (x @ jnp.cos(phase) + 1j * (x @ jnp.sin(phase))) / rate_Hz

    values = jax.lax.map(at, freq_Hz, batch_size=_DTFT_BLOCK)  # (m, ...)
    return jnp.moveaxis(values, 0, -1)


def force_spectrum_dB(force_N, rate_Hz, freq_Hz=None) -> tuple[jax.Array, jax.Array]:
    """Narrow-band force spectrum level 20 log10(|F(f)| / 1 N·s), dB (paper Fig. 12).

    F(f) = ∫F(t) e^{-2πift} dt is approximated by the DTFT of the samples,
    sum_n F_n e^{-2πi f n/rate} / rate: at the rfft bins when ``freq_Hz`` is None (an FFT),
    otherwise at the given frequencies (any grid, e.g. 0.1 Hz, finer than the 1/duration
    bin spacing). Exact zeros of F give -inf.

    Returns:
      (freq_Hz, level_dB): shapes (m,) and (..., m).
    """
    _check_rate(rate_Hz)
    x = _as_force(force_N)
    if freq_Hz is None:
        freq = _rfft_freq_Hz(x.shape[-1], rate_Hz)
        spectrum_Ns = _rfft_Ns(x, rate_Hz)
    else:
        freq = jnp.atleast_1d(jnp.asarray(freq_Hz, dtype=jnp.float64))
        if freq.ndim != 1:
            raise ValueError(f"freq_Hz has shape {tuple(freq.shape)}; expected 1-D")
        spectrum_Ns = _dtft_Ns(x, rate_Hz, freq)
    return freq, 10.0 * jnp.log10(_abs2(spectrum_Ns))


@jax.jit
def _rfft_Ns(x, rate_Hz) -> jax.Array:
    return jnp.fft.rfft(x, axis=-1) / rate_Hz


def _dtft_derivatives(x, rate_Hz, f_Hz):
    """X(f), X'(f), X''(f) of the DTFT (per record; x (b, n), f (b,))."""
    t_s = jnp.arange(x.shape[-1], dtype=jnp.float64) / rate_Hz
    kernel = jnp.exp(-2j * jnp.pi * f_Hz[:, None] * t_s[None, :]) / rate_Hz * x
    d = -2j * jnp.pi * t_s
    return kernel.sum(-1), (kernel * d).sum(-1), (kernel * d**2).sum(-1)


def _first_notch_bin(power, k_lo, k_hi):
    """Index of the first local minimum of ``power`` (last axis) among bins k_lo..k_hi,
    and whether there is one (k_lo >= 1, k_hi <= last bin - 1)."""
    k = jnp.arange(1, power.shape[-1] - 1)
    mid, left, right = power[..., 1:-1], power[..., :-2], power[..., 2:]
    is_min = (mid < left) & (mid <= right) & (k >= k_lo) & (k <= k_hi)
    return 1 + jnp.argmax(is_min, axis=-1), jnp.any(is_min, axis=-1)


def contact_resonance_Hz(
    force_N, rate_Hz, fmin_Hz: float = 20.0, fmax_Hz: float = 200.0
) -> jax.Array:
    """The "fundamental contact resonance": the first minimum (notch) of the narrow-band
    force spectrum |F(f)| above ``fmin_Hz`` (paper §4.2, Fig. 12: 66 Hz at 10 cm and
    73 Hz at 160 cm drop height for a ~20 ms pulse; a half-sine of duration T has it at
    1.5/T).

    The spectrum is evaluated on a fine grid (≤ 0.1 Hz, the zero-padded FFT, i.e. the exact
    DTFT there), the first local minimum in [fmin_Hz, fmax_Hz] is taken, and refined by
    Newton steps on d|F|²/df = 0 with the analytic DTFT derivatives (each step clipped to
    one grid step). The result is differentiable with respect to the force (through the
    refinement; the grid search itself is held fixed). NaN where there is no minimum.

    Args:
      force_N: force record(s), shape (..., n).
      rate_Hz: sampling rate, Hz (concrete: it sets the grid).
      fmin_Hz, fmax_Hz: search range, Hz, 0 < fmin < fmax < rate/2.

    Returns:
      resonance frequency, Hz, shape (...).
    """
    _check_rate(rate_Hz)
    rate = float(rate_Hz)
    check_range("fmin_Hz", fmin_Hz, lower=0.0, upper=rate / 2)
    check_range("fmax_Hz", fmax_Hz, lower=float(fmin_Hz), upper=rate / 2)
    x = _as_force(force_N)
    n = x.shape[-1]
    n_fft = max(n, math.ceil(rate / _RESONANCE_GRID_Hz))
    step_Hz = rate / n_fft
    k_lo = max(1, math.ceil(float(fmin_Hz) / step_Hz))
    k_hi = min(n_fft // 2 - 1, math.floor(float(fmax_Hz) / step_Hz))
    f = _refined_notch_Hz(x.reshape((-1, n)), rate, n_fft, k_lo, k_hi)
    return f.reshape(x.shape[:-1])


@functools.partial(jax.jit, static_argnames=("rate_Hz", "n_fft"))
def _refined_notch_Hz(x, rate_Hz: float, n_fft: int, k_lo, k_hi) -> jax.Array:
    """First notch of |F(f)| on the grid k·rate/n_fft, k_lo ≤ k ≤ k_hi, Newton-refined;
    x of shape (b, n); NaN where the grid has no local minimum."""
    step_Hz = rate_Hz / n_fft
    grid = jnp.fft.rfft(jax.lax.stop_gradient(x), n=n_fft, axis=-1)
    k, found = _first_notch_bin(_abs2(grid), k_lo, k_hi)

    def newton(_, f):
        X, X1, X2 = _dtft_derivatives(x, rate_Hz, f)
        slope = 2.0 * jnp.real(jnp.conj(X) * X1)
        curvature = 2.0 * (_abs2(X1) + jnp.real(jnp.conj(X) * X2))
        safe = curvature > 0
        step = -slope / jnp.where(safe, curvature, 1.0)
        return f + jnp.where(safe, jnp.clip(step, -step_Hz, step_Hz), 0.0)

    f = jax.lax.fori_loop(0, _RESONANCE_NEWTON_STEPS, newton, k.astype(jnp.float64) * step_Hz)
    return jnp.where(found, f, jnp.nan)


# --------------------------------------------------------------------------------------
# level against drop height (paper Figs. 10-11)
# --------------------------------------------------------------------------------------


def lfe_increase_per_doubling_dB(height_m, lfe_dB, ref_height_m: float = 1.0) -> jax.Array:
    """Increase of L_FE per doubling of drop height, dB: the least-squares slope of L_FE
    against log2(h / h_ref) (paper §4.2, Figs. 10-11; ~3 dB for a linear source whose force
    scales with the impact speed sqrt(2 g h), Eq. 10).

    Args:
      height_m: drop heights, shape (n_heights,), m (> 0, at least two distinct).
      lfe_dB: levels, shape (n_heights,) or (n_heights, n_bands) (any trailing shape):
        heights on the first axis, bands on the last.
      ref_height_m: reference height of the abscissa (moves the intercept, not the slope).

    Returns:
      slope in dB per doubling, shape lfe_dB.shape[1:].
    """
    check_range("height_m", height_m, lower=0.0)
    check_range("ref_height_m", ref_height_m, lower=0.0)
    h = jnp.asarray(height_m, dtype=jnp.float64)
    y = jnp.asarray(lfe_dB, dtype=jnp.float64)
    if h.ndim != 1 or y.ndim < 1 or y.shape[0] != h.shape[0] or h.shape[0] < 2:
        raise ValueError(
            f"height_m has shape {tuple(h.shape)} and lfe_dB has shape {tuple(y.shape)}; "
            "expected (n_heights,) and (n_heights, ...) with n_heights >= 2"
        )
    if not is_traced(height_m) and np.ptp(np.asarray(height_m, float)) == 0:
        raise ValueError(
            f"height_m={np.asarray(height_m).tolist()} needs at least two distinct heights"
        )
    return _least_squares_slope(jnp.log2(h / ref_height_m), y)


@jax.jit
def _least_squares_slope(u, y) -> jax.Array:
    """Slope of y (first axis) against u, per trailing index."""
    du = (u - u.mean()).reshape((-1,) + (1,) * (y.ndim - 1))
    return jnp.sum(du * (y - y.mean(axis=0)), axis=0) / jnp.sum(du**2, axis=0)

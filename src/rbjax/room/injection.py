"""Force → floor: the energy the ball's force history puts into the floor, per band or per mode.

A force F(t) on a drive point of mobility Y(ω) = u̇/F injects (Parseval)

    W = ∫ F u̇ dt = ∫₀^∞ E_F(f) Re Y(f) df,   E_F = 2|F(f)|²  (one-sided, N²·s/Hz).

* An infinite thin plate has the real mobility Y = 1/Z = 1/(8√(B′m″)) (Cremer, Heckl &
  Petersson §5.3), which is also the frequency average of a finite plate's drive-point
  mobility (its modal density × π/(2M)): the energy injected into a band is the force energy
  of the band (``rbjax.spectrum.band_energies_N2s``) over Z. This is the SEA input of a
  resonant slab.
* A modal floor (``AbstractModalFloor``: u = Σ q_k, m_k(q̈_k + η_kω_k q̇_k + ω_k² q_k) = F) has
  Re Y = Σ_k Re Y_k, Re Y_k(ω) = η_kω_kω²/m_k / ((ω_k² − ω²)² + (η_kω_kω)²) (modal
  superposition), so each mode receives W_k = ∫ E_F Re Y_k df. The integral is a sum over a
  uniform grid of the zero-padded spectrum of the force samples (the trapezoidal rule, which
  for the Lorentzian of half-width γ_k = η_k f_k/2 converges as e^{−2πγ_k/Δf}: Δf ≤ γ_k/3
  gives ~1e-8). A mode narrower than the finest grid (γ_k < 3·rate/2²¹) or without loss gets
  the limit W_k = |F(f_k)|²/(2m_k) (Re Y_k → (π/2m_k)δ(ω − ω_k)); a free-mass mode (f_k = 0)
  gets (∫F dt)²/(2m_k). Σ_k W_k = ∫ F u̇ dt, the floor energy of ``rbjax.energy_balance``.
* A floating floor (``FloatingFloor``) over a slab as an insertion: the slab receives the force
  the layer passes, F_slab = T F (``FloatingFloor.force_transmissibility``, EN 12354-2 Annex C's
  40 lg(f/f₀) above the mass–spring resonance), and injects into band b the energy
  Σ_{f∈b} E_F |T|² Δf / Z of the slab's real mobility 1/Z (``floating_band_energies_J``), on the
  grid of ``modal_grid_size`` (which resolves T's resonance, half-width η f₀/2, as a mode's).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .._validate import is_traced
from ..spectrum.levels import band_energies_N2s, energy_spectrum
from ..terms.floors.floating import FloatingFloor
from ..terms.floors.kinds import AbstractModalFloor

#: The finest frequency grid of the modal energies: 2^21 points of the zero-padded record.
MAX_FFT = 2**21
#: Grid points per half-width of the narrowest mode's resonance.
POINTS_PER_HALF_WIDTH = 3.0


def plate_band_energies_J(
    force_N, rate_Hz: float, lower_Hz, upper_Hz, impedance_Ns_per_m, *, n_record: int | None = None
):
    """Energy injected per band into a floor of real point impedance Z: E_band/Z (J)."""
    return (
        band_energies_N2s(force_N, rate_Hz, lower_Hz, upper_Hz, n_record=n_record)
        / impedance_Ns_per_m
    )


def modal_grid_size(floor: AbstractModalFloor, rate_Hz: float, n_samples: int) -> int:
    """The FFT length of ``modal_energies_J`` and ``floating_band_energies_J``: Δf ≤ γ_min/3 over
    the lossy modes (and a floating floor's layer resonance), at least the
    samples' count, at most ``MAX_FFT`` (a power of two). The floor's values must be concrete
    (a shape): under a transformation, compute it first and pass it on as ``n_fft``."""
    if is_traced(floor):
        raise ValueError(
            "modal_grid_size needs the floor's concrete values; under jit/jvp pass "
            "n_fft=modal_grid_size(floor, rate_Hz, n_samples) computed outside"
        )
    _, omega, eta = (np.asarray(x, dtype=np.float64) for x in floor.modes())
    freq = omega / (2.0 * math.pi)
    widths = [0.5 * e * f for f, e in zip(freq, eta) if f > 0.0 and e > 0.0]
    if isinstance(floor, FloatingFloor):
        layer_loss, f0 = (
            float(np.asarray(x)) for x in (floor.layer_loss_factor, floor.layer_resonance_Hz)
        )
        if layer_loss > 0.0:
            widths.append(0.5 * layer_loss * f0)
    step = min([1.0] + [w / POINTS_PER_HALF_WIDTH for w in widths])
    return int(
        min(
            MAX_FFT,
            max(2 ** math.ceil(math.log2(rate_Hz / step)), 2 ** math.ceil(math.log2(n_samples))),
        )
    )


def dtft_Ns(force_N, rate_Hz: float, freq_Hz):
    """F(f) = Σ_n F_n e^{−2πj f n/rate}/rate: the spectrum of the samples at any ``freq_Hz``
    (N·s)."""
    n = jnp.arange(force_N.shape[-1])
    phase = jnp.exp(-2j * jnp.pi * jnp.asarray(freq_Hz)[:, None] * n[None, :] / rate_Hz)
    return phase @ force_N / rate_Hz


def modal_energies_J(force_N, rate_Hz: float, floor: AbstractModalFloor, n_fft: int | None = None):
    """Energy W_k injected into each mode of ``floor`` by the force samples (module docstring);
    shape (num_modes,). ``force_N`` holds every non-zero sample of the record (1-D); ``n_fft``:
    the grid (default ``modal_grid_size``; give it where the floor's values are traced)."""
    x = jnp.asarray(force_N, dtype=jnp.float64)
    n_fft = modal_grid_size(floor, rate_Hz, x.shape[-1]) if n_fft is None else int(n_fft)
    freq, esd = energy_spectrum(x, rate_Hz, n_record=n_fft)
    df = rate_Hz / n_fft
    mass, omega, eta = floor.modes()
    fk = omega / (2.0 * jnp.pi)
    resolved = (
        (fk > 0.0) & (eta > 0.0) & (0.5 * eta * fk >= POINTS_PER_HALF_WIDTH * df * (1.0 - 1e-12))
    )
    w = 2.0 * jnp.pi * freq

    def one(args):
        m, wk, e = args
        re_y = e * wk * w**2 / m / ((wk**2 - w**2) ** 2 + (e * wk * w) ** 2)
        return jnp.sum(esd * re_y) * df

    # an unresolved mode's sum is not used: a harmless resonance (half the Nyquist frequency,
    # η = 1) stands in for it, so that no 0/0 reaches the values or the gradient
    grid = jax.lax.map(
        one,
        (mass, jnp.where(resolved, omega, 0.5 * jnp.pi * rate_Hz), jnp.where(resolved, eta, 1.0)),
    )
    spectrum = dtft_Ns(x, rate_Hz, fk)
    narrow = (spectrum.real**2 + spectrum.imag**2) / (2.0 * mass)
    return jnp.where(resolved, grid, narrow)


def floating_band_energies_J(
    force_N,
    rate_Hz: float,
    lower_Hz,
    upper_Hz,
    floor: FloatingFloor,
    impedance_Ns_per_m,
    n_fft: int,
):
    """Energy injected per band into a slab of real point impedance Z through the layer of a
    floating floor: Σ_{lower ≤ f < upper} E_F(f) |T(f)|² Δf / Z on the ``n_fft``-point grid of the
    zero-padded force record (module docstring)."""
    freq, esd = energy_spectrum(
        jnp.asarray(force_N, dtype=jnp.float64), rate_Hz, n_record=int(n_fft)
    )
    t = floor.force_transmissibility(freq)
    passed = esd * (t.real**2 + t.imag**2) * (rate_Hz / int(n_fft))
    grid = np.fft.rfftfreq(int(n_fft), 1.0 / rate_Hz)
    inside = (grid[None, :] >= np.asarray(lower_Hz)[:, None]) & (
        grid[None, :] < np.asarray(upper_Hz)[:, None]
    )
    return (
        jnp.sum(jnp.where(jnp.asarray(inside), passed[None, :], 0.0), axis=-1) / impedance_Ns_per_m
    )

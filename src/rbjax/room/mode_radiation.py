"""The radiation efficiency of one mode of a simply supported rectangular plate in a baffle.

A mode φ_mn = sin(mπx/a) sin(nπy/b) of a plate a × b in an infinite rigid baffle, vibrating at
wavenumber k = ω/c₀, radiates into the half space the far-field power of its velocity; per unit
of ρ₀c₀ S ⟨v²⟩ (the space- and time-averaged mean square velocity) that is (Wallace 1972,
JASA 51, 946, Eq. 6; Gomperts 1974, Acustica 30, 320)

    σ_mn = (64 k² a b/(π⁶ m² n²)) ∫₀^{π/2} ∫₀^{π/2} [F_m(α) F_n(β)]² sin θ dθ dφ,

    α = k a sin θ cos φ,   β = k b sin θ sin φ,
    F_m(α) = {cos(α/2) (m odd) or sin(α/2) (m even)} / ((α/(mπ))² − 1).

With δ = α − mπ both parities give |F_m| = |sin(δ/2)| (mπ)²/(|δ| (α + mπ)), which is evaluated as
(mπ)² sinc(δ/2π)/(2(α + mπ)) (no 0/0 at α = mπ, the trace-matching of the mode). Limits:
acoustically small (ka, kb ≪ 1) an odd–odd mode has σ → 32k²ab/(π⁵m²n²) (Wallace Eq. 13),
even modes less (their volume velocity cancels); well above its coincidence (k ≫ the mode's
wavenumber) σ → 1. It is the per-mode counterpart of the band-averaged σ of ISO 12354-1
Annex B (``rbjax.room.radiation``): below coincidence it counts the slab's size through the
mode's edge and corner cells.

The double integral is a product Gauss–Legendre rule of ``nodes`` × ``nodes`` points (default
64): against adaptive quadrature (``scipy.integrate.dblquad``) to 1e-8 relative for ka, kb ≤ 10
(the modes of a 4 m × 5 m slab below 100 Hz) and 1e-4 at ka ≈ 40 (checked in
``tests/room/test_finite_slab.py``); modes that far above the modal bands enter their levels only
through the tails of their resonances.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from .radiation import SPEED_OF_SOUND_m_per_s

#: Gauss–Legendre nodes per angle of the far-field integral.
RADIATION_NODES = 64


def _mode_factor(alpha, order):
    """|F_m(α)| in the stable form of the module docstring."""
    mp = order * math.pi
    return mp**2 * jnp.sinc((alpha - mp) / (2.0 * math.pi)) / (2.0 * (alpha + mp))


def mode_radiation_efficiency(
    freq_Hz, order_x, order_y, length_x_m, length_y_m, *, nodes: int = RADIATION_NODES
):
    """σ_mn of the modes (``order_x``, ``order_y``) of a baffled simply supported plate at
    ``freq_Hz`` (Wallace 1972; module docstring). Arguments broadcast to one shape; the
    result has it. Differentiable in the frequency and the sides."""
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    angle = jnp.asarray(0.25 * math.pi * (x + 1.0))  # [0, π/2]
    weight = jnp.asarray(0.25 * math.pi * w)
    f = jnp.asarray(freq_Hz, dtype=jnp.float64)
    m = jnp.asarray(order_x, dtype=jnp.float64)
    n = jnp.asarray(order_y, dtype=jnp.float64)
    f, m, n = jnp.broadcast_arrays(f, m, n)
    k = 2.0 * math.pi * f / SPEED_OF_SOUND_m_per_s
    theta = angle[:, None]
    phi = angle[None, :]
    sin_t = jnp.sin(theta)
    ka = (k * length_x_m)[..., None, None]
    kb = (k * length_y_m)[..., None, None]
    alpha = ka * sin_t * jnp.cos(phi)
    beta = kb * sin_t * jnp.sin(phi)
    integrand = (
        _mode_factor(alpha, m[..., None, None]) * _mode_factor(beta, n[..., None, None])
    ) ** 2 * sin_t
    total = jnp.einsum("...ij,i,j->...", integrand, weight, weight)
    return 64.0 * k**2 * length_x_m * length_y_m / (math.pi**6 * m**2 * n**2) * total

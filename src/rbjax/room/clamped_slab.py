"""The modes of a rectangular thin plate with clamped edges: Warburton's beam-function modes,
their frequencies by Rayleigh's quotient and the radiation efficiency of each in a baffle.

**Modes.** A plate l_x × l_y clamped on its four edges has no closed-form modes. Warburton
(1954, Proc. IMechE 168, 371) takes as mode (m, n) the product of the clamped–clamped beam
functions along the two sides, φ_mn(x, y) = X_m(x/l_x) X_n(y/l_y), with (Blevins, *Formulas
for Natural Frequency and Mode Shape*, 1979, Table 8-1)

    X_m(z) = cosh β_m z − cos β_m z − s_m (sinh β_m z − sin β_m z),
    s_m = (cosh β_m − cos β_m)/(sinh β_m − sin β_m),   cos β_m cosh β_m = 1,

β₁ = 4.730…, β_m → (m + ½)π, normalised so that ∫₀¹ X_m² dz = 1 (``beam_function``; evaluated
in a form free of the cancellation of cosh against sinh at large β). Each mode has modal mass
m″ l_x l_y and, driven at (x₀, y₀), 1/m_k = φ_mn(x₀, y₀)²/(m″ l_x l_y).

**Frequencies.** Rayleigh's quotient of that shape (the plate's bending energy over its kinetic
energy; the cross terms ∫X″X = −∫X′² by parts, the clamped ends dropping the boundary terms):

    ω_mn² = (B′/m″) [(β_m/l_x)⁴ + (β_n/l_y)⁴ + 2 I_m I_n/(l_x l_y)²],   I_m = ∫₀¹ X_m′² dz,

Poisson's ratio cancelling between the ν and (1 − ν) terms. It is Warburton's formula with his
G = β/π and H = J = I/π² evaluated exactly instead of from his rounded table (G₁ = 1.506,
H₁ = 1.248; G = m + ½, H = G²(1 − 2/(Gπ)) above). A one-term Rayleigh estimate lies above the
true frequency: for a square plate 36.11 against 35.99 for λ² = ωa²√(m″/B′) of the first mode
(Leissa, JSV 31 (1973) 257, Table 1), and within 1 % for the low modes of the slabs here
(``tests/room/test_clamped_slab.py``, against a finite-difference eigen-solve).

**Radiation.** A baffled plate vibrating in the shape φ radiates, per unit ρ₀c₀S⟨v²⟩ (the
far field of its wavenumber transform, Williams, *Fourier Acoustics*, 1999, ch. 2, after the
change of variables κ = k sin θ (cos ψ, sin ψ) that removes the 1/√(k² − κ²) singularity)

    σ = (k² l_x l_y/π²) ∫∫ |X̂_m(k l_x sin θ cos ψ)|² |X̂_n(k l_y sin θ sin ψ)|² sin θ dθ dψ,
    X̂_m(q) = ∫₀¹ X_m(z) e^{−iqz} dz   (θ, ψ over [0, π/2] each)

(closed form, ``beam_transform``). For sine modes the same integral is Wallace's (1972)
(``rbjax.room.mode_radiation``). The product Gauss–Legendre rule is that of
``mode_radiation.RADIATION_NODES``.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .mode_radiation import RADIATION_NODES
from .radiation import SPEED_OF_SOUND_m_per_s

#: Gauss–Legendre nodes for I_m = ∫X_m′² (the integrand is smooth; exact to rounding).
SLOPE_NODES = 400


def beam_root(order: int) -> float:
    """β_m, the m-th positive root of cos β cosh β = 1 (m ≥ 1): Newton from (m + ½)π on
    cos β − 1/cosh β = 0 (a form with no overflow)."""
    beta = (order + 0.5) * math.pi
    for _ in range(50):
        value = math.cos(beta) - 1.0 / math.cosh(beta)
        slope = -math.sin(beta) + math.tanh(beta) / math.cosh(beta)
        step = value / slope
        beta -= step
        if abs(step) < 1e-15 * beta:
            break
    return beta


def _coefficients(order):
    """(β, s, A, B) per order (numpy): X = A e^{β(z−1)} + B e^{−βz} − cos βz + s sin βz, the
    beam function with cosh and sinh split into their growing and decaying exponentials."""
    orders = np.asarray(order, dtype=int)
    beta = np.array([beam_root(int(m)) for m in orders.reshape(-1)]).reshape(orders.shape)
    decay = np.exp(-beta)
    # s = (cosh β − cos β)/(sinh β − sin β) with both over e^β/2
    s = (1.0 + decay**2 - 2.0 * decay * np.cos(beta)) / (
        1.0 - decay**2 - 2.0 * decay * np.sin(beta)
    )
    # (1 − s)e^β/2 = (cos β − sin β − e^{−β})/(1 − e^{−2β} − 2e^{−β} sin β)
    a = (np.cos(beta) - np.sin(beta) - decay) / (1.0 - decay**2 - 2.0 * decay * np.sin(beta))
    return beta, s, a, 0.5 * (1.0 + s)


def beam_function(order, z):
    """X_m(z) of the clamped–clamped beam on 0 ≤ z ≤ 1 (module docstring; ``order`` static,
    numpy integers; ``z`` broadcasts with it)."""
    beta, s, a, b = _coefficients(order)
    z = jnp.asarray(z, dtype=jnp.float64)
    return (
        a * jnp.exp(beta * (z - 1.0))
        + b * jnp.exp(-beta * z)
        - jnp.cos(beta * z)
        + s * jnp.sin(beta * z)
    )


def slope_integral(order) -> np.ndarray:
    """I_m = ∫₀¹ X_m′(z)² dz per order (numpy, Gauss–Legendre)."""
    beta, s, a, b = _coefficients(order)
    x, w = np.polynomial.legendre.leggauss(SLOPE_NODES)
    z = 0.5 * (x + 1.0)
    beta, s, a, b = (np.asarray(c)[..., None] for c in (beta, s, a, b))
    slope = beta * (
        a * np.exp(beta * (z - 1.0))
        - b * np.exp(-beta * z)
        + np.sin(beta * z)
        + s * np.cos(beta * z)
    )
    return 0.5 * np.sum(w * slope**2, axis=-1)


def clamped_frequencies_Hz(speed_constant, order_x, order_y, length_x_m, length_y_m):
    """f_mn of the clamped plate by Rayleigh's quotient (module docstring);
    ``speed_constant`` = √(B′/m″) (m²/s), the orders static numpy arrays."""
    bx, _, _, _ = _coefficients(order_x)
    by, _, _, _ = _coefficients(order_y)
    cross = 2.0 * slope_integral(order_x) * slope_integral(order_y)
    lx, ly = length_x_m, length_y_m
    omega_sq = (bx / lx) ** 4 + (by / ly) ** 4 + cross / (lx * ly) ** 2
    return speed_constant * jnp.sqrt(omega_sq) / (2.0 * math.pi)


def _sinc_exp(x):
    """∫₀¹ e^{ixz} dz = e^{ix/2} sinc(x/2π) (no 0/0 at x = 0)."""
    return jnp.exp(0.5j * x) * jnp.sinc(x / (2.0 * math.pi))


def _transform(coefficients, q):
    """X̂(q) from the beam's (β, s, A, B) (arrays broadcasting with q)."""
    beta, s, a, b = coefficients
    growing = a * (jnp.exp(-1j * q) - jnp.exp(-beta)) / (beta - 1j * q)
    decaying = b * (1.0 - jnp.exp(-beta) * jnp.exp(-1j * q)) / (beta + 1j * q)
    plus, minus = _sinc_exp(beta - q), _sinc_exp(-beta - q)
    return growing + decaying - 0.5 * (plus + minus) + s * (plus - minus) / 2j


def beam_transform(order, q):
    """X̂_m(q) = ∫₀¹ X_m(z) e^{−iqz} dz in closed form (complex; ``order`` static)."""
    return _transform(_coefficients(order), jnp.asarray(q, dtype=jnp.float64))


@jax.jit
def _radiation_integral(k, length_x_m, length_y_m, along_x, along_y, angle, weight):
    """(k² l_x l_y/π²) ∫∫ |X̂|²|Ŷ|² sin θ by the product rule (one fused program: the modes ×
    nodes² transforms are the cost)."""
    theta, psi = angle[:, None], angle[None, :]
    sin_t = jnp.sin(theta)
    ka = (k * length_x_m)[..., None, None]
    kb = (k * length_y_m)[..., None, None]
    coefficients_x = tuple(c[..., None, None] for c in along_x)
    coefficients_y = tuple(c[..., None, None] for c in along_y)
    x = jnp.abs(_transform(coefficients_x, ka * sin_t * jnp.cos(psi))) ** 2
    y = jnp.abs(_transform(coefficients_y, kb * sin_t * jnp.sin(psi))) ** 2
    total = jnp.einsum("...ij,i,j->...", x * y * sin_t, weight, weight)
    return k**2 * length_x_m * length_y_m / math.pi**2 * total


def clamped_radiation_efficiency(
    freq_Hz, order_x, order_y, length_x_m, length_y_m, *, nodes: int = RADIATION_NODES
):
    """σ_mn of the modes (``order_x``, ``order_y``: static numpy arrays of one shape) of a
    baffled clamped plate at ``freq_Hz`` (their shape; module docstring). Differentiable in
    the frequency and the sides."""
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    f = jnp.asarray(freq_Hz, dtype=jnp.float64)
    k = 2.0 * math.pi * f / SPEED_OF_SOUND_m_per_s
    along_x = tuple(jnp.asarray(c) for c in _coefficients(order_x))
    along_y = tuple(jnp.asarray(c) for c in _coefficients(order_y))
    return _radiation_integral(
        k,
        jnp.asarray(length_x_m, dtype=jnp.float64),
        jnp.asarray(length_y_m, dtype=jnp.float64),
        along_x,
        along_y,
        jnp.asarray(0.25 * math.pi * (x + 1.0)),  # [0, π/2]
        jnp.asarray(0.25 * math.pi * w),
    )

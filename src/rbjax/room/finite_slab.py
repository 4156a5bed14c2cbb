"""The finite slab at low frequencies: the modes of a rectangular thin plate with simply
supported or clamped edges, its drive-point mobility and the energy a force injects into each
mode per band. Below, the simply supported modes in closed form; the clamped ones (Warburton's
beam-function modes, their frequencies by Rayleigh's quotient and their radiation) are in
``rbjax.room.clamped_slab``, and everything from the mobility on is the same for both.

**Modes.** A thin (Kirchhoff) plate l_x × l_y of bending stiffness B′ = Et³/(12(1 − ν²)) and
mass per area m″ = ρt, simply supported on its four edges, has the modes (Leissa, *Vibration of
Plates*, NASA SP-160, 1969, §4.1; Cremer, Heckl & Petersson, *Structure-Borne Sound*, 3rd ed.,
§5.5)

    φ_mn(x, y) = sin(mπx/l_x) sin(nπy/l_y),   ω_mn = √(B′/m″) [(mπ/l_x)² + (nπ/l_y)²],

m, n ≥ 1, each of modal mass m″ ∫φ² dS = m″ l_x l_y/4. Driven at (x₀, y₀) it has the mobility

    Y(ω) = Σ_k jω / (m_k (ω_k² − ω² + j η_k ω_k ω)),   1/m_k = 4 φ_k(x₀, y₀)²/(m″ l_x l_y),

a sum of resonators (viscous loss, as ``rbjax.room.injection``'s modal floors): a mode with a
node at the drive point (the even modes at the centre) takes nothing. Its frequency average is
the infinite plate's 1/(8√(B′m″)) (modal density (l_x l_y/2)√(m″/B′) times π/(2M) times
⟨4φ²⟩ = 1), so where many modes share a band the modal sum joins the infinite-plate result.

**Loss.** η_k = η_s(f_k) + 2η_rad,k: the slab's structural loss (``Slab.structural_loss``) and
the radiation into the rooms on both faces, η_rad,k = ρ₀c₀σ_k/(ω_k m″) with σ_k the mode's own
radiation efficiency (``rbjax.room.mode_radiation``, from the slab's size): the band sources of
the chain count 2η_rad the same way.

**Energy per band.** A force of one-sided energy spectrum E_F = 2|F(f)|² (the DTFT of the
samples, as the infinite plate's band energies) injects into mode k within band b

    W_kb = ∫_b E_F(f) Re Y_k(f) df,
    Re Y_k = η_k ω_k ω²/m_k / ((ω_k² − ω²)² + (η_k ω_k ω)²).

The band integral is taken by Gauss–Legendre after f = f_k + γ_k tan u (γ_k = η_k f_k/2: the
resonance becomes flat in u), on two panels of ``QUADRATURE_NODES`` nodes; against adaptive
quadrature of the same integral 1e-9 relative for η ≥ 0.01 and 1e-6 at η = 0.002. The band's
edges cut a mode's resonance where they fall (as a band filter does): a mode that crosses an
edge moves its energy across smoothly, so the levels are smooth in the slab's parameters.

**Which modes.** Every (m, n) with m ≤ M, n ≤ N; ``mode_orders`` picks M, N so that every mode
below ``MODE_CUTOFF`` times the highest band edge is in (the others add only the tails of their
resonances, < 1e-3 of a band's energy). M, N are a shape: computed from concrete values and
passed on under a transformation.

**Validity.** Thin plate (t ≤ min(l_x, l_y)/10, checked by ``Slab``), isotropic, edges simply
supported or clamped (a slab cast into walls lies between the two; clamped edges raise the
lowest modes, by 1.83× for a square plate, so the modal bands depend on the edge), one drive
point (the standards average several: ``rbjax.room.position_average``), the ball's force
that on the infinite plate of the section (the slab's drive-point impedance, ≈ 4.5e5 N·s/m for
150 mm of concrete, is far above the ball's: the force is that on a rigid floor).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from .._validate import is_traced
from .clamped_slab import beam_function, clamped_frequencies_Hz, clamped_radiation_efficiency
from .injection import dtft_Ns
from .mode_radiation import mode_radiation_efficiency
from .radiation import AIR_DENSITY_kg_per_m3, SPEED_OF_SOUND_m_per_s, bending_stiffness_Nm

#: The edge conditions offered.
EDGE_CONDITIONS = ("simply-supported", "clamped")
#: Modes are taken up to this multiple of the highest band edge.
MODE_CUTOFF = 4.0
#: Gauss–Legendre nodes per panel of a mode's band integral (two panels).
QUADRATURE_NODES = 48


def bending_speed_constant(slab):
    """√(B′/m″), m²/s: ω_mn = √(B′/m″) k_mn² (module docstring)."""
    return jnp.sqrt(
        bending_stiffness_Nm(slab.thickness_m, slab.youngs_Pa, slab.poisson)
        / slab.mass_per_area_kg_per_m2
    )


def mode_orders(slab, upper_Hz: float) -> tuple[int, int]:
    """(M, N): the largest orders along x and y of the modes below ``MODE_CUTOFF`` ×
    ``upper_Hz`` (module docstring); needs the slab's concrete values (a shape)."""
    if is_traced(slab):
        raise ValueError(
            "mode_orders needs the slab's concrete values; under jit/jvp pass "
            "orders=mode_orders(slab, upper_Hz) computed outside"
        )
    c = float(np.asarray(bending_speed_constant(slab)))
    cutoff = MODE_CUTOFF * float(upper_Hz)
    # f_m1 = (π/2) c ((m/l_x)² + (1/l_y)²) ≤ cutoff, and the same along y
    lx, ly = (float(np.asarray(x)) for x in (slab.length_x_m, slab.length_y_m))
    bound = 2.0 * cutoff / (math.pi * c)
    m_max = math.sqrt(max(bound - 1.0 / ly**2, 0.0)) * lx
    n_max = math.sqrt(max(bound - 1.0 / lx**2, 0.0)) * ly
    return max(1, int(math.floor(m_max))), max(1, int(math.floor(n_max)))


def mode_indices(orders: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The orders (m, n) of every mode of the set ``orders`` = (M, N), m-major."""
    m, n = np.meshgrid(np.arange(1, orders[0] + 1), np.arange(1, orders[1] + 1), indexing="ij")
    return m.reshape(-1).astype(float), n.reshape(-1).astype(float)


def slab_modes(slab, orders: tuple[int, int]):
    """Per mode of the set ``orders``: (f_k in Hz, 1/m_k in 1/kg at the drive point, σ_k,
    η_k, η_rad,k) of the slab with its ``edge`` condition (module docstring; clamped edges:
    ``rbjax.room.clamped_slab``); differentiable in the slab."""
    m, n = mode_indices(orders)
    lx, ly = slab.length_x_m, slab.length_y_m
    x0, y0 = slab.drive_point_m
    mass = slab.mass_per_area_kg_per_m2
    if slab.edge == "clamped":
        freq = clamped_frequencies_Hz(bending_speed_constant(slab), m, n, lx, ly)
        shape = beam_function(m, x0 / lx) * beam_function(n, y0 / ly)
        inverse_mass = shape**2 / (mass * lx * ly)
        sigma = clamped_radiation_efficiency(freq, m, n, lx, ly)
    else:
        k_sq = (m * math.pi / lx) ** 2 + (n * math.pi / ly) ** 2
        freq = bending_speed_constant(slab) * k_sq / (2.0 * math.pi)
        shape = jnp.sin(m * math.pi * x0 / lx) * jnp.sin(n * math.pi * y0 / ly)
        inverse_mass = 4.0 * shape**2 / (mass * lx * ly)
        sigma = mode_radiation_efficiency(freq, m, n, lx, ly)
    omega = 2.0 * math.pi * freq
    eta_rad = AIR_DENSITY_kg_per_m3 * SPEED_OF_SOUND_m_per_s * sigma / (omega * mass)
    eta = slab.structural_loss(freq) + 2.0 * eta_rad
    return freq, inverse_mass, sigma, eta, eta_rad


def modal_band_energies_J(
    force_N,
    rate_Hz: float,
    freq_Hz,
    loss_factor,
    inverse_mass_per_kg,
    lower_Hz,
    upper_Hz,
    *,
    nodes: int = QUADRATURE_NODES,
):
    """W_kb = ∫_b E_F Re Y_k df of each mode k (``freq_Hz``, ``loss_factor``, 1/m_k) and band b
    (``lower_Hz`` ≤ f < ``upper_Hz``): shape (modes, bands) (module docstring). ``force_N``:
    every non-zero sample of the record (1-D) at ``rate_Hz``."""
    x = jnp.asarray(force_N, dtype=jnp.float64)
    gx, gw = np.polynomial.legendre.leggauss(int(nodes))
    lo = jnp.asarray(lower_Hz, dtype=jnp.float64)
    hi = jnp.asarray(upper_Hz, dtype=jnp.float64)

    def one(args):
        fk, eta, inv_m = args
        gamma = 0.5 * eta * fk
        u_lo = jnp.arctan((lo - fk) / gamma)
        u_hi = jnp.arctan((hi - fk) / gamma)
        mid = 0.5 * (u_lo + u_hi)
        # two panels [u_lo, mid], [mid, u_hi]: (bands, 2, nodes)
        a = jnp.stack([u_lo, mid], axis=-1)[..., None]
        b = jnp.stack([mid, u_hi], axis=-1)[..., None]
        u = 0.5 * (a + b) + 0.5 * (b - a) * gx
        f = fk + gamma * jnp.tan(u)
        spectrum = dtft_Ns(x, rate_Hz, f.reshape(-1)).reshape(f.shape)
        esd = 2.0 * (spectrum.real**2 + spectrum.imag**2)
        wk, w = 2.0 * math.pi * fk, 2.0 * math.pi * f
        re_y = inv_m * eta * wk * w**2 / ((wk**2 - w**2) ** 2 + (eta * wk * w) ** 2)
        jac = gamma / jnp.cos(u) ** 2
        return jnp.sum(0.5 * (b - a) * gw * esd * re_y * jac, axis=(-2, -1))

    return jax.lax.map(one, (jnp.asarray(freq_Hz), jnp.asarray(loss_factor), inverse_mass_per_kg))

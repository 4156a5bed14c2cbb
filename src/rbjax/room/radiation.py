"""Sound radiated by a floor slab into the room below: the critical frequency, the radiation
efficiency σ of a rectangular plate and the radiation loss factor.

The slab of thickness t, Young's modulus E, density ρ and Poisson's ratio ν has the bending
stiffness per width B′ = Et³/(12(1 − ν²)) and the mass per area m″ = ρt; bending waves in it
are as fast as sound in air at the critical (coincidence) frequency

    f_c = (c₀²/2π) √(m″/B′)

(Cremer, Heckl & Petersson, *Structure-Borne Sound*, 3rd ed., §6.2; ISO 12354-1:2017 Eq. B.1
in the form f_c = c₀²/(1.8 c_L t)). A 150 mm C30/37 slab has f_c ≈ 112 Hz.

**Radiation efficiency** σ = P/(ρ₀c₀S⟨v²⟩) of the resonant (free) bending field of a
rectangular plate l₁ × l₂ (perimeter P, area S) in a baffle, after Maidanik (1962, JASA 34,
809) and Leppington, Broadbent & Heron (1982, Proc. R. Soc. A 382, 245), in the form of
ISO 12354-1:2017 Annex B (EN 12354-1:2000 Annex B):

    σ₁ = 1/√(1 − f_c/f),   σ₂ = 4 l₁l₂ (f/c₀)²,   σ₃ = √(2πf (l₁ + l₂)/(16 c₀)),
    f₁₁ = (c₀²/(4f_c)) (1/l₁² + 1/l₂²);

if f₁₁ ≤ f_c/2: σ = σ₁ above f_c (at most σ₃, Leppington's value at coincidence); below f_c,
with λ = √(f/f_c),

    δ₁ = [(1 − λ²) ln((1 + λ)/(1 − λ)) + 2λ] / [4π²(1 − λ²)^{3/2}],
    δ₂ = 8c₀²(1 − 2λ²) / [f_c²π⁴ l₁l₂ λ √(1 − λ²)]   (f < f_c/2; 0 above),
    σ = (2(l₁ + l₂)c₀/(l₁l₂f_c)) δ₁ + δ₂   (the edge and corner modes of Maidanik),

and σ = σ₂ where f < f₁₁ and σ₂ is smaller; if f₁₁ > f_c/2 (a small or thin plate): σ₂ below
f_c and σ₁ above where they are below σ₃, σ₃ otherwise. σ is at most 2. It is evaluated at
the exact mid-band frequencies (band values, as in ISO 12354-1).

**Radiation loss factor.** A resonant field of energy E = m″S⟨v²⟩ radiates into the room
below P = ρ₀c₀Sσ⟨v²⟩ = ω η_rad E with η_rad = ρ₀c₀σ/(ωm″) (Cremer, Heckl & Petersson §6.6;
ISO 12354-1 Eq. C.3 counts both sides, 2η_rad). Validity: a thin plate (bending wavelength
≫ t: f ≪ c_L/(6t)), in a baffle, resonant transmission only (the forced, non-resonant field
near the drive point is left out: a heavy slab radiates mostly above its first modes).
"""

from __future__ import annotations

import math

import jax.numpy as jnp

#: Air at 20 °C, 101.325 kPa: density, kg/m³, and speed of sound, m/s (ISO 12354-1:2017, 3.x
#: constants ρ₀ = 1.21 kg/m³, c₀ = 343 m/s).
AIR_DENSITY_kg_per_m3 = 1.21
SPEED_OF_SOUND_m_per_s = 343.0


def bending_stiffness_Nm(thickness_m, youngs_Pa, poisson):
    """B′ = E t³/(12(1 − ν²)), N·m (per unit width)."""
    return youngs_Pa * thickness_m**3 / (12.0 * (1.0 - poisson**2))


def critical_frequency_Hz(thickness_m, youngs_Pa, density_kg_per_m3, poisson):
    """f_c = (c₀²/2π)√(m″/B′) (module docstring)."""
    mass = density_kg_per_m3 * thickness_m
    return (
        SPEED_OF_SOUND_m_per_s**2
        / (2.0 * math.pi)
        * jnp.sqrt(mass / bending_stiffness_Nm(thickness_m, youngs_Pa, poisson))
    )


def radiation_efficiency(freq_Hz, critical_Hz, length_x_m, length_y_m):
    """σ of a rectangular plate at ``freq_Hz`` (ISO 12354-1 Annex B; module docstring)."""
    f = jnp.asarray(freq_Hz, dtype=jnp.float64)
    fc, l1, l2, c0 = critical_Hz, length_x_m, length_y_m, SPEED_OF_SOUND_m_per_s
    above = f > fc
    below_ratio = jnp.where(above, 0.5, f / fc)  # λ², kept inside (0, 1) where not used
    sigma1 = 1.0 / jnp.sqrt(1.0 - jnp.where(above, fc / f, 0.5))
    sigma2 = 4.0 * l1 * l2 * (f / c0) ** 2
    sigma3 = jnp.sqrt(2.0 * math.pi * f * (l1 + l2) / (16.0 * c0))
    f11 = c0**2 / (4.0 * fc) * (1.0 / l1**2 + 1.0 / l2**2)

    lam = jnp.sqrt(below_ratio)
    one = 1.0 - below_ratio
    delta1 = (one * jnp.log((1.0 + lam) / (1.0 - lam)) + 2.0 * lam) / (4.0 * math.pi**2 * one**1.5)
    delta2 = jnp.where(
        f < 0.5 * fc,
        8.0
        * c0**2
        * (1.0 - 2.0 * below_ratio)
        / (fc**2 * math.pi**4 * l1 * l2 * lam * jnp.sqrt(one)),
        0.0,
    )
    edge = 2.0 * (l1 + l2) * c0 / (l1 * l2 * fc) * delta1 + delta2
    edge = jnp.where((f < f11) & (sigma2 < edge), sigma2, edge)
    large = jnp.where(above, jnp.minimum(sigma1, sigma3), edge)
    small = jnp.where(
        ~above & (sigma2 < sigma3), sigma2, jnp.where(above & (sigma1 < sigma3), sigma1, sigma3)
    )
    return jnp.minimum(jnp.where(f11 <= 0.5 * fc, large, small), 2.0)


def radiation_loss_factor(freq_Hz, sigma, mass_per_area_kg_per_m2):
    """η_rad = ρ₀c₀σ/(ωm″): the loss of a resonant field by radiation into one room."""
    return (
        AIR_DENSITY_kg_per_m3
        * SPEED_OF_SOUND_m_per_s
        * sigma
        / (2.0 * math.pi * freq_Hz * mass_per_area_kg_per_m2)
    )

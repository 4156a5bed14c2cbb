"""The terms of the ball's force on the floor, each a small pure function (paper §2.2–2.3).

Every function takes the deflection δ (m) of the shell at the contact point, measured from
first contact, and returns newtons. The printed Eqs. 3 and 4 of the paper are corrupted in
transcription; the corrected forms used here are derived in each docstring.

Extensions beyond the paper (damping, stiffening) are pytrees: a term is present only
when the caller passes one ("model no more than a scene needs").
"""

from __future__ import annotations

import functools
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike

from .declare import NON_NEGATIVE, Parameter, check_declared

#: Ambient (atmospheric) pressure p_a in Pa; the ball's vent hole makes p_0 = p_a (§2.2).
AMBIENT_PRESSURE_Pa = 101_325.0
#: Ratio of specific heats of air for the adiabatic cavity compression (§2.2).
GAMMA_AIR = 1.4


def reissner_stiffness_N_per_m(ball) -> jnp.ndarray:
    """Reissner's point-load stiffness of a shallow spherical shell (paper Eqs. 1–3, corrected).

    Eq. 1: F_B = 8B δ / (R h_r) with the plate bending stiffness B = E h³ / (12(1−ν²))
    (Eq. 2). The printed Eq. 3, h_r = h √(12/(1−ν²)), is a transcription error: Reissner's
    characteristic length of the shell is ℓ² = R h / √(12(1−ν²)) = R h_r, so

        h_r = h / √(12(1−ν²))                                   (Eq. 3, corrected)

    and F_B / δ = 8B / (R h_r) = 4 E h² / (R √(3(1−ν²))).

    Args:
        ball: the :class:`~rbjax.terms.ball.Ball` (its ``youngs_Pa``, ``wall_m``, ``radius_m``
            and ``poisson``; array fields broadcast).

    Returns:
        The stiffness k = F_B/δ of the shell (N/m), with the broadcast shape of the ball's fields
        (a ball that carries it already, ``known_stiffness_N_per_m``, gives that: see
        :class:`rbjax.solve.record_samples.StiffnessKnown`).
    """
    known = getattr(ball, "known_stiffness_N_per_m", None)
    if known is not None:
        return known
    e, h, r, nu = ball.youngs_Pa, ball.wall_m, ball.radius_m, ball.poisson
    bending = e * h**3 / (12.0 * (1.0 - nu**2))
    reduced_wall = h / jnp.sqrt(12.0 * (1.0 - nu**2))
    return 8.0 * bending / (r * reduced_wall)


def cap_volume_m3(deflection_m, radius_m):
    """Volume πδ²(3R−δ)/3 of the spherical cap of height δ that the flat floor cuts off."""
    d = deflection_m
    return jnp.pi * d**2 * (3.0 * radius_m - d) / 3.0


def contact_area_m2(deflection_m, radius_m):
    """Area πa² = πδ(2R−δ) of the flattened cap (a: the cap's base radius).

    Args:
        deflection_m: deflection δ of the shell (m), measured from first contact.
        radius_m: outer radius R of the ball (m).

    Returns:
        The contact area (m²), with the broadcast shape of the arguments.
    """
    d = deflection_m
    return jnp.pi * d * (2.0 * radius_m - d)


def gas_force_N(deflection_m, ball, *, ambient_Pa=AMBIENT_PRESSURE_Pa, gamma=GAMMA_AIR):
    """Force of the air squeezed adiabatically in the cavity (paper Eq. 4, corrected).

    The cavity of volume V0 = 4πR³/3 loses the cap volume, V = V0 − πδ²(3R−δ)/3, so
    V/V0 = 1 − (3 − δ/R)(δ/(2R))². Adiabatic compression from p_0 = p_a (vented ball, p_g = 0)
    gives the over-pressure p_a((V0/V)^γ − 1), acting on the contact area πRδ(2 − δ/R):

        F_G = p_a πR (2 − δ/R) δ [ (1 − (3 − δ/R)(δ/2R)²)^(−γ) − 1 ]     (Eq. 4, corrected)

    The printed Eq. 4 has (2δ/R)² for (δ/2R)² and the exponent +γ for −γ (which would make
    the cavity pull the ball into the floor). V0 uses the outer radius R as in Hubbard's
    thin-shell model; for the thick rubber wall the real cavity is smaller, so this
    underestimates the (already secondary) gas force.

    Args:
        deflection_m: deflection δ of the shell (m), measured from first contact.
        ball: the :class:`~rbjax.terms.ball.Ball` (its ``radius_m`` is R).
        ambient_Pa: ambient pressure p_a (Pa), the cavity's pressure before contact (default
            ``AMBIENT_PRESSURE_Pa``, 101 325 Pa).
        gamma: ratio of specific heats γ of the gas (default ``GAMMA_AIR``, 1.4).

    Returns:
        The gas force F_G (N) on the floor, with the broadcast shape of δ and the ball's fields.
    """
    r = ball.radius_m
    d = deflection_m
    volume_ratio = 1.0 - (3.0 - d / r) * (d / (2.0 * r)) ** 2
    overpressure = ambient_Pa * (_power(volume_ratio, -gamma) - 1.0)
    return overpressure * contact_area_m2(d, r)


@functools.partial(jax.custom_jvp, nondiff_argnums=(1,))
def _power(x, a: float):
    """x**a (constant a) whose derivative reuses the value, a·x^a/x: JAX's own rule evaluates
    x^(a − 1), a second pow, in every tangent (forward-mode Jacobians, the ODE's adjoint)."""
    return x**a


@_power.defjvp
def _power_jvp(a, primals, tangents):
    (x,), (dx,) = primals, tangents
    y = x**a
    return y, a * y / x * dx


def cap_mass_rate_kg_per_m(ball, model=None):
    """dM_c/dδ, the mass the flattened cap gains per unit deflection: the paper's thin-shell
    M/2R (Eq. 6), or the wall column of the model's arrest law (``model.arrest``,
    :meth:`rbjax.terms.arrest.AbstractArrest.mass_rate_kg_per_m`), so that the mass the moving
    part loses is the mass whose flux the arrest law puts on the floor."""
    arrest = getattr(model, "arrest", None)
    if arrest is not None:
        return arrest.mass_rate_kg_per_m(ball)
    return ball.mass_kg / (2.0 * ball.radius_m)


def dynamic_mass_kg(deflection_m, ball, model=None):
    """Mass M − M_c of the moving part, M_c = (dM_c/dδ) δ the flattened cap at rest (Eq. 6:
    Mδ/(2R); :func:`cap_mass_rate_kg_per_m`)."""
    if getattr(model, "arrest", None) is None:
        return ball.mass_kg * (1.0 - deflection_m / (2.0 * ball.radius_m))
    return ball.mass_kg - cap_mass_rate_kg_per_m(ball, model) * deflection_m


def momentum_flux_N(velocity_m_per_s, ball, model=None):
    """Rate (dM_c/dδ) δ̇² at which momentum is carried by mass joining or leaving the cap (Eq. 7:
    (M/2R)δ̇²; :func:`cap_mass_rate_kg_per_m`)."""
    return cap_mass_rate_kg_per_m(ball, model) * velocity_m_per_s**2


def singular_deflection_m(ball, model=None):
    """The deflection at which the dynamic mass vanishes: 2R for the paper's, M / (dM_c/dδ)
    with an arrest law's column."""
    if getattr(model, "arrest", None) is None:
        return 2.0 * ball.radius_m
    return ball.mass_kg / cap_mass_rate_kg_per_m(ball, model)


# ----------------------------------------------------------------------------------------------
# Stiffening: a pytree of its parameter (damping laws: ``rbjax.terms.damping``).


class CubicStiffening(eqx.Module):
    """Hardening of the shell at large deflection: F_B = kδ (1 + β (δ/h)²).

    Attributes:
        beta: dimensionless coefficient β ≥ 0 (0: Reissner's linear shell).

    Raises:
        ValueError: ``beta`` outside its valid range or not finite (concrete values only).
    """

    beta: ArrayLike
    PARAMETERS: ClassVar = {
        "beta": Parameter("1", **NON_NEGATIVE, description="cubic stiffening β in kδ(1 + β(δ/h)²)")
    }

    def __check_init__(self):
        check_declared(self)


def shell_force_N(deflection_m, ball, stiffening=None):
    """F_B = kδ (Eq. 1 with the corrected Eq. 3), times (1 + β(δ/h)²) with stiffening.

    Args:
        deflection_m: deflection δ of the shell (m), measured from first contact.
        ball: the :class:`~rbjax.terms.ball.Ball` (k from :func:`reissner_stiffness_N_per_m`,
            h its ``wall_m``).
        stiffening: ``None`` (Reissner's linear shell) or a :class:`CubicStiffening` (its β).

    Returns:
        The shell force F_B (N), with the broadcast shape of δ and the ball's fields.
    """
    force = reissner_stiffness_N_per_m(ball) * deflection_m
    if stiffening is not None:
        force = force * (1.0 + stiffening.beta * (deflection_m / ball.wall_m) ** 2)
    return force


def contact_force_N(deflection_m, velocity_m_per_s, internal, ball, model):
    """Force between shell and floor, F_B + F_G + F_d (the right-hand side of Eq. 7; F_B + F_G
    through the contact layer where the model has one).

    ``internal`` holds the internal states of the model's damping terms, in their order.
    """
    return elastic_force_N(deflection_m, ball, model) + damping_force_N(
        deflection_m, velocity_m_per_s, internal, ball, model
    )


def elastic_force_N(deflection_m, ball, model):
    """F_B + F_G of the deflection alone; with a contact layer in series with the shell
    (``model.layer``, :mod:`rbjax.terms.contact_layer`), the force of the pair pressed by δ."""

    def shell_and_gas(d):
        force = shell_force_N(d, ball, model.stiffening)
        if model.gas == "adiabatic":
            force = force + gas_force_N(d, ball)
        return force

    if model.layer is None:
        return shell_and_gas(deflection_m)
    return model.layer.series_force_N(deflection_m, shell_and_gas)


def damping_force_N(deflection_m, velocity_m_per_s, internal, ball, model):
    """F_d, the sum of the model's damping laws' forces (0 without any)."""
    force = jnp.zeros_like(deflection_m)
    for term, z in zip(model.damping, model.split_internal(internal)):
        force = force + term.force_N(deflection_m, velocity_m_per_s, z, ball)
    return force


def internal_rates(deflection_m, velocity_m_per_s, internal, ball, model):
    """Time derivatives of the internal states of the model's damping terms (concatenated)."""
    rates = [
        term.internal_rates(deflection_m, velocity_m_per_s, z, ball)
        for term, z in zip(model.damping, model.split_internal(internal))
    ]
    return jnp.concatenate([jnp.zeros(0), *rates])

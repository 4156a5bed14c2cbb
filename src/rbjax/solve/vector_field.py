"""The equations of motion as a vector field dy/dt (paper Eq. 7 and the terms that couple to
it: damping states, the elements in series with the shell, a moving floor), the state at first
contact and the forces read from a state. The phases, events and outputs of a solve are
:mod:`rbjax.solve.ode`; the fixed-step paths (:mod:`~rbjax.solve.sampled`,
:mod:`~rbjax.solve.record_samples`) step the same field.

State y = (δ, δ̇[, internal states]) from first contact, δ(0) = 0, δ̇(0) = √(2 g h_D) (Eq. 10)
less what a massless floor or a massless element in series take at once.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..terms.forces import (
    cap_mass_rate_kg_per_m,
    contact_force_N,
    damping_force_N,
    dynamic_mass_kg,
    internal_rates,
    momentum_flux_N,
)
from ..terms.model import Model


def _split(y):
    return y[0], y[1], y[2:]


def contact_force(y, ball, model):
    d, v, z = _split(y)
    return contact_force_N(d, v, z, ball, model)


def floor_force_N(y, ball, model):
    """The force on the floor for state y: the contact force plus the arrested momentum's flux
    during compression (``floor_flux_N``; the blocked force on the rigid floor)."""
    return contact_force(y, ball, model) + floor_flux_N(y[1], ball, model)


def floor_flux_N(v, ball, model):
    """The arrested momentum's flux the floor receives during compression (δ̇ > 0): the model's
    arrest law (``model.arrest``, :mod:`rbjax.terms.arrest`), or the share
    ``model.momentum_flux_weight`` of the paper's (M/2R)δ̇²."""
    if model.arrest is not None:
        return model.arrest.flux_N(v, ball)
    return model.momentum_flux_weight * jnp.where(v > 0.0, momentum_flux_N(v, ball, model), 0.0)


def floor_velocity_m_per_s(y, ball, model):
    """u̇, the velocity of the floor's surface under the ball (0 on the rigid floor)."""
    if model.floor.rigid:
        return jnp.zeros_like(y[1])
    return model.floor.velocity_m_per_s(model.floor_states(y[2:]), floor_force_N(y, ball, model))


def body_velocity_m_per_s(y, ball, model):
    """Ẋ = δ̇ + u̇ − Σẇ, the velocity of the ball's moving part (δ̇ on the rigid floor without
    elements in series)."""
    v = y[1] + floor_velocity_m_per_s(y, ball, model)
    for w_rate in _element_velocities(y, ball, model):
        v = v - w_rate
    return v


def _element_velocities(y, ball, model) -> list:
    """ẇ of each element in series with the shell (``rbjax.terms.series_element``)."""
    if not model.series_elements:
        return []
    force = contact_force(y, ball, model)
    states = model.element_states(y[2:])
    return [e.velocity_m_per_s(z, force) for e, z in zip(model.series_elements, states)]


def _vector_field(flux_on: bool, energy: bool = False):
    """dy/dt. The ball's moving part, mass M − M_c (Eq. 6), feels the contact force F_c and,
    while mass leaves the cap (δ̇ < 0, restitution), the thrust (M/2R)δ̇² (Eq. 7):

        (M − M_c) Ẍ = −F_c + (M/2R) δ̇² H(−δ̇),      δ = X + w − u,  δ̈ = Ẍ + ẅ − ü,

    (M/2R, M_c = (M/2R)δ: the column μ and μδ where the model has an arrest law,
    ``rbjax.terms.forces.cap_mass_rate_kg_per_m``)

    with w the displacement the elements in series with the shell add and u the floor's surface
    (``rbjax.terms.floors.kinds``); on the rigid floor without elements in series δ̈ = Ẍ,
    Eq. 7. Each element in series with the shell (``rbjax.terms.series_element``) adds its
    ẅ: an inertial one (the ball mode) from its states; a massless one (the series element,
    τẇ = −(w + C F_c), ``rbjax.terms.series_kelvin_voigt``) as ẅ = c − a dF_c/dt, linear in
    δ̈; a massless floor (u̇ = F/Z) has ü = (dF/dt)/Z with dF/dt = ∂F/∂y·ẏ, linear in δ̈ too;
    both are solved for δ̈ in closed form. With ``energy`` four accumulators follow the state
    (see ``energy_balance``).
    """

    def rhs(t, y, args):
        ball, model = args
        d, v, z = _split(y)
        parts = [internal_rates(d, v, z, ball, model)]
        elements = tuple(zip(model.series_elements, model.element_states(z)))
        if not any(e.massless for e, _ in elements):
            force = contact_force(y, ball, model)
        else:
            # F_c and G = ∂F_c/∂δ δ̇ + ∂F_c/∂z ż in one forward pass, H = ∂F_c/∂δ̇ (the damping
            # laws only) in another: a massless element's dF_c/dt = G + H δ̈
            zd = z[: model.num_damping_states]
            force, g_c = jax.jvp(
                lambda dd, zz: contact_force_N(dd, v, zz, ball, model), (d, zd), (v, parts[0])
            )
            h_c = jax.jvp(
                lambda vv: damping_force_N(d, vv, zd, ball, model), (v,), (jnp.ones_like(v),)
            )[1]
        thrust = jnp.where(v < 0.0, momentum_flux_N(v, ball, model), 0.0) if flux_on else 0.0
        accel = (thrust - force) / dynamic_mass_kg(d, ball, model)
        # Massless elements make δ̈ appear on both sides: each adds −a(G + H δ̈) (+ c) to δ̈,
        # with dF/dt = G + H δ̈ of the force it carries (F depends on δ, δ̇ and the damping
        # states only); δ̈ (1 + Σ a H) = Ẍ + … − Σ a G is solved in closed form.
        denominator = 1.0
        for element, states in elements:
            rates = element.rates(states, force, ball)
            parts.append(rates)
            accel = accel + element.acceleration_m_per_s2(states, rates)
            if element.massless:
                a = element.force_rate_weight()
                accel = accel - a * g_c
                denominator = denominator + a * h_c
        floor = model.floor
        if not floor.rigid:
            states = model.floor_states(z)
            ff = floor_force_N(y, ball, model)
            parts.append(floor.rates(states, ff))
            accel = accel - floor.acceleration_m_per_s2(states, ff)
            if floor.massless:
                nd = model.num_damping_states
                ydot = jnp.concatenate(
                    [jnp.stack([v, jnp.zeros_like(v)]), parts[0], jnp.zeros(y.shape[0] - 2 - nd)]
                )
                force_of = lambda yy: floor_force_N(yy, ball, model)  # noqa: E731
                _, g = jax.jvp(force_of, (y,), (ydot,))
                _, h = jax.jvp(force_of, (y,), (jnp.zeros_like(y).at[1].set(1.0),))
                b = floor.admittance_m_per_Ns
                accel = accel - b * g
                denominator = denominator + b * h
        accel = accel / denominator
        rates = jnp.concatenate([jnp.stack([v, accel]), *parts])
        if energy:
            rates = jnp.concatenate([rates, _energy_rates(y, ball, model)])
        return rates

    return rhs


#: Energy accumulators (``energy_balance``): floor work ∫F u̇ dt, flux loss ∫½(M/2R)|δ̇|³ dt,
#: contact work ∫F_c δ̇ dt, and the work the quasi-static cap and the flux the floor does not
#: receive leave out, ∫[½(M/2R)δ̇ u̇² + ((M/2R)δ̇² H(δ̇) − F_flux) u̇] dt (F_flux:
#: ``floor_flux_N``, the share w of the flux or the arrest law's).
NUM_ENERGY_STATES = 4


def _energy_rates(y, ball, model):
    _, v, _ = _split(y)
    ff = floor_force_N(y, ball, model)
    u_dot = floor_velocity_m_per_s(y, ball, model)
    per_speed = cap_mass_rate_kg_per_m(ball, model)
    flux = per_speed * v**2  # momentum_flux_N
    cap = 0.5 * per_speed * v * u_dot**2 + _flux_left_out(v, flux, ball, model) * u_dot
    return jnp.stack(
        [ff * u_dot, 0.5 * per_speed * jnp.abs(v) ** 3, contact_force(y, ball, model) * v, cap]
    )


def _flux_left_out(v, flux, ball, model):
    """The part of the flux (M/2R)δ̇² H(δ̇) the floor does not receive."""
    if model.arrest is None:
        return (1.0 - model.momentum_flux_weight) * jnp.where(v > 0.0, flux, 0.0)
    return jnp.where(v > 0.0, flux, 0.0) - floor_flux_N(v, ball, model)


def split_energy(y, model):
    """The state without the energy accumulators, and the accumulators."""
    n = 2 + model.num_internal_states
    return y[:n], y[n:]


COMPRESSION_FIELD = _vector_field(flux_on=False)
RESTITUTION_FIELD = _vector_field(flux_on=True)
COMPRESSION_ENERGY_FIELD = _vector_field(flux_on=False, energy=True)
RESTITUTION_ENERGY_FIELD = _vector_field(flux_on=True, energy=True)


def initial_state(v0, ball, model: Model, energy: bool = False):
    """y at first contact: δ = 0, internal states at their start (0, or an element's
    ``initial_states``), δ̇ = v0 − u̇(0) + ẇ(0). On a massless floor u̇(0) = F(0, δ̇)/Z (the
    momentum flux, a damper's δ̇ term), and a massless element in series has ẇ(0) set by the
    force (the series element's −C F_c(0, δ̇)/τ): δ̇ + F(0, δ̇)/Z + F_c(0, δ̇)/c_b = v0 is solved
    by Newton's method (exact in one step where the forces are affine in δ̇)."""
    internal = model.initial_internal_states()
    zeros = jnp.zeros(NUM_ENERGY_STATES if energy else 0)
    y0 = jnp.concatenate([jnp.stack([jnp.zeros_like(v0), v0]), internal, zeros])
    jumps = model.floor.massless or any(e.massless for e in model.series_elements)
    if not jumps:
        return y0

    def residual(v):
        y = y0.at[1].set(v)
        r = v - v0
        if model.floor.massless:
            r = r + model.floor.admittance_m_per_Ns * floor_force_N(y, ball, model)
        for w_rate in _element_velocities(y, ball, model):
            r = r - w_rate
        return r

    v = v0
    for _ in range(8):
        r, dr = jax.jvp(residual, (v,), (jnp.ones_like(v),))
        v = v - r / dr
    return y0.at[1].set(v)

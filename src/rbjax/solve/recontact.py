"""Whether the free motion after the end of contact brings the shell back onto the floor (a
second contact, which the model does not follow within one record: the impact is flagged
``recontact``), and over how long that motion is followed."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..terms.floors.kinds import AbstractModalFloor
from ..terms.model import Model
from ..terms.series_element import free_oscillation
from .vector_field import body_velocity_m_per_s


def recontact_horizon_s(model: Model):
    """How long after separation ``recontacts`` follows the free motion: two periods of the
    slowest floor mode, each element in series with the shell's own horizon (two periods of
    the ball mode, two relaxation times of the series element), at least 10 ms."""
    floor = model.floor
    horizon: jax.Array | float = 0.01
    if isinstance(floor, AbstractModalFloor):
        omega = floor.modes()[1]
        periods = jnp.where(omega > 0.0, 4.0 * jnp.pi / jnp.where(omega > 0.0, omega, 1.0), 0.0)
        horizon = jnp.maximum(jnp.max(periods), horizon)
    for element in model.series_elements:
        horizon = jnp.maximum(horizon, element.recontact_horizon_s())
    return horizon


def recontacts(y_end, args):
    """True if, after separation, the free motion brings the shell back onto the floor.

    After the end of contact the ball's moving part flies off at Ẋ (gravity is neglected over
    the short horizon), the elements in series move freely (``free_change_m``: the ball mode
    rings, the series element relaxes) and a modal floor rings (a massless floor stops).
    The gap closes again where δ(τ) = δ_end + Ẋτ + Δw(τ) − Δu(τ) > δ_end, checked on 256 times
    over ``recontact_horizon_s``. The model does not follow a second contact within one
    record: such an impact is flagged ``recontact``.
    """
    ball, model = args
    taus = jnp.linspace(0.0, recontact_horizon_s(model), 257)[1:]
    z = y_end[2:]
    gap_close = body_velocity_m_per_s(y_end, ball, model) * taus
    for element, states in zip(model.series_elements, model.element_states(z)):
        gap_close = gap_close + element.free_change_m(states, taus)
    if isinstance(model.floor, AbstractModalFloor):
        s = model.floor_states(z)
        n = model.floor.num_modes
        q, qd = s[:n], s[n:]
        _, omega, eta = model.floor.modes()
        free = free_oscillation(q, qd, omega, eta, taus[:, None])  # (times, modes)
        gap_close = gap_close - jnp.sum(free - q, axis=1)
    scale = 1e-9 * ball.wall_m
    return jnp.any(gap_close > scale)

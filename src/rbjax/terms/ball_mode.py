"""The ball's own vibration during contact: one mode of the ball in series with the shell.

The paper's open problem (§4.1, §4.2, §5): measured force pulses ring with a period much
shorter than the contact, and the elastic model underestimates L_FE above 125 Hz, because
the ball itself vibrates while it is pressed. ``BallMode`` adds one degree of freedom: the
region of the ball behind the flattened cap moves relative to the ball's centre of mass by
w (downward positive) as one mode of the ball, driven by the contact force F_c that pushes it
back:

    m_b (ẅ + η ω ẇ + ω² w) = −F_c,      m_b = M/μ,

so the shell is pressed by δ = X + w − u (X: the ball's rigid motion, u: the floor's
surface). The same equations describe the axisymmetric mode of the shell that the contact
drives (its modal mass at the contact point m_b and frequency f = ω/2π, see
``rbjax.terms.shell_modes``) and a light contact zone with its own mass and local stiffness (a
two-degree-of-freedom contact). μ = M/m_b = 0 switches the term off exactly (w ≡ 0); a very
stiff mode (ω → ∞) recovers the model without it.
"""

from __future__ import annotations

import math
from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import ArrayLike

from .declare import NON_NEGATIVE, POSITIVE, Parameter
from .series_element import AbstractSeriesElement, free_oscillation


class BallMode(AbstractSeriesElement):
    """One mode of the ball in series with the shell (see the module docstring): an inertial
    element, states (w, ẇ).

    Attributes:
        mode_mass_ratio: μ = M/m_b ≥ 0, the ball's mass over the mode's mass at the contact
            point (0: off; large: a light contact zone).
        mode_frequency_Hz: f = ω/2π > 0 of the mode on its own.
        mode_loss_factor: η ≥ 0 (viscous at resonance: damping η ω m_b).

    Raises:
        ValueError: a field outside its valid range or not finite, named in the message
            (concrete values only).
    """

    mode_mass_ratio: ArrayLike
    mode_frequency_Hz: ArrayLike
    mode_loss_factor: ArrayLike
    name: ClassVar[str] = "ball-mode"
    num_states: ClassVar[int] = 2
    state_names: ClassVar[tuple[str, ...]] = ("w", "w_dot")
    label: ClassVar[str] = "the ball mode"
    file_key: ClassVar[str] = "ball_mode"
    PARAMETERS: ClassVar = {
        "mode_mass_ratio": Parameter(
            "1",
            **NON_NEGATIVE,
            description="μ = M/m_b, the ball's mass over the mode's mass at the contact",
        ),
        "mode_frequency_Hz": Parameter(
            "Hz", **POSITIVE, description="natural frequency f of the ball's mode"
        ),
        "mode_loss_factor": Parameter(
            "1", **NON_NEGATIVE, description="loss factor η of the ball's mode"
        ),
    }

    def rates(self, states, contact_force_N, ball):
        """(ẇ, ẅ) of the mode's displacement at the contact, driven by −F_c."""
        w, wd = states[0], states[1]
        omega = 2.0 * jnp.pi * self.mode_frequency_Hz
        wdd = (
            -(jnp.asarray(self.mode_mass_ratio) * contact_force_N) / ball.mass_kg
            - self.mode_loss_factor * omega * wd
            - omega**2 * w
        )
        return jnp.stack([wd, wdd])

    def velocity_m_per_s(self, states, contact_force_N):
        """ẇ, a state."""
        return states[1]

    def acceleration_m_per_s2(self, states, rates):
        """ẅ, the rate of the state ẇ."""
        return rates[1]

    def recontact_horizon_s(self):
        """Two periods of the mode."""
        return 2.0 / self.mode_frequency_Hz

    def free_change_m(self, states, times_s):
        """The mode rings freely from (w, ẇ): w(τ) − w."""
        w, wd = states[0], states[1]
        omega = 2.0 * jnp.pi * self.mode_frequency_Hz
        return free_oscillation(w, wd, omega, self.mode_loss_factor, times_s) - w

    @classmethod
    def off(cls) -> BallMode:
        """μ = 0: the mode is not driven and stays at rest (frequency and loss then do nothing)."""
        return cls(0.0, 500.0, 0.1)

    #: Other start values a fit tries beside ``start``'s (in the same compiled program): the fit
    #: of f has several minima (one per mode of the pulse's ringing it can lock onto).
    START_ALTERNATIVES: ClassVar = {"mode_frequency_Hz": (300.0, 1200.0)}

    @classmethod
    def start(
        cls,
        stiffness_N_per_m: float,
        mass_kg: float,
        restitution: float,
        contact_time_s: float,
        speed_m_per_s: float,
    ) -> dict:
        """Start values for fitting: a light contact zone (μ = 20) ringing near 600 Hz, η = 0.2."""
        return {"mode_mass_ratio": 20.0, "mode_frequency_Hz": 600.0, "mode_loss_factor": 0.2}


def from_modal_mass(mass_kg: float, frequency_Hz: float, loss_factor: float, ball) -> BallMode:
    """A ``BallMode`` from the mode's mass at the contact point (kg) instead of μ = M/m_b."""
    if not mass_kg > 0.0 or not math.isfinite(mass_kg):
        raise ValueError(
            f"mass_kg={mass_kg!r} is outside the valid range (0, inf): a mode needs a positive mass"
        )
    return BallMode(float(ball.mass_kg) / mass_kg, frequency_Hz, loss_factor)

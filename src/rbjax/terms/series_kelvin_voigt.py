"""A massless spring and damper in series with the shell: the ball mode's overdamped limit.

Fits of ``rbjax.BallMode`` to the bundled recordings run towards a limit: at loss factors
η = 4 and 5.9 the fitted mode has nearly the same stiffness k_b = m_b ω² (330–345 kN/m)
and damping c_b = η ω m_b (1.5–1.7 kN s/m) while its mass m_b falls 0.53 → 0.21 kg.
The mode's equation m_b (ẅ + η ω ẇ + ω² w) = −F_c then tends, as m_b → 0 at fixed k_b and
c_b, to

    c_b ẇ + k_b w = −F_c,          δ = X + w,

a massless Kelvin–Voigt element between the ball's moving body (X) and the shell pressed by
δ, carrying the contact force F_c. Written with the element's compliance C = 1/k_b and time
constant τ = c_b/k_b (the parameters here):

    τ ẇ = −(w + C F_c(δ, δ̇, …)).

With δ̇ a state of the ODE, ẇ is explicit; δ̈ = Ẍ + ẅ, with ẅ = −(ẇ + C Ḟ_c)/τ and Ḟ_c
linear in δ̈, is solved for δ̈ in closed form (``rbjax.solve.ode``), as for a massless floor.
At first contact w = 0 and δ̇ solves δ̇ + F_c(0, δ̇)/c_b = v0 (a damper's jump).

C = 0 switches the term off exactly (w ≡ 0). Two parameters instead of the ball mode's three,
and no mass whose fit can run to zero: in the limit above the ball mode's (μ, f, η) are
singular (f and η correlated +1), these are not.
"""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp
from jaxtyping import ArrayLike

from .declare import NON_NEGATIVE, POSITIVE, Parameter
from .series_element import AbstractSeriesElement


class SeriesKelvinVoigt(AbstractSeriesElement):
    """A massless spring and damper in series with the shell (see the module docstring): a
    massless element, state (w,).

    Attributes:
        series_compliance_m_per_N: C = 1/k_b ≥ 0 of the element's spring (0: off).
        series_time_constant_s: τ = c_b/k_b > 0, the element's relaxation time.

    Raises:
        ValueError: a field outside its valid range or not finite, named in the message
            (concrete values only).
    """

    series_compliance_m_per_N: ArrayLike
    series_time_constant_s: ArrayLike
    name: ClassVar[str] = "series-kelvin-voigt"
    num_states: ClassVar[int] = 1
    state_names: ClassVar[tuple[str, ...]] = ("w",)
    massless: ClassVar[bool] = True
    label: ClassVar[str] = "the series element"
    file_key: ClassVar[str] = "series"
    PARAMETERS: ClassVar = {
        "series_compliance_m_per_N": Parameter(
            "m/N",
            **NON_NEGATIVE,
            description=(
                "C = 1/k_b, compliance of the spring in series with the shell (τẇ = −(w + C F_c))"
            ),
        ),
        "series_time_constant_s": Parameter(
            "s",
            **POSITIVE,
            description="τ = c_b/k_b, relaxation time of the element in series with the shell",
        ),
    }

    @property
    def stiffness_N_per_m(self):
        """k_b = 1/C (infinite when the term is off)."""
        return 1.0 / jnp.asarray(self.series_compliance_m_per_N)

    @property
    def damping_Ns_per_m(self):
        """c_b = τ/C (infinite when the term is off)."""
        return jnp.asarray(self.series_time_constant_s) / jnp.asarray(
            self.series_compliance_m_per_N
        )

    def velocity_m_per_s(self, states, contact_force_N):
        """ẇ = −(w + C F_c)/τ."""
        w = states[0]
        return -(w + self.series_compliance_m_per_N * contact_force_N) / self.series_time_constant_s

    def rates(self, states, contact_force_N, ball):
        """(ẇ,)."""
        return self.velocity_m_per_s(states, contact_force_N)[None]

    def acceleration_m_per_s2(self, states, rates):
        """ẅ = −(ẇ + C dF_c/dt)/τ less its dF_c/dt term: −ẇ/τ."""
        return -(rates[0] / self.series_time_constant_s)

    def force_rate_weight(self):
        """a = C/τ."""
        return self.series_compliance_m_per_N / self.series_time_constant_s

    def recontact_horizon_s(self):
        """Two relaxation times."""
        return 2.0 * self.series_time_constant_s

    def free_change_m(self, states, times_s):
        """It relaxes freely, τẇ = −w: w(τ) − w = w (e^(−τ/τ_s) − 1)."""
        return states[0] * jnp.expm1(-times_s / self.series_time_constant_s)

    @classmethod
    def off(cls) -> SeriesKelvinVoigt:
        """C = 0: the element is rigid and w stays 0 (τ then does nothing)."""
        return cls(0.0, 1e-3)

    @classmethod
    def start(
        cls,
        stiffness_N_per_m: float,
        mass_kg: float,
        restitution: float,
        contact_time_s: float,
        speed_m_per_s: float,
    ) -> dict:
        """Start values for fitting: a spring five times stiffer than the shell's, relaxing in a
        quarter of the contact (k_b ≈ 5 k, c_b ≈ 5 k t_c/4: near what fits of the ball mode
        reach in their overdamped limit)."""
        return {
            "series_compliance_m_per_N": 0.2 / stiffness_N_per_m,
            "series_time_constant_s": 0.25 * contact_time_s,
        }

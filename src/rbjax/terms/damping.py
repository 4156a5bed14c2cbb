"""Damping laws: one abstract module, one subclass per law (a new law is one class).

A damping law adds a force F_d to the contact force (Eq. 7's right-hand side and the floor
force) and may carry internal states with their own rates, the way diffrax's solvers
subclass ``AbstractSolver``. The solver knows a law only through :class:`AbstractDamping`:
``force_N`` and ``internal_rates``. Each law declares its parameters in ``PARAMETERS``
(name with unit, bounds, fitting transform; see :mod:`rbjax.terms.parameters`) and a ``start``
rule for fitting. Subclasses register themselves by ``name`` (for parameter files and the
fit's model names).
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import ArrayLike

from .declare import NON_NEGATIVE, POSITIVE, Parameter, check_declared
from .forces import reissner_stiffness_N_per_m

#: name → class of every damping law defined (filled by subclassing).
DAMPING_MODELS: dict[str, type[AbstractDamping]] = {}


class AbstractDamping(eqx.Module):
    """A damping term: F_d(δ, δ̇, z) on the floor and dz/dt for its ``num_states`` states z.

    Subclasses set the class attributes ``name`` (unique), ``num_states`` and
    ``PARAMETERS``, and implement :meth:`force_N` (and :meth:`internal_rates` if they have
    states). Every state starts at 0 at first contact.
    """

    name: ClassVar[str] = ""
    num_states: ClassVar[int] = 0
    PARAMETERS: ClassVar[dict[str, Parameter]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.name and not getattr(cls, "__abstractmethods__", None):
            DAMPING_MODELS[cls.name] = cls

    def __check_init__(self):
        check_declared(self)

    @abc.abstractmethod
    def force_N(self, deflection_m, velocity_m_per_s, internal, ball):
        """The damping force F_d on the floor (N)."""

    def internal_rates(self, deflection_m, velocity_m_per_s, internal, ball):
        """dz/dt of the internal states (shape ``(num_states,)``)."""
        return jnp.zeros(0)

    @classmethod
    def start(
        cls,
        stiffness_N_per_m: float,
        mass_kg: float,
        restitution: float,
        contact_time_s: float,
        speed_m_per_s: float,
    ) -> dict:
        """Start values for fitting from a linear spring k, the mass, and the measured
        restitution, contact time and impact speed (a damped linear oscillator)."""
        return {}

    @classmethod
    def off(cls) -> AbstractDamping:
        """The law with parameters that make its force vanish (for a shared structure):
        by default every parameter at its lower bound 0; a law for which that is not "off"
        (or not allowed) overrides this."""
        specs = cls.PARAMETERS
        if not all(s.lower == 0.0 and not s.lower_open for s in specs.values()):
            raise NotImplementedError(
                f"{cls.__name__} must define off(): not every parameter may be 0"
            )
        return cls(**{name: 0.0 for name in specs})


def damping_ratio(restitution: float) -> float:
    """ζ of a linear oscillator whose half-period rebound has coefficient e:
    e = exp(−πζ/√(1−ζ²))."""
    return -math.log(restitution) / math.sqrt(math.pi**2 + math.log(restitution) ** 2)


class KelvinVoigt(AbstractDamping):
    """Viscous damping in parallel with the shell: F_d = c δ̇ (model name ``kelvin-voigt``).

    Attributes:
        damping_Ns_per_m: c ≥ 0 (N·s/m).

    Raises:
        ValueError: ``damping_Ns_per_m`` outside its valid range or not finite (concrete
            values only).
    """

    damping_Ns_per_m: ArrayLike
    name = "kelvin-voigt"
    PARAMETERS = {
        "damping_Ns_per_m": Parameter(
            "N s/m", **NON_NEGATIVE, description="viscous coefficient c in F_d = cδ̇"
        )
    }

    def force_N(self, deflection_m, velocity_m_per_s, internal, ball):
        return self.damping_Ns_per_m * velocity_m_per_s

    @classmethod
    def start(cls, stiffness_N_per_m, mass_kg, restitution, contact_time_s, speed_m_per_s):
        return {
            "damping_Ns_per_m": 2
            * damping_ratio(restitution)
            * math.sqrt(stiffness_N_per_m * mass_kg)
        }


class HuntCrossley(AbstractDamping):
    """Hunt–Crossley damping F_d = α k δ (δ/h)^(n−1) δ̇, zero at first contact (``hunt-crossley``).

    With n = 1 it is α·F_B·δ̇: damping grows with the deflection, so the pulse rises fast and
    falls slowly, and no force jump appears at first contact.

    Attributes:
        alpha_s_per_m: α ≥ 0 (s/m).
        exponent: n ≥ 1 (static).

    Raises:
        ValueError: ``alpha_s_per_m`` outside its valid range or not finite (concrete values
            only), or ``exponent`` < 1.
    """

    alpha_s_per_m: ArrayLike
    exponent: float = eqx.field(static=True, default=1.0)
    name = "hunt-crossley"
    PARAMETERS = {
        "alpha_s_per_m": Parameter(
            "s/m", **NON_NEGATIVE, description="Hunt–Crossley α in F_d = αkδ(δ/h)^(n−1)δ̇"
        )
    }

    def __check_init__(self):
        check_declared(self)
        if not self.exponent >= 1.0:
            raise ValueError(f"exponent={self.exponent!r} is outside the valid range [1, inf)")

    def force_N(self, deflection_m, velocity_m_per_s, internal, ball):
        k = reissner_stiffness_N_per_m(ball)
        shape = deflection_m
        if self.exponent != 1.0:  # static; a safe power keeps derivatives finite at δ = 0
            ratio = jnp.maximum(deflection_m, 1e-300) / ball.wall_m
            shape = shape * jnp.where(deflection_m > 0.0, ratio ** (self.exponent - 1.0), 0.0)
        return self.alpha_s_per_m * k * shape * velocity_m_per_s

    @classmethod
    def start(cls, stiffness_N_per_m, mass_kg, restitution, contact_time_s, speed_m_per_s):
        # Hunt & Crossley's small-loss estimate α ≈ 3(1 − e)/(2 v0)
        return {"alpha_s_per_m": 3 * (1 - restitution) / (2 * speed_m_per_s)}


class Zener(AbstractDamping):
    """Standard linear solid: a Maxwell branch (spring k₁ = r·k, dashpot k₁τ) beside the shell.

    The branch force F_M is an internal state, dF_M/dt = k₁ δ̇ − F_M/τ, F_M(0) = 0, so fast
    impacts see the stiffer instantaneous spring (1 + r)k and the branch dissipates energy.
    Model name ``zener``.

    Attributes:
        stiffness_ratio: r = k₁/k ≥ 0.
        relaxation_time_s: τ > 0 (s).

    Raises:
        ValueError: a field outside its valid range or not finite, named in the message
            (concrete values only).
    """

    stiffness_ratio: ArrayLike
    relaxation_time_s: ArrayLike
    name = "zener"
    num_states = 1
    PARAMETERS = {
        "stiffness_ratio": Parameter(
            "1", **NON_NEGATIVE, description="Maxwell branch stiffness k₁/k"
        ),
        "relaxation_time_s": Parameter(
            "s", **POSITIVE, description="Maxwell branch relaxation time τ"
        ),
    }

    def force_N(self, deflection_m, velocity_m_per_s, internal, ball):
        return internal[0]

    def internal_rates(self, deflection_m, velocity_m_per_s, internal, ball):
        k1 = self.stiffness_ratio * reissner_stiffness_N_per_m(ball)
        return jnp.stack([k1 * velocity_m_per_s - internal[0] / self.relaxation_time_s])

    @classmethod
    def start(cls, stiffness_N_per_m, mass_kg, restitution, contact_time_s, speed_m_per_s):
        eta = -2 * math.log(restitution) / math.pi  # loss factor of the rebound
        return {
            "stiffness_ratio": max(2 * eta / max(1 - eta, 0.1), 0.05),
            "relaxation_time_s": contact_time_s / math.pi,
        }

    @classmethod
    def off(cls):
        return cls(0.0, 1e-3)

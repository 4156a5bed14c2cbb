"""How the floor receives the momentum of the wall it arrests: one abstract module, one subclass
per law (a new law is one class).

The paper's model stops the flattened cap at once (§2.1, Eq. 6): during compression mass joins
the cap at the rate (M/2R)δ̇ and the floor supplies its momentum flux (M/2R)δ̇² on top of the
contact force (§2.3, ``rbjax.Model(blocked_force="momentum")``). Two things in that picture are
idealised:

- **The mass arrested.** (M/2R)δ̇ is the thin-shell cap, M = 4πR²ρh. The wall of the JIS ball is
  thick (h/R = 0.36): the column of wall above the contact area 2πRδ has the mass 2πRhρ per unit
  deflection, with ρ = M / (4π(R³ − (R−h)³)/3), i.e. a mass rate

      μ δ̇,     μ = 3 M R h / (2 (R³ − (R − h)³))          (20.5 kg/m for the JIS ball)

  1.46 times the paper's M/2R = 14.0 kg/m.
- **How abruptly it stops.** The column stops at once only while the contact's edge outruns the
  waves in the rubber that would slow it first: the edge spreads at da/dt = Rδ̇/a and the
  arrest is abrupt while the edge Mach number M_e = Rδ̇/(a c) is large (Lesser 1981 for liquid
  impact; Tanaka, Yamazaki & Okumura 2003 for gel spheres leaving Hertz at higher speed).
  Once the edge is subsonic, the elastic field slows the column ahead of the edge and its
  momentum reaches the floor through the contact force instead of as a flux.

:class:`WaveLimitedArrest` keeps the share s(M_e) = M_e^n / (1 + M_e^n) of the column's flux
on the floor during compression, with the edge Mach number taken at the contact radius where
the arrest is decided (a one-parameter reduction: M_e = δ̇ / v_a with the arrest speed
v_a = c a*/R, the deflection speed at which half the flux arrives abruptly, and the exponent n
its sharpness):

    F_floor = F_c + s(δ̇/v_a) μ δ̇² H(δ̇).

At small speeds the arrest is quasi-static (s → 0: the paper's blocked force ``paper``); at
large ones the whole column stops at once (s → 1: 1.46 times the paper's ``momentum``). The
share of the flux that reaches the floor grows like (v/v_a)^n: a jump of height ∝ v^(2+n) at
first contact, the mechanism behind L_FE growing by more than 3 dB per doubling of drop height
above 125 Hz (§4.2, Fig. 11). The equation of motion of the moving part (Eqs. 6/7) takes the
same column for its cap: the dynamic mass M − μδ and the thrust μδ̇² in restitution
(:meth:`AbstractArrest.mass_rate_kg_per_m`). With the paper's M/2R there, the floor would
receive up to 1.46 times the flux the moving part loses (measured on the composite of
``docs/guides/ball-across-heights.md``: 3 % more impulse than the ball's change of momentum at
1.6 m).
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike

from .declare import Parameter, check_declared

#: name → class of every arrest law defined (filled by subclassing).
ARREST_LAWS: dict[str, type[AbstractArrest]] = {}


def column_mass_rate_kg_per_m(ball):
    """μ = 3MRh / (2(R³ − (R−h)³)): the mass of wall above the contact area per unit deflection
    (the paper's thin-shell M/2R for h ≪ R)."""
    r, h, m = ball.radius_m, ball.wall_m, ball.mass_kg
    return 3.0 * m * r * h / (2.0 * (r**3 - (r - h) ** 3))


class AbstractArrest(eqx.Module):
    """A law for the flux of arrested momentum on the floor during compression.

    Subclasses set ``name`` and ``PARAMETERS`` and implement :meth:`flux_N`.
    """

    name: ClassVar[str] = ""
    PARAMETERS: ClassVar[dict[str, Parameter]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.name and not getattr(cls, "__abstractmethods__", None):
            ARREST_LAWS[cls.name] = cls

    def __check_init__(self):
        check_declared(self)

    def mass_rate_kg_per_m(self, ball):
        """The mass arrested per unit deflection: the wall column μ. The moving part loses it in
        compression and regains it in restitution (the dynamic mass M − μδ and the thrust μδ̇²
        of Eqs. 6/7 with μ for the paper's M/2R, ``rbjax.terms.forces.cap_mass_rate_kg_per_m``),
        so that where the whole flux arrives abruptly the floor receives the momentum the ball
        loses, no more."""
        return column_mass_rate_kg_per_m(ball)

    @abc.abstractmethod
    def flux_N(self, velocity_m_per_s, ball):
        """The arrested momentum's flux on the floor (N) at deflection speed δ̇ > 0."""

    @classmethod
    def start(cls, speed_m_per_s: float) -> dict:
        """Start values for fitting, from the largest impact speed of the data."""
        return {}


class WaveLimitedArrest(AbstractArrest):
    """The column's flux μδ̇², its share s = x^n/(1 + x^n), x = δ̇/v_a, arriving abruptly (see
    the module docstring).

    Attributes:
        arrest_speed_m_per_s: v_a > 0, the deflection speed at which half of the flux arrives
            abruptly (0.2–20 m/s: a tenth of the impact speeds of 0.1–1.6 m drops to ten times).
        arrest_exponent: n, 0.5 ≤ n ≤ 100, how sharply the share rises with speed (n = 100:
            from 10 % to 90 % of the flux within ±2.2 % of v_a, the sharp threshold of an edge
            turning supersonic).

    Raises:
        ValueError: a field outside its range or not finite, named in the message (concrete
            values only).
    """

    arrest_speed_m_per_s: ArrayLike
    arrest_exponent: ArrayLike
    name: ClassVar[str] = "arrest"
    PARAMETERS: ClassVar = {
        "arrest_speed_m_per_s": Parameter(
            "m/s",
            lower=0.2,
            upper=20.0,
            lower_open=False,
            upper_open=False,
            transform="interval",
            description=(
                "v_a, deflection speed at which half of the wall column's momentum flux reaches "
                "the floor abruptly (edge Mach number δ̇/v_a)"
            ),
        ),
        "arrest_exponent": Parameter(
            "1",
            lower=0.5,
            upper=100.0,
            lower_open=False,
            upper_open=False,
            transform="interval",
            description="n in the abrupt share (δ̇/v_a)^n / (1 + (δ̇/v_a)^n) of the arrest",
        ),
    }

    def share(self, velocity_m_per_s):
        """s(δ̇/v_a) = x^n/(1 + x^n), 0 for δ̇ ≤ 0, written as the logistic function of n log x:
        no overflow, and finite derivatives at every speed (x^−n overflowed below
        x = 10^(−308/n), and its derivative there was NaN)."""
        v = jnp.asarray(velocity_m_per_s)
        x = jnp.maximum(v, 1e-300) / self.arrest_speed_m_per_s
        n = jnp.asarray(self.arrest_exponent)
        return jnp.where(v > 0.0, jax.nn.sigmoid(n * jnp.log(x)), 0.0)

    def flux_N(self, velocity_m_per_s, ball):
        """s(δ̇/v_a) μ δ̇² during compression (δ̇ > 0), 0 otherwise."""
        v = jnp.asarray(velocity_m_per_s)
        return self.share(v) * self.mass_rate_kg_per_m(ball) * jnp.where(v > 0.0, v * v, 0.0)

    @classmethod
    def start(cls, speed_m_per_s: float) -> dict:
        """Half the flux abrupt at 0.6 times the largest impact speed, a sharp rise (n = 6)."""
        return {"arrest_speed_m_per_s": 0.6 * speed_m_per_s, "arrest_exponent": 6.0}

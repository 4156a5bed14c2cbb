"""Elements in series with the shell: one abstract module, one subclass per element (a new
element is one class, as a damping law is).

An element in series with the shell sits between the ball's moving body (its rigid motion X)
and the cap pressed onto the floor: it carries the contact force F_c and adds a displacement
w of its own, so the shell is pressed by δ = X + w (− u on a moving floor). The solver knows an
element only through :class:`AbstractSeriesElement`:

- its internal states z (``num_states``, named ``state_names``; ``initial_states`` at first
  contact, zeros by default) and their rates ż given the contact force (``rates``);
- how it couples: the rate ẇ of the displacement it adds (``velocity_m_per_s``) and the
  acceleration ẅ it adds to δ̈ = Ẍ + ẅ. An inertial element (``massless = False``, e.g.
  ``rbjax.BallMode``) gives ẅ explicitly from its states (``acceleration_m_per_s2``). A
  massless one (``massless = True``, e.g. ``rbjax.SeriesKelvinVoigt``) has ẇ set by the force
  itself, so ẅ = ``acceleration_m_per_s2`` − a dF_c/dt with a = ``force_rate_weight``; the
  solver then solves for δ̈ in closed form (dF_c/dt is linear in δ̈) and, at first contact,
  for the velocity jump δ̇ = v0 + ẇ(0);
- its free motion after the contact ends (``free_change_m``: w(τ) − w(0) with F_c = 0) over a
  horizon of its slowest time scale (``recontact_horizon_s``), for the recontact check;
- its "off" value (``off``: parameters that make w ≡ 0, held by a fit in a shared structure), its
  start values for fitting (``start``, and ``START_ALTERNATIVES``), and its parameters'
  declarations (``PARAMETERS``).

Subclasses register themselves by ``name`` (``SERIES_ELEMENTS``: model names such as
``hunt-crossley+ball-mode``, parameter files under ``file_key``). ``rbjax.Model`` walks its
elements (``Model.series_elements``) for states, names and starts; the solver walks them for
rates and coupling, with no element named anywhere in it.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp

from .declare import Parameter, check_declared

#: name → class of every element in series with the shell (filled by subclassing, in the order
#: the classes are defined: the order a shared structure holds them in).
SERIES_ELEMENTS: dict[str, type[AbstractSeriesElement]] = {}


class AbstractSeriesElement(eqx.Module):
    """An element in series with the shell (see the module docstring).

    Subclasses set the class attributes ``name`` (unique), ``num_states``, ``state_names``,
    ``PARAMETERS`` (and ``massless``, ``label``, ``file_key`` where the defaults do not fit),
    and implement :meth:`rates`, :meth:`velocity_m_per_s`, :meth:`acceleration_m_per_s2`,
    :meth:`recontact_horizon_s` and :meth:`free_change_m` (massless ones also
    :meth:`force_rate_weight`).
    """

    name: ClassVar[str] = ""
    num_states: ClassVar[int] = 0
    state_names: ClassVar[tuple[str, ...]] = ()
    #: True: ẇ is set by the contact force itself (no mass of its own; see the module docstring).
    massless: ClassVar[bool] = False
    #: The element in words, for messages (default: ``the series element 'name'``).
    label: ClassVar[str] = ""
    #: The key of the element's table in parameter files (default: ``name``).
    file_key: ClassVar[str] = ""
    PARAMETERS: ClassVar[dict[str, Parameter]] = {}
    #: Other start values a fit tries beside ``start``'s (name → values).
    START_ALTERNATIVES: ClassVar[dict[str, tuple[float, ...]]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.name and not getattr(cls, "__abstractmethods__", None):
            SERIES_ELEMENTS[cls.name] = cls

    def __check_init__(self):
        check_declared(self)

    @classmethod
    def description(cls) -> str:
        """The element in words (``label``, or one made from ``name``)."""
        return cls.label or f"the series element {cls.name!r}"

    @classmethod
    def key(cls) -> str:
        """The key of the element's table in parameter files (``file_key``, or ``name``)."""
        return cls.file_key or cls.name

    def initial_states(self):
        """z at first contact (shape ``(num_states,)``; zeros by default)."""
        return jnp.zeros(self.num_states)

    @abc.abstractmethod
    def rates(self, states, contact_force_N, ball):
        """dz/dt of the element's states, given the contact force F_c it carries."""

    @abc.abstractmethod
    def velocity_m_per_s(self, states, contact_force_N):
        """ẇ, the rate of the displacement the element adds to the shell's deflection."""

    @abc.abstractmethod
    def acceleration_m_per_s2(self, states, rates):
        """ẅ given the states and their ``rates`` (a massless element: the part of ẅ besides
        −``force_rate_weight()``·dF_c/dt)."""

    def force_rate_weight(self):
        """a in ẅ = … − a dF_c/dt (massless elements only)."""
        raise NotImplementedError(f"{type(self).__name__} is not massless: ẅ has no dF_c/dt term")

    @abc.abstractmethod
    def recontact_horizon_s(self):
        """How long after separation its free motion is followed (a few of its time scales)."""

    @abc.abstractmethod
    def free_change_m(self, states, times_s):
        """w(τ) − w(0) of its free motion (F_c = 0) at the times τ after separation."""

    @classmethod
    def start(
        cls,
        stiffness_N_per_m: float,
        mass_kg: float,
        restitution: float,
        contact_time_s: float,
        speed_m_per_s: float,
    ) -> dict:
        """Start values for fitting from the shell's stiffness, the mass, and the measured
        restitution, contact time and impact speed."""
        return {}

    @classmethod
    def off(cls) -> AbstractSeriesElement:
        """The element with parameters that keep w ≡ 0 (for a shared structure): by
        default every parameter at its lower bound 0; an element for which that is not "off"
        (or not allowed) overrides this."""
        specs = cls.PARAMETERS
        if not all(s.lower == 0.0 and not s.lower_open for s in specs.values()):
            raise NotImplementedError(
                f"{cls.__name__} must define off(): not every parameter may be 0"
            )
        return cls(**{name: 0.0 for name in specs})


def free_oscillation(q0, qd0, omega, eta, tau):
    """q(τ) of q̈ + ηωq̇ + ω²q = 0 from (q0, q̇0) (any damping: complex ω_d; ω = 0: a free mass)."""
    zeta = 0.5 * eta
    wd = omega * jnp.sqrt((1.0 - zeta**2) + 0j)
    small = jnp.abs(wd) < 1e-9 * jnp.maximum(omega, 1.0)
    safe = jnp.where(small, 1.0, wd)
    sin_over = jnp.where(small, tau, jnp.sin(safe * tau) / safe)
    q = jnp.exp(-zeta * omega * tau) * (
        q0 * jnp.cos(wd * tau) + (qd0 + zeta * omega * q0) * sin_over
    )
    return jnp.real(q)

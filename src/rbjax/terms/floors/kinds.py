"""Floors under the ball: the rigid floor of the paper, and floors whose surface moves.

The paper computes the blocked force, "the ball dropped on a flat immobile object" (§1). On a
real floor the surface under the ball moves by u(t) while the force acts, so the shell's
deflection is the ball's displacement relative to the surface, δ = X − u (X: the ball's
moving part, downward positive), and the floor receives the force of the coupled motion. A
floor is an equinox Module, a term like the others: ``Rigid`` (the default, today's model
exactly), ``Dashpot`` (a real point impedance Z: u̇ = F/Z), ``InfinitePlate`` (the thin plate's
Z = 8√(B′m″)) and the modal floors (modes at the drive point: ``ModalFloor``, values given;
``rbjax.terms.floors.floating.FloatingFloor``, a floating floor of declared parameters). The
coupled equations are derived in :mod:`rbjax.solve.ode` and docs/guides/floors.md.

A floor tells the solver three things about its drive point, for a floor force F and the
floor's states s (all zero at first contact):

- ``rates(s, F)``: ds/dt;
- ``velocity_m_per_s(s, F)``: u̇;
- ``acceleration_m_per_s2(s, F)`` and ``admittance_m_per_Ns``: ü = acceleration + admittance·dF/dt
  (a massless floor, u̇ = F/Z, has ü = (dF/dt)/Z; a floor with mass has ü from its states).
"""

from __future__ import annotations

import abc
import math
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from ..declare import POSITIVE, Parameter, check_declared

#: name → class of every floor defined (filled by subclassing).
FLOOR_MODELS: dict[str, type[AbstractFloor]] = {}


class AbstractFloor(eqx.Module):
    """The drive point of a floor under the ball (see the module docstring)."""

    name: ClassVar[str] = ""
    PARAMETERS: ClassVar[dict[str, Parameter]] = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.name and not getattr(cls, "__abstractmethods__", None):
            FLOOR_MODELS[cls.name] = cls

    def __check_init__(self):
        check_declared(self)

    @property
    def num_states(self) -> int:
        return 0

    @property
    def rigid(self) -> bool:
        """True for the immobile floor (no states, u ≡ 0)."""
        return False

    @property
    def massless(self) -> bool:
        """True for a floor without mass at the drive point (u̇ = F/Z): ü depends on dF/dt."""
        return False

    @property
    def admittance_m_per_Ns(self):
        """1/Z of a massless floor (ü = (dF/dt)/Z), 0 for a floor with mass."""
        return 0.0

    @abc.abstractmethod
    def rates(self, states, force_N):
        """ds/dt of the floor's states under the floor force ``force_N``."""

    @abc.abstractmethod
    def velocity_m_per_s(self, states, force_N):
        """Velocity u̇ of the floor's surface under the ball (downward positive)."""

    def displacement_m(self, states):
        """Displacement u of the floor's surface under the ball (downward positive)."""
        return jnp.zeros(())

    def acceleration_m_per_s2(self, states, force_N):
        """ü less its ``admittance_m_per_Ns``·dF/dt part."""
        return jnp.zeros(())


class Rigid(AbstractFloor):
    """The immobile floor of the paper (the default): u ≡ 0, the force is the blocked force."""

    name = "rigid"

    @property
    def rigid(self) -> bool:
        return True

    def rates(self, states, force_N):
        return jnp.zeros(0)

    def velocity_m_per_s(self, states, force_N):
        return jnp.zeros(())


class _Impedance(AbstractFloor):
    """A massless floor with a real point impedance Z: u̇ = F/Z; its one state is u."""

    @property
    @abc.abstractmethod
    def impedance_Ns_per_m(self):
        """The real point impedance Z (N·s/m)."""

    @property
    def num_states(self) -> int:
        return 1

    @property
    def massless(self) -> bool:
        return True

    @property
    def admittance_m_per_Ns(self):
        return 1.0 / self.impedance_Ns_per_m

    def rates(self, states, force_N):
        return jnp.reshape(force_N / self.impedance_Ns_per_m, (1,))

    def velocity_m_per_s(self, states, force_N):
        return force_N / self.impedance_Ns_per_m

    def displacement_m(self, states):
        return states[0]


class Dashpot(_Impedance):
    """A floor with a given real point impedance Z (N·s/m): u̇ = F/Z (a dashpot to ground).

    Attributes:
        floor_impedance_Ns_per_m: Z > 0 (N·s/m), the point impedance at the drive point.

    Raises:
        ValueError: ``floor_impedance_Ns_per_m`` not finite and > 0 (concrete values only).
    """

    floor_impedance_Ns_per_m: ArrayLike
    name = "dashpot"
    PARAMETERS = {
        "floor_impedance_Ns_per_m": Parameter(
            "N s/m", **POSITIVE, description="point impedance Z of the floor, u̇ = F/Z"
        )
    }

    @property
    def impedance_Ns_per_m(self):
        return self.floor_impedance_Ns_per_m


def plate_impedance_Ns_per_m(thickness_m, youngs_Pa, density_kg_per_m3, poisson):
    """Drive-point impedance of an infinite thin (Kirchhoff) plate, Z = 8√(B′m″).

    B′ = E t³/(12(1 − ν²)) is the bending stiffness per unit width and m″ = ρ t the mass per
    unit area (Cremer, Heckl & Petersson, *Structure-Borne Sound*, 3rd ed., §5.3, Eq. 5.46;
    Vigran, *Building Acoustics*, §5.6). Z is real and frequency-independent: the far field
    of the plate carries the power away as bending waves and nothing returns.

    Args:
        thickness_m: plate thickness t (m).
        youngs_Pa: Young's modulus E of the plate (Pa).
        density_kg_per_m3: density ρ of the plate (kg/m³).
        poisson: Poisson's ratio ν of the plate.

    Returns:
        The drive-point impedance Z (N·s/m), with the broadcast shape of the arguments.
    """
    bending = youngs_Pa * thickness_m**3 / (12.0 * (1.0 - poisson**2))
    return 8.0 * jnp.sqrt(bending * density_kg_per_m3 * thickness_m)


class InfinitePlate(_Impedance):
    """An infinite thin plate under the ball: Z = 8√(B′m″) (see ``plate_impedance_Ns_per_m``).

    Attributes:
        plate_thickness_m: t > 0.
        plate_youngs_Pa: E > 0.
        plate_density_kg_per_m3: ρ > 0.
        plate_poisson: ν in (−1, 0.5].

    Raises:
        ValueError: a field outside its valid range or not finite, named in the message
            (concrete values only).
    """

    plate_thickness_m: ArrayLike
    plate_youngs_Pa: ArrayLike
    plate_density_kg_per_m3: ArrayLike
    plate_poisson: ArrayLike
    name = "infinite-plate"
    PARAMETERS = {
        "plate_thickness_m": Parameter("m", **POSITIVE, description="plate thickness t"),
        "plate_youngs_Pa": Parameter("Pa", **POSITIVE, description="plate Young's modulus E"),
        "plate_density_kg_per_m3": Parameter("kg/m^3", **POSITIVE, description="plate density ρ"),
        "plate_poisson": Parameter(
            "1",
            lower=-1.0,
            upper=0.5,
            upper_open=False,
            transform="interval",
            description="plate Poisson's ratio ν",
        ),
    }

    @property
    def impedance_Ns_per_m(self):
        return plate_impedance_Ns_per_m(
            self.plate_thickness_m,
            self.plate_youngs_Pa,
            self.plate_density_kg_per_m3,
            self.plate_poisson,
        )


def _static_tuple(name: str, values) -> tuple[float, ...]:
    out = tuple(float(v) for v in np.ravel(np.asarray(values, dtype=np.float64)))
    if not out:
        raise ValueError(f"{name} is empty; give at least one mode")
    if not all(math.isfinite(v) for v in out):
        raise ValueError(f"{name}={out!r} has a non-finite value")
    return out


class AbstractModalFloor(AbstractFloor):
    """A floor given by its modes at the drive point: u = Σ q_k with
    m_k(q̈_k + η_k ω_k q̇_k + ω_k² q_k) = F. Each mode k is a mass m_k (its modal mass seen at the
    drive point, m_k = M_k/φ_k² for a mode of generalised mass M_k and shape value φ_k there), an
    angular frequency ω_k = 2πf_k and a loss factor η_k (viscous at resonance); each adds two
    states (q_k, q̇_k). Subclasses give ``modes()`` (``ModalFloor``: the values as given;
    ``rbjax.terms.floors.floating.FloatingFloor``: computed from its declared parameters)."""

    @property
    @abc.abstractmethod
    def num_modes(self) -> int:
        """How many modes (static)."""

    @abc.abstractmethod
    def modes(self):
        """(m_k in kg, ω_k in rad/s, η_k): three arrays of ``num_modes`` values (JAX, traceable)."""

    @property
    def num_states(self) -> int:
        return 2 * self.num_modes

    def _modal_accelerations(self, states, force_N):
        m, w, eta = self.modes()
        n = self.num_modes
        q, qd = states[:n], states[n:]
        return force_N / m - eta * w * qd - w**2 * q

    def rates(self, states, force_N):
        n = self.num_modes
        return jnp.concatenate([states[n:], self._modal_accelerations(states, force_N)])

    def velocity_m_per_s(self, states, force_N):
        return jnp.sum(states[self.num_modes :])

    def displacement_m(self, states):
        return jnp.sum(states[: self.num_modes])

    def acceleration_m_per_s2(self, states, force_N):
        return jnp.sum(self._modal_accelerations(states, force_N))


class ModalFloor(AbstractModalFloor):
    """A floor given by its modes at the drive point (a finite plate, a floating floor, a
    measured modal model; ``AbstractModalFloor``).

    The values are static (given, not fitted): a new floor compiles a new program. A floor whose
    modes follow from parameters to differentiate declares them as leaves and computes its
    modes (``rbjax.terms.floors.floating.FloatingFloor``).

    Attributes:
        mass_kg, frequency_Hz, loss_factor: one value per mode (sequences of equal length);
            m_k > 0, f_k ≥ 0 (0: a free mass, e.g. a plate's rigid-body mode), η_k ≥ 0.
            One ``loss_factor`` is shared by every mode.

    Raises:
        ValueError: an empty sequence or a non-finite value; sequences of different lengths;
            a mass ≤ 0, a frequency < 0 or a loss factor < 0 (the mode named in the message).
    """

    mass_kg: tuple[float, ...] = eqx.field(static=True)
    frequency_Hz: tuple[float, ...] = eqx.field(static=True)
    loss_factor: tuple[float, ...] = eqx.field(static=True)
    name = "modal"

    def __init__(self, mass_kg, frequency_Hz, loss_factor):
        self.mass_kg = _static_tuple("mass_kg", mass_kg)
        self.frequency_Hz = _static_tuple("frequency_Hz", frequency_Hz)
        loss = _static_tuple("loss_factor", loss_factor)
        self.loss_factor = loss * len(self.mass_kg) if len(loss) == 1 else loss

    def __check_init__(self):
        n = len(self.mass_kg)
        if len(self.frequency_Hz) != n or len(self.loss_factor) != n:
            raise ValueError(
                f"mass_kg, frequency_Hz and loss_factor need one value per mode; got {n}, "
                f"{len(self.frequency_Hz)} and {len(self.loss_factor)}"
            )
        for k, (m, f, eta) in enumerate(zip(self.mass_kg, self.frequency_Hz, self.loss_factor)):
            if not m > 0.0:
                raise ValueError(
                    f"mass_kg[{k}]={m!r} is outside the valid range (0, inf): a mode needs a "
                    "positive mass"
                )
            if not f >= 0.0:
                raise ValueError(f"frequency_Hz[{k}]={f!r} is outside the valid range [0, inf)")
            if not eta >= 0.0:
                raise ValueError(f"loss_factor[{k}]={eta!r} is outside the valid range [0, inf)")

    @property
    def num_modes(self) -> int:
        return len(self.mass_kg)

    def modes(self):
        return (
            jnp.asarray(self.mass_kg),
            2.0 * jnp.pi * jnp.asarray(self.frequency_Hz),
            jnp.asarray(self.loss_factor),
        )

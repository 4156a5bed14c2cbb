"""What is modelled: the model that assembles the terms, and the shared structure of several."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .._validate import as_float, check_choice, check_range, is_traced
from .arrest import AbstractArrest
from .ball_mode import BallMode
from .contact_layer import ContactLayer
from .damping import DAMPING_MODELS, AbstractDamping
from .declare import Parameter, check_declared
from .floors.kinds import AbstractFloor, Rigid
from .forces import CubicStiffening
from .series_element import SERIES_ELEMENTS, AbstractSeriesElement
from .series_kelvin_voigt import SeriesKelvinVoigt

GAS_OPTIONS = ("adiabatic", "none")
#: ``paper``: the floor force is F_B + F_G (+ damping), as the paper computes it (§2.4).
#: ``momentum``: during compression the floor also supplies the momentum flux (M/2R)δ̇² of
#: the cap being stopped (§2.3), so it is added to the floor force while δ̇ > 0.
BLOCKED_FORCE_OPTIONS = ("paper", "momentum")


def _as_damping_tuple(damping) -> tuple:
    if damping is None:
        return ()
    if isinstance(damping, AbstractDamping):
        return (damping,)
    if isinstance(damping, (tuple, list)):
        return tuple(damping)
    return damping  # rejected by __check_init__ with a named error


def _as_element_tuple(ball_mode, series, series_elements) -> tuple:
    """The elements in series with the shell: ``ball_mode``, ``series``, then the others."""
    if ball_mode is not None and not isinstance(ball_mode, BallMode):
        raise ValueError(f"ball_mode={ball_mode!r} must be None or an rbjax.BallMode")
    if series is not None and not isinstance(series, SeriesKelvinVoigt):
        raise ValueError(f"series={series!r} must be None or an rbjax.SeriesKelvinVoigt")
    if isinstance(series_elements, AbstractSeriesElement):
        series_elements = (series_elements,)
    elif isinstance(series_elements, (tuple, list)):
        series_elements = tuple(series_elements)
    given = tuple(e for e in (ball_mode, series) if e is not None)
    if not isinstance(series_elements, tuple):
        return series_elements  # rejected by __check_init__ with a named error
    return given + series_elements


class Model(eqx.Module):
    """The terms of the impact model. Every extension is off unless given.

    Attributes:
        gas: ``"adiabatic"`` (gas force F_G, Eq. 4 corrected) or ``"none"``.
        damping: damping laws acting in parallel (their forces add), each an
            ``rbjax.AbstractDamping`` (``KelvinVoigt``, ``HuntCrossley``, ``Zener``, or your
            own subclass); ``None``, one law, or a tuple of laws may be given.
        stiffening: ``None`` or a ``CubicStiffening`` pytree.
        momentum_flux_weight: the share w of the momentum flux (M/2R)δ̇² the floor receives
            during compression (a parameter, 0 ≤ w ≤ 1): 0 is ``blocked_force="paper"``, 1 is
            ``"momentum"``. A runtime value, so models that differ only in it share one
            compiled program.
        max_deflection_ratio: largest valid δ_max/h; beyond it the small-deflection shell
            model (§2.1: δ_max < δ_c, buckling from δ_c/h ≈ 2 for thin shells) is not valid
            and the result is flagged ``deflection_limit``.
        series_elements: the elements in series with the shell, each an
            ``rbjax.AbstractSeriesElement`` (``rbjax.terms.series_element``), in the order of
            their states. ``Model(ball_mode=BallMode(…))`` (the ball's own vibration,
            ``rbjax.terms.ball_mode``; two states) and ``Model(series=SeriesKelvinVoigt(…))``
            (a massless spring and damper, the ball mode's overdamped limit,
            ``rbjax.terms.series_kelvin_voigt``; one state) put the two built-in ones first
            (read back as ``model.ball_mode``, ``model.series``); ``series_elements=`` takes
            one element or a tuple of them (any subclass: a new element is one class).
        floor: an ``rbjax.terms.floors.kinds.AbstractFloor``; ``Rigid()`` (the default) is the
            paper's immobile floor, others move under the force (``rbjax.terms.floors.kinds``).
        layer: ``None`` or a ``ContactLayer``: a massless layer F = K y^p in series with the
            shell (``rbjax.terms.contact_layer``); the contact force stays a function of δ.
        arrest: ``None`` or an ``rbjax.terms.arrest.AbstractArrest`` (``WaveLimitedArrest``):
            the flux of the wall's arrested momentum on the floor during compression, in place
            of the share ``momentum_flux_weight`` of the paper's (M/2R)δ̇².

    ``Model(blocked_force="momentum")`` sets ``momentum_flux_weight=1``.

    Raises:
        ValueError: ``blocked_force`` and ``momentum_flux_weight`` both given; an unknown
            ``gas`` or ``blocked_force``; ``ball_mode`` not a ``BallMode`` or ``series`` not a
            ``SeriesKelvinVoigt``; a ``damping``, ``stiffening``, ``series_elements`` or
            ``floor`` of the wrong kind; a damping law or element in series given twice;
            ``momentum_flux_weight`` outside [0, 1] or ``max_deflection_ratio`` ≤ 0 (concrete
            values only); ``layer`` not a ``ContactLayer``; ``arrest`` not an arrest law, or
            given together with a non-zero ``momentum_flux_weight`` (``blocked_force=
            "momentum"``): both say what the floor receives of the flux. The message names the
            argument.
    """

    gas: str = eqx.field(static=True)
    damping: tuple
    stiffening: CubicStiffening | None
    momentum_flux_weight: ArrayLike
    max_deflection_ratio: float = eqx.field(static=True)
    series_elements: tuple
    floor: AbstractFloor
    layer: ContactLayer | None
    arrest: AbstractArrest | None
    PARAMETERS: ClassVar = {
        "momentum_flux_weight": Parameter(
            "1",
            lower=0.0,
            upper=1.0,
            lower_open=False,
            upper_open=False,
            transform="interval",
            description="share of the momentum flux (M/2R)δ̇² in the floor force during compression",
        )
    }

    def __init__(
        self,
        gas: str = "adiabatic",
        blocked_force: str | None = None,
        damping: AbstractDamping | Sequence[AbstractDamping] | None = None,
        stiffening: CubicStiffening | None = None,
        max_deflection_ratio: float = 2.0,
        *,
        momentum_flux_weight=None,
        ball_mode: BallMode | None = None,
        floor: AbstractFloor | None = None,
        series: SeriesKelvinVoigt | None = None,
        series_elements: AbstractSeriesElement | Sequence[AbstractSeriesElement] = (),
        layer: ContactLayer | None = None,
        arrest: AbstractArrest | None = None,
    ):
        if blocked_force is not None and momentum_flux_weight is not None:
            raise ValueError("give blocked_force or momentum_flux_weight, not both")
        if momentum_flux_weight is None:
            bf = "paper" if blocked_force is None else blocked_force
            check_choice("blocked_force", bf, BLOCKED_FORCE_OPTIONS)
            momentum_flux_weight = 1.0 if bf == "momentum" else 0.0
        self.gas = gas
        self.damping = _as_damping_tuple(damping)
        self.stiffening = stiffening
        self.momentum_flux_weight = momentum_flux_weight
        self.max_deflection_ratio = max_deflection_ratio
        self.series_elements = _as_element_tuple(ball_mode, series, series_elements)
        self.floor = Rigid() if floor is None else floor
        self.layer = layer
        self.arrest = arrest

    def __check_init__(self):
        check_choice("gas", self.gas, GAS_OPTIONS)
        check_declared(self)
        if not isinstance(self.damping, tuple) or not all(
            isinstance(d, AbstractDamping) for d in self.damping
        ):
            raise ValueError(
                f"damping={self.damping!r} is not a damping model; valid: None, an "
                "rbjax.AbstractDamping (KelvinVoigt, HuntCrossley, Zener, …) or a tuple of them"
            )
        names = [d.name for d in self.damping]
        if len(set(names)) != len(names):
            raise ValueError(f"damping: each law may appear once; got {names}")
        if self.stiffening is not None and not isinstance(self.stiffening, CubicStiffening):
            raise ValueError(f"stiffening={self.stiffening!r} must be None or a CubicStiffening")
        if not isinstance(self.series_elements, tuple) or not all(
            isinstance(e, AbstractSeriesElement) for e in self.series_elements
        ):
            raise ValueError(
                f"series_elements={self.series_elements!r} is not an element in series with the "
                "shell; valid: an rbjax.AbstractSeriesElement (BallMode, SeriesKelvinVoigt, …) or "
                "a tuple of them"
            )
        names = [e.name for e in self.series_elements]
        if len(set(names)) != len(names):
            raise ValueError(f"series_elements: each element may appear once; got {names}")
        if not isinstance(self.floor, AbstractFloor):
            raise ValueError(
                f"floor={self.floor!r} is not a floor; valid: an "
                "rbjax.terms.floors.kinds.AbstractFloor (Rigid, InfinitePlate, ModalFloor, …)"
            )
        check_range(
            "max_deflection_ratio",
            self.max_deflection_ratio,
            lower=0.0,
            upper=float("inf"),
            upper_open=False,
        )
        if self.layer is not None and not isinstance(self.layer, ContactLayer):
            raise ValueError(f"layer={self.layer!r} must be None or an rbjax.ContactLayer")
        if self.arrest is not None:
            if not isinstance(self.arrest, AbstractArrest):
                raise ValueError(
                    f"arrest={self.arrest!r} is not an arrest law; valid: None or an "
                    "rbjax.terms.arrest.AbstractArrest (WaveLimitedArrest)"
                )
            w = self.momentum_flux_weight
            if not is_traced(w) and np.ndim(w) == 0 and as_float(w) != 0.0:
                raise ValueError(
                    f"arrest={self.arrest.name!r} with momentum_flux_weight={as_float(w)!r}: both "
                    "say what the floor receives of the momentum flux; give the arrest law with "
                    "blocked_force='paper' (momentum_flux_weight=0)"
                )

    @property
    def blocked_force(self) -> str:
        """``paper`` (w = 0), ``momentum`` (w = 1), or ``momentum×w`` in between (concrete w)."""
        w = self.momentum_flux_weight
        if is_traced(w) or np.ndim(w) != 0:
            return "weighted"
        w = as_float(w)
        return "paper" if w == 0.0 else "momentum" if w == 1.0 else f"momentum×{w:g}"

    @property
    def name(self) -> str:
        """``paper`` or the damping laws' names joined by ``+``, then ``+stiffening``,
        ``+contact-layer``, ``+arrest`` and ``+name`` of each element in series with the shell
        (``+ball-mode``, ``+series-kelvin-voigt``, …)."""
        base = "+".join(d.name for d in self.damping) or "paper"
        stiffening = "+stiffening" if self.stiffening is not None else ""
        layer = f"+{self.layer.name}" if self.layer is not None else ""
        arrest = f"+{self.arrest.name}" if self.arrest is not None else ""
        elements = "".join(f"+{e.name}" for e in self.series_elements)
        return base + stiffening + layer + arrest + elements

    @property
    def ball_mode(self) -> BallMode | None:
        """The ``BallMode`` among the elements in series with the shell (None without one)."""
        return next((e for e in self.series_elements if isinstance(e, BallMode)), None)

    @property
    def series(self) -> SeriesKelvinVoigt | None:
        """The ``SeriesKelvinVoigt`` among the elements in series (None without one)."""
        return next((e for e in self.series_elements if isinstance(e, SeriesKelvinVoigt)), None)

    @property
    def num_damping_states(self) -> int:
        return sum(d.num_states for d in self.damping)

    @property
    def num_element_states(self) -> int:
        """The states of the elements in series with the shell, all together."""
        return sum(e.num_states for e in self.series_elements)

    @property
    def num_internal_states(self) -> int:
        """States beyond (δ, δ̇): the damping laws', the elements' in series (the ball mode's
        (w, ẇ), the series element's (w), …), then the floor's."""
        return self.num_damping_states + self.num_element_states + self.floor.num_states

    @property
    def internal_state_names(self) -> tuple[str, ...]:
        """``term:state`` of every internal state, in the state vector's order."""
        names = [f"{d.name}:z{i}" for d in self.damping for i in range(d.num_states)]
        names += [f"{e.name}:{s}" for e in self.series_elements for s in e.state_names]
        names += [f"{self.floor.name}:q{i}" for i in range(self.floor.num_states)]
        return tuple(names)

    def element_states(self, internal) -> list:
        """The internal-state vector cut into one slice per element in series with the shell."""
        out, i = [], self.num_damping_states
        for e in self.series_elements:
            out.append(internal[i : i + e.num_states])
            i += e.num_states
        return out

    def initial_internal_states(self):
        """The internal states at first contact: the damping laws' and the floor's 0, the
        elements' ``initial_states``."""
        parts = [jnp.zeros(self.num_damping_states)]
        parts += [e.initial_states() for e in self.series_elements]
        return jnp.concatenate([*parts, jnp.zeros(self.floor.num_states)])

    def floor_states(self, internal):
        """The floor's states from the internal-state vector."""
        i = self.num_damping_states + self.num_element_states
        return internal[i : i + self.floor.num_states]

    def split_internal(self, internal) -> list:
        """The internal-state vector cut into one slice per damping law."""
        out, i = [], 0
        for d in self.damping:
            out.append(internal[i : i + d.num_states])
            i += d.num_states
        return out

    def term_starts(
        self,
        stiffness_N_per_m: float,
        mass_kg: float,
        restitution: float,
        contact_time_s: float,
        speed_m_per_s: float,
    ) -> dict:
        """Start values for fitting the parameters of the damping laws and the elements in series
        (each term's ``start`` from the shell's stiffness, the ball's mass and the measured
        restitution, contact time and impact speed)."""
        out: dict = {}
        for term in (*self.damping, *self.series_elements):
            out.update(
                type(term).start(
                    stiffness_N_per_m, mass_kg, restitution, contact_time_s, speed_m_per_s
                )
            )
        return out

    @property
    def velocity_dependent(self) -> bool:
        """True if the contact force depends on δ̇ or an internal state (damped models)."""
        return bool(self.damping)

    @property
    def coupling(self) -> str | None:
        """Why the shell is pressed by more than the ball's rigid motion, δ = X + w − u (an
        element in series, a moving floor), in words; None on the rigid floor without one. The
        paths that solve only δ = X (quadrature, phase angle, sampled histories) give it as
        their reason."""
        if self.series_elements:
            e = self.series_elements[0]
            states = "a state" if e.num_states == 1 else "states"
            return f"{e.description()} adds {states} of its own (the shell is pressed by δ = X + w)"
        if not self.floor.rigid:
            return f"the floor ({self.floor.name}) moves under the force (δ = X − u)"
        return None

    @property
    def coupled(self) -> bool:
        """True if the shell is pressed by more than the ball's rigid motion (``coupling``)."""
        return self.coupling is not None


def structure_model(
    base: Model,
    laws=None,
    stiffening: bool = True,
    ball_mode: bool = False,
    series: bool = False,
    elements: Sequence[type[AbstractSeriesElement]] = (),
) -> Model:
    """``base`` with every damping law of ``laws`` (default: all registered), the stiffening
    and the elements in series of ``elements`` (with ``ball_mode``, ``series``: the ball mode
    and the series element too) present but switched off (their ``off()`` values, β = 0,
    μ = 0, C = 0).

    Models that differ in which of these terms are on share this structure, so one
    compiled program serves them all; the terms a candidate leaves off are held at their
    off values. The elements are opt-in: held off they are exact (w ≡ 0) but carry their
    states and Jacobian columns through every solve (the ball mode two states and three
    columns). The structure holds its elements in the order their classes were defined
    (``SERIES_ELEMENTS``).
    """
    laws = tuple(DAMPING_MODELS.values()) if laws is None else tuple(laws)
    have = {type(d) for d in base.damping}
    damping = base.damping + tuple(law.off() for law in laws if law not in have)
    stiff = (
        base.stiffening
        if base.stiffening is not None
        else (CubicStiffening(0.0) if stiffening else None)
    )
    present = {type(e): e for e in base.series_elements}
    wanted = set(present) | set(elements)
    wanted |= {BallMode} if ball_mode else set()
    wanted |= {SeriesKelvinVoigt} if series else set()
    order = list(SERIES_ELEMENTS.values())
    order += [c for c in (*present, *elements) if c not in order]
    in_series = tuple(present[c] if c in present else c.off() for c in order if c in wanted)
    return Model(
        gas=base.gas,
        damping=damping,
        stiffening=stiff,
        max_deflection_ratio=base.max_deflection_ratio,
        momentum_flux_weight=base.momentum_flux_weight,
        floor=base.floor,
        series_elements=in_series,
        layer=base.layer,
        arrest=base.arrest,
    )

"""What is modelled (the terms) and how it is integrated (solver settings)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import diffrax as dfx
import equinox as eqx
import numpy as np
import optimistix as optx
from jaxtyping import ArrayLike

from .._validate import as_float, check_choice, check_range, is_traced
from .ball_mode import BallMode
from .damping import DAMPING_MODELS, AbstractDamping
from .declare import Parameter, check_declared
from .floors.kinds import AbstractFloor, Rigid
from .forces import CubicStiffening
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
        ball_mode: ``None`` or a ``BallMode``: the ball's own vibration in series with the
            shell (``rbjax.terms.ball_mode``; two states).
        series: ``None`` or a ``SeriesKelvinVoigt``: a massless spring and damper in series
            with the shell, the ball mode's overdamped limit
            (``rbjax.terms.series_kelvin_voigt``; one state).
        floor: an ``rbjax.terms.floors.kinds.AbstractFloor``; ``Rigid()`` (the default) is the
            paper's immobile floor, others move under the force (``rbjax.terms.floors.kinds``).

    ``Model(blocked_force="momentum")`` sets ``momentum_flux_weight=1``.
    """

    gas: str = eqx.field(static=True)
    damping: tuple
    stiffening: CubicStiffening | None
    momentum_flux_weight: ArrayLike
    max_deflection_ratio: float = eqx.field(static=True)
    ball_mode: BallMode | None
    series: SeriesKelvinVoigt | None
    floor: AbstractFloor
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
        self.ball_mode = ball_mode
        self.series = series
        self.floor = Rigid() if floor is None else floor

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
        if self.ball_mode is not None and not isinstance(self.ball_mode, BallMode):
            raise ValueError(f"ball_mode={self.ball_mode!r} must be None or an rbjax.BallMode")
        if self.series is not None and not isinstance(self.series, SeriesKelvinVoigt):
            raise ValueError(f"series={self.series!r} must be None or an rbjax.SeriesKelvinVoigt")
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
        ``+ball-mode`` and ``+series-kelvin-voigt`` for the terms present."""
        base = "+".join(d.name for d in self.damping) or "paper"
        terms = (self.stiffening, self.ball_mode, self.series)
        return base + "".join(f"+{_TERM_NAMES[i]}" for i, t in enumerate(terms) if t is not None)

    @property
    def num_damping_states(self) -> int:
        return sum(d.num_states for d in self.damping)

    @property
    def _num_mode_states(self) -> int:
        return BallMode.num_states if self.ball_mode is not None else 0

    @property
    def _num_series_states(self) -> int:
        return SeriesKelvinVoigt.num_states if self.series is not None else 0

    @property
    def num_internal_states(self) -> int:
        """States beyond (δ, δ̇): the damping laws', the ball mode's (w, ẇ), the series
        element's (w), then the floor's."""
        return (
            self.num_damping_states
            + self._num_mode_states
            + self._num_series_states
            + self.floor.num_states
        )

    def ball_mode_states(self, internal):
        """(w, ẇ) of the ball mode from the internal-state vector (empty without one)."""
        i = self.num_damping_states
        return internal[i : i + self._num_mode_states]

    def series_states(self, internal):
        """(w,) of the series element from the internal-state vector (empty without one)."""
        i = self.num_damping_states + self._num_mode_states
        return internal[i : i + self._num_series_states]

    def floor_states(self, internal):
        """The floor's states from the internal-state vector."""
        i = self.num_damping_states + self._num_mode_states + self._num_series_states
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
        """Start values for fitting the parameters of the damping laws, the ball mode and the
        series element (each term's ``start`` from the shell's stiffness, the ball's mass and
        the measured restitution, contact time and impact speed)."""
        out: dict = {}
        for term in (*self.damping, self.ball_mode, self.series):
            if term is not None:
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
        """Why the shell is pressed by more than the ball's rigid motion, δ = X + w − u (a ball
        mode, a moving floor), in words; None on the rigid floor without a ball mode. The paths
        that solve only δ = X (quadrature, phase angle, sampled histories) give it as their
        reason."""
        if self.ball_mode is not None:
            return "the ball mode adds states of its own (the shell is pressed by δ = X + w)"
        if self.series is not None:
            return "the series element adds a state of its own (the shell is pressed by δ = X + w)"
        if not self.floor.rigid:
            return f"the floor ({self.floor.name}) moves under the force (δ = X − u)"
        return None

    @property
    def coupled(self) -> bool:
        """True if the shell is pressed by more than the ball's rigid motion (``coupling``)."""
        return self.coupling is not None


_TERM_NAMES = ("stiffening", BallMode.name, SeriesKelvinVoigt.name)

_SOLVERS = {
    "euler": dfx.Euler,
    "heun": dfx.Heun,
    "midpoint": dfx.Midpoint,
    "bosh3": dfx.Bosh3,
    "tsit5": dfx.Tsit5,
    "dopri5": dfx.Dopri5,
    "dopri8": dfx.Dopri8,
    "kvaerno5": dfx.Kvaerno5,
}
FIXED_STEP_METHODS = ("euler", "heun", "midpoint")
ADJOINTS = ("reverse", "forward")


class Solver(eqx.Module):
    """How the equation of motion is integrated.

    Attributes:
        method: a diffrax solver name, one of ``_SOLVERS`` (default ``tsit5``).
        rtol, atol: adaptive step-size tolerances (atol in the state's units, m and m/s).
        step_s: fixed step for the fixed-step methods (required for them, ignored otherwise).
        max_steps: step budget per phase; exhausting it gives status ``step_limit``.
        adjoint: ``"reverse"`` (works with ``jax.grad``) or ``"forward"`` (works with
            ``jax.jacfwd``/``jax.jvp``, cheaper for a few parameters).
    """

    method: str = eqx.field(static=True, default="tsit5")
    rtol: float = eqx.field(static=True, default=1e-9)
    atol: float = eqx.field(static=True, default=1e-12)
    step_s: float | None = eqx.field(static=True, default=None)
    max_steps: int = eqx.field(static=True, default=4096)
    adjoint: str = eqx.field(static=True, default="reverse")

    def __check_init__(self):
        check_choice("method", self.method, tuple(_SOLVERS))
        check_choice("adjoint", self.adjoint, ADJOINTS)
        check_range("rtol", self.rtol, lower=0.0, upper=1.0)
        check_range("atol", self.atol, lower=0.0, upper=1.0)
        if self.method in FIXED_STEP_METHODS and self.step_s is None:
            raise ValueError(f"method={self.method!r} is a fixed-step method: give step_s > 0")
        if self.step_s is not None:
            check_range("step_s", self.step_s, lower=0.0, upper=1.0)
        check_range("max_steps", self.max_steps, lower=0.0)

    def diffrax_solver(self):
        return _SOLVERS[self.method]()

    def controller(self):
        if self.method in FIXED_STEP_METHODS:
            return dfx.ConstantStepSize()
        # Kvaerno5 and the explicit RK methods alike: PID control on rtol/atol.
        return dfx.PIDController(rtol=self.rtol, atol=self.atol)

    def dt0(self):
        return self.step_s if self.method in FIXED_STEP_METHODS else None

    def diffrax_adjoint(self):
        return dfx.ForwardMode() if self.adjoint == "forward" else dfx.RecursiveCheckpointAdjoint()

    def root_finder(self):
        # Event times to ~1e-12 relative on the dense interpolant of each step (event functions
        # are scaled to O(1), and Newton's test also needs |cond| < atol at the root).
        return optx.Newton(rtol=1e-12, atol=1e-13)


def superset_model(
    base: Model, laws=None, stiffening: bool = True, ball_mode: bool = False, series: bool = False
) -> Model:
    """``base`` with every damping law of ``laws`` (default: all registered), the stiffening
    and (with ``ball_mode``, ``series``) the ball mode and the series element present but
    switched off (their ``off()`` values, β = 0, μ = 0, C = 0).

    Models that differ in which of these terms are on share the superset's structure, so one
    compiled program serves them all; the terms a candidate leaves off are held at their
    off values. The ball mode is opt-in: held off it is exact (w ≡ 0) but carries two states
    and three Jacobian columns through every solve.
    """

    laws = tuple(DAMPING_MODELS.values()) if laws is None else tuple(laws)
    have = {type(d) for d in base.damping}
    damping = base.damping + tuple(law.off() for law in laws if law not in have)
    stiff = (
        base.stiffening
        if base.stiffening is not None
        else (CubicStiffening(0.0) if stiffening else None)
    )
    mode = base.ball_mode if base.ball_mode is not None else (BallMode.off() if ball_mode else None)
    element = (
        base.series if base.series is not None else (SeriesKelvinVoigt.off() if series else None)
    )
    return Model(
        gas=base.gas,
        damping=damping,
        stiffening=stiff,
        max_deflection_ratio=base.max_deflection_ratio,
        momentum_flux_weight=base.momentum_flux_weight,
        ball_mode=mode,
        series=element,
        floor=base.floor,
    )

"""What is modelled (terms and their options) and how it is integrated (solver settings)."""

from __future__ import annotations

import diffrax as dfx
import equinox as eqx
import optimistix as optx

from ._validate import check_choice, check_range
from .forces import DAMPING_MODELS, CubicStiffening

GAS_OPTIONS = ("adiabatic", "none")
#: ``paper``: the floor force is F_B + F_G (+ damping), as the paper computes it (§2.4).
#: ``momentum``: during compression the floor also supplies the momentum flux (M/2R)δ̇² of
#: the cap being stopped (§2.3), so it is added to the floor force while δ̇ > 0.
BLOCKED_FORCE_OPTIONS = ("paper", "momentum")


class Model(eqx.Module):
    """The terms of the impact model. Every extension is off unless given.

    Attributes:
        gas: ``"adiabatic"`` (gas force F_G, Eq. 4 corrected) or ``"none"``.
        blocked_force: ``"paper"`` or ``"momentum"`` (see ``BLOCKED_FORCE_OPTIONS``).
        damping: ``None`` (the paper's elastic model) or a ``KelvinVoigt``, ``HuntCrossley``
            or ``Zener`` pytree.
        stiffening: ``None`` or a ``CubicStiffening`` pytree.
        max_deflection_ratio: largest valid δ_max/h; beyond it the small-deflection shell
            model (§2.1: δ_max < δ_c, buckling from δ_c/h ≈ 2 for thin shells) is not valid
            and the result is flagged ``deflection_limit``.
    """

    gas: str = eqx.field(static=True, default="adiabatic")
    blocked_force: str = eqx.field(static=True, default="paper")
    damping: eqx.Module | None = None
    stiffening: CubicStiffening | None = None
    max_deflection_ratio: float = eqx.field(static=True, default=2.0)

    def __check_init__(self):
        check_choice("gas", self.gas, GAS_OPTIONS)
        check_choice("blocked_force", self.blocked_force, BLOCKED_FORCE_OPTIONS)
        if self.damping is not None and not isinstance(self.damping, tuple(DAMPING_MODELS.values())):
            raise ValueError(
                f"damping={self.damping!r} is not a damping model; valid: None or one of "
                f"{', '.join(c.__name__ for c in DAMPING_MODELS.values())}"
            )
        if self.stiffening is not None and not isinstance(self.stiffening, CubicStiffening):
            raise ValueError(f"stiffening={self.stiffening!r} must be None or a CubicStiffening")
        check_range("max_deflection_ratio", self.max_deflection_ratio, lower=0.0, upper=float("inf"), upper_open=False)

    @property
    def name(self) -> str:
        """``paper`` or the damping model's name, with ``+stiffening`` if present."""
        base = "paper" if self.damping is None else self.damping.name
        return base + ("+stiffening" if self.stiffening is not None else "")

    @property
    def num_internal_states(self) -> int:
        return 0 if self.damping is None else self.damping.num_states

    @property
    def velocity_dependent(self) -> bool:
        """True if the contact force depends on δ̇ or an internal state (damped models)."""
        return self.damping is not None


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

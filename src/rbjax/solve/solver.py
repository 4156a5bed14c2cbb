"""How the equation of motion is integrated: the diffrax scheme, its tolerances or fixed step,
the step budget and the adjoint (:class:`Solver`)."""

from __future__ import annotations

import diffrax as dfx
import equinox as eqx
import optimistix as optx

from .._validate import check_choice, check_range

_SCHEMES = {
    "euler": dfx.Euler,
    "heun": dfx.Heun,
    "midpoint": dfx.Midpoint,
    "bosh3": dfx.Bosh3,
    "tsit5": dfx.Tsit5,
    "dopri5": dfx.Dopri5,
    "dopri8": dfx.Dopri8,
    "kvaerno5": dfx.Kvaerno5,
}
FIXED_STEP_SCHEMES = ("euler", "heun", "midpoint")
ADJOINTS = ("reverse", "forward")


class Solver(eqx.Module):
    """How the equation of motion is integrated.

    Attributes:
        scheme: the diffrax scheme by name, one of ``_SCHEMES`` (default ``tsit5``).
        rtol, atol: adaptive step-size tolerances (atol in the state's units, m and m/s).
        step_s: fixed step for the fixed-step schemes (required for them, ignored otherwise).
        max_steps: step budget per phase; exhausting it gives status ``step_limit``.
        adjoint: ``"reverse"`` (works with ``jax.grad``) or ``"forward"`` (works with
            ``jax.jacfwd``/``jax.jvp``, cheaper for a few parameters).

    Raises:
        ValueError: an unknown ``scheme`` or ``adjoint``; ``rtol``, ``atol`` or ``step_s``
            outside (0, 1); a fixed-step scheme without ``step_s``; ``max_steps`` ≤ 0. The
            message names the field.
    """

    scheme: str = eqx.field(static=True, default="tsit5")
    rtol: float = eqx.field(static=True, default=1e-9)
    atol: float = eqx.field(static=True, default=1e-12)
    step_s: float | None = eqx.field(static=True, default=None)
    max_steps: int = eqx.field(static=True, default=4096)
    adjoint: str = eqx.field(static=True, default="reverse")

    def __check_init__(self):
        check_choice("scheme", self.scheme, tuple(_SCHEMES))
        check_choice("adjoint", self.adjoint, ADJOINTS)
        check_range("rtol", self.rtol, lower=0.0, upper=1.0)
        check_range("atol", self.atol, lower=0.0, upper=1.0)
        if self.scheme in FIXED_STEP_SCHEMES and self.step_s is None:
            raise ValueError(f"scheme={self.scheme!r} is a fixed-step scheme: give step_s > 0")
        if self.step_s is not None:
            check_range("step_s", self.step_s, lower=0.0, upper=1.0)
        check_range("max_steps", self.max_steps, lower=0.0)

    def diffrax_solver(self):
        return _SCHEMES[self.scheme]()

    def controller(self):
        if self.scheme in FIXED_STEP_SCHEMES:
            return dfx.ConstantStepSize()
        # Kvaerno5 and the explicit RK schemes alike: PID control on rtol/atol.
        return dfx.PIDController(rtol=self.rtol, atol=self.atol)

    def dt0(self):
        return self.step_s if self.scheme in FIXED_STEP_SCHEMES else None

    def diffrax_adjoint(self):
        return dfx.ForwardMode() if self.adjoint == "forward" else dfx.RecursiveCheckpointAdjoint()

    def root_finder(self):
        # Event times to ~1e-12 relative on the dense interpolant of each step (event functions
        # are scaled to O(1), and Newton's test also needs |cond| < atol at the root).
        return optx.Newton(rtol=1e-12, atol=1e-13)

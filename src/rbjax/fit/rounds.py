"""The rounds of the optimiser of a fit, one driver step (see :func:`rbjax.fit.driver.fit`;
its starts come from :mod:`rbjax.fit.start`):

- :func:`optimise`: rounds of the compiled optimiser for every start at once, each in the
  whitened frame of its current point, until the remaining Gauss–Newton step is below
  ``STEP_TOLERANCE_SIGMA`` σ (a parameter pressed onto a bound of its fit range held there);
- :func:`pick_best`: the converged start of least cost.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._progress import progress as say
from . import uncertainty as unc
from .physical import BOUND_TOLERANCE
from .setup import FitSetup

#: Most re-centrings of the whitened coordinates (rounds of ``STEPS_PER_ROUND`` steps).
MAX_ROUNDS = 8


#: A start still going after two rounds at a cost this many times that of a converged start is
#: abandoned (its lane would keep the others' batch running; it is reported as not converged).
#: See :func:`abandoned`.
ABANDON_FACTOR = 1.5


@dataclasses.dataclass(eq=False)
class Lane:
    """One start's way through the optimiser (see :func:`optimise`)."""

    theta: np.ndarray
    out: dict
    previous_cost: float = math.inf
    steps: int = 0
    done: bool = False
    converged: bool = False
    message: str = ""

    @property
    def cost(self) -> float:
        r = self.out["r"]
        return 0.5 * float(r @ r) if np.all(np.isfinite(r)) else math.inf


@dataclasses.dataclass(frozen=True)
class Rounds:
    """How :func:`optimise` runs: the optimiser (``rbjax.fit.program.OPTIMIZERS``), its step
    budget in all, progress lines (one per start and round, named ``label``, showing the
    parameters ``shown``)."""

    optimizer: str
    max_steps: int
    progress: bool = False
    label: str = "fit"
    shown: tuple[str, ...] = ()


def optimise(
    setup: FitSetup, thetas, outs, free, free_idx, *, weights_of, reevaluate, settings: Rounds
) -> list[Lane]:
    """Rounds of the compiled optimiser for every start (one call per round), each round in the
    whitened frame of that start's current point, until each start's remaining Gauss–Newton
    step is below ``unc.STEP_TOLERANCE_SIGMA`` σ, its steps are spent, or its prediction
    fails. ``outs``: the evaluations at ``thetas`` (evaluated again with ``weights_of`` where
    ``reevaluate``); ``free``, ``free_idx``: the free parameters' mask and θ positions;
    ``settings``: the optimiser, its budget and the progress lines. A start that is done is not
    run again."""
    problem, constants, fit_mask = setup.problem, setup.constants, setup.fit_mask
    optimizer, max_steps, progress = settings.optimizer, settings.max_steps, settings.progress
    label, shown = settings.label, settings.shown
    lay = problem.layout
    n = len(lay.names)
    if reevaluate:  # the residuals' weights depend on the residuals (the ν prior's row)
        outs = problem.run_batch(
            thetas, np.zeros(n, bool), [weights_of(o["r"]) for o in outs], constants
        )
    lanes = [Lane(th, o) for th, o in zip(thetas, outs)]
    for rounds in range(MAX_ROUNDS + 1):
        active, phi_c, w, atol, weights = [], [], [], [], []
        for i, lane in enumerate(lanes):
            if lane.done:
                continue
            phi = lay.to_phi(lane.theta)
            r = lane.out["r"]
            jac_phi = lane.out["jac_theta"][:, free_idx] * lay.from_phi(phi)[1][free_idx][None, :]
            values = ", ".join(f"{k}={lane.theta[lay.index(k)]:.5g}" for k in shown)
            start = f" start {i}" if len(lanes) > 1 else ""
            say(
                f"{label}{start} round {rounds}: cost {lane.cost:.9g}, rms "
                f"{problem.history_rms_N(lane.out['force'], fit_mask):.3g} N, {values}",
                enabled=progress,
            )
            if not (np.all(np.isfinite(r)) and np.all(np.isfinite(jac_phi))):
                lane.done, lane.message = (
                    True,
                    "the model's prediction or its Jacobian is not finite at these parameters "
                    "(a failed solve)",
                )
                continue
            tau = unc.integrated_autocorrelation(problem.history_rows(r, fit_mask))
            # a parameter pressed onto a bound of its fit range: the remaining step is judged
            # on the others
            inside = ~pressed_on_bound(lay, phi, free_idx, jac_phi, r)
            remaining = unc.step_in_sigma(r, jac_phi[:, inside], tau)
            if remaining < unc.STEP_TOLERANCE_SIGMA:
                lane.done, lane.converged = True, True
                lane.message = (
                    f"converged (remaining Gauss–Newton step {remaining:.1g} σ < "
                    f"{unc.STEP_TOLERANCE_SIGMA:g} σ)"
                )
                continue
            best = min((other.cost for other in lanes if other.converged), default=math.inf)
            why = abandoned(lane, best, rounds)
            if why:
                lane.done, lane.message = True, why
                continue
            if lane.steps >= max_steps or rounds >= MAX_ROUNDS:
                lane.done = True
                lane.message = (
                    lane.message
                    or f"not converged after {lane.steps} optimiser steps (remaining Gauss–Newton "
                    f"step {remaining:.2g} σ)"
                )
                continue
            wi = np.zeros((n, n))
            moving = free_idx[inside]  # a parameter on a bound is held there for the round
            wi[np.ix_(moving, moving)] = unc.whitening(jac_phi[:, inside], full=True)
            active.append(lane)
            phi_c.append(phi)
            w.append(wi)
            weights.append(weights_of(r))
            atol.append(
                unc.STEP_TOLERANCE_SIGMA
                * math.sqrt(tau * float(r @ r) / max(r.size - free_idx.size, 1))
            )
        if not active:
            break
        results = problem.run_batch(
            [lane.theta for lane in active],
            free,
            weights,
            constants,
            optimizer=optimizer,
            phi_c=np.stack(phi_c),
            w=np.stack(w),
            atol=atol,
        )
        for lane, phi, wi, res in zip(active, phi_c, w, results):
            lane.steps += int(res["steps"])
            new_theta = np.where(free, lay.from_phi(phi + wi @ res["u"])[0], lane.theta)
            if not np.all(np.isfinite(new_theta)):
                lane.done, lane.message = True, "the optimiser produced non-finite parameters"
                continue
            lane.previous_cost = lane.cost
            lane.theta, lane.out = new_theta, res
            if not res["successful"]:
                lane.message = f"not converged after {lane.steps} optimiser steps" + (
                    " (step limit)" if res["max_steps_reached"] else " (the optimiser stopped)"
                )
    return lanes


def abandoned(lane: Lane, best: float, rounds: int) -> str:
    """Why a start still going after ``rounds`` rounds is given up, where a converged start
    costs ``best`` ("" if it goes on). After two rounds: a cost over ``ABANDON_FACTOR`` times
    ``best``. Before its last round: a cost that would still be above ``best`` when its rounds
    run out, were it to fall in each round left by as much as in its last (a start crawling
    towards a bound or along a valley, which could only end not converged or above ``best``;
    crawls slow down, so the last round's descent is a generous rate)."""
    if rounds >= 2 and lane.cost > ABANDON_FACTOR * best:
        return (
            f"abandoned after {rounds} rounds: cost {lane.cost:.4g} > {ABANDON_FACTOR:g}× "
            f"that of a converged start ({best:.4g})"
        )
    left = MAX_ROUNDS - rounds
    descent = lane.previous_cost - lane.cost
    if math.isfinite(best) and math.isfinite(descent) and left > 0:
        if lane.cost - left * descent > best:
            return (
                f"abandoned after {rounds} rounds: at its last round's descent ({descent:.3g}) "
                f"its cost {lane.cost:.6g} would stay above that of a converged start "
                f"({best:.6g}) in the {left} rounds left"
            )
    return ""


def pressed_on_bound(lay, phi, free_idx, jac_phi, r) -> np.ndarray:
    """Which of the free parameters ``free_idx`` the data press onto a bound of their fit range:
    within ``physical.BOUND_TOLERANCE`` of the range from the bound (where the fit reports
    them on it), with the Gauss–Newton step pointing out of the range. Held there for the next
    round: in φ the interval's slope vanishes at the bound, and the optimiser would crawl."""
    side = np.zeros(len(free_idx))
    for j, i in enumerate(free_idx):
        spec = lay.specs[i]
        if spec.transform == "interval":
            theta = float(spec.from_unconstrained(phi[i]))
            width = spec.upper - spec.lower
            side[j] = (
                1.0
                if spec.upper - theta <= BOUND_TOLERANCE * width
                else (-1.0 if theta - spec.lower <= BOUND_TOLERANCE * width else 0.0)
            )
    if not side.any():
        return np.zeros(len(free_idx), dtype=bool)
    step = np.linalg.lstsq(jac_phi, -r, rcond=None)[0]  # φ grows with θ on an interval
    return (side != 0) & (np.sign(step) == side)


def pick_best(lanes: list[Lane]) -> Lane:
    """The converged start of least cost; the least-cost start if none converged."""
    converged = [lane for lane in lanes if lane.converged]
    return min(converged or lanes, key=lambda lane: lane.cost)

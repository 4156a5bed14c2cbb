"""Where a fit starts (the second step of :func:`rbjax.fit.driver.fit`):

- :func:`start_values`: physically motivated start values from the records;
- :func:`alternative_starts`: the other starts of parameters whose fit has several minima;
- :func:`start_plan`: the start θ of a fit (start values, the caller's start map or a previous
  fit, the held values) and its alternative starts;
- :func:`evaluate_starts`: every start evaluated, its onsets aligned to the records'.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._validate import as_float
from ..solve.outcome import G_N_PER_KG
from ..terms.ball import Ball
from ..terms.forces import reissner_stiffness_N_per_m
from ..terms.model import Model
from .problem import Problem, realign
from .result import FitResult
from .setup import FitSetup


def start_values(problem: Problem, model: Model, ball: Ball, ref_mask, nu: float) -> dict:
    """Physically motivated start values from the measured records.

    Stiffness from the contact time of the lowest fitted height (least gas force):
    t_c ≈ π√(M/k) (a linear spring-mass half period), k → E by Eqs. 1–3; each damping law's
    own ``start`` rule from the restitution read off the impulse, e = ∫F dt/(M v0) − 1 (Eq. 10).
    """

    d = problem.data
    meas = problem.measured
    k_idx = np.flatnonzero(ref_mask)
    lowest = k_idx[np.argmin(d.height_m[k_idx])]
    tc = float(meas["contact_time_s"][lowest])
    mass = as_float(ball.mass_kg)
    k_spring = mass * (math.pi / tc) ** 2
    e_young = (
        k_spring
        * as_float(ball.radius_m)
        * math.sqrt(3 * (1 - nu**2))
        / (4 * as_float(ball.wall_m) ** 2)
    )
    v0 = np.sqrt(2 * G_N_PER_KG * d.height_m)
    impulse = d.force_N.sum(axis=1) / d.rate_Hz
    e = float(np.clip(np.median((impulse / (mass * v0) - 1.0)[k_idx]), 0.05, 0.99))
    values = {"youngs_Pa": e_young, "poisson": nu}
    k_shell = float(
        reissner_stiffness_N_per_m(ball.replace(youngs_Pa=e_young, poisson=min(nu, 0.4999)))
    )
    values.update(model.term_starts(k_shell, mass, e, tc, float(np.median(v0[k_idx]))))
    if model.stiffening is not None:
        values["beta"] = 0.05
    return values


def alternative_starts(model: Model, given: set[str]) -> list[dict]:
    """The starts of a fit of ``model``: ``{}`` (the start values), then one per alternative
    value of a parameter whose fit has several minima, as its term declares them
    (``START_ALTERNATIVES``; e.g. the ball mode's frequency), unless the caller gave or held it."""
    starts: list[dict] = [{}]
    terms = [*model.damping, model.stiffening, *model.series_elements]
    for term in terms:
        for name, values in getattr(type(term), "START_ALTERNATIVES", {}).items():
            if name not in given:
                starts += [{name: float(v)} for v in values]
    return starts


@dataclasses.dataclass(frozen=True, eq=False)
class StartPlan:
    """The start θ of a fit and the alternative values of its other starts (``points``, ``{}``
    first: θ itself); ``aligned``: θ's onsets are aligned already (a warm start);
    ``rescale_E``: E is to be rescaled from the contact times (start values from the records)."""

    theta: np.ndarray
    points: list[dict]
    aligned: bool
    rescale_E: bool


def start_plan(setup: FitSetup, model, start) -> StartPlan:
    """The start θ: start values from the records (or a given ``Model``'s values), then the
    caller's ``start`` map, then the held values; or a previous :class:`FitResult`'s θ (a warm
    start, the held values kept). ``model``, ``start``: as given to :func:`rbjax.fit.driver.fit`."""
    problem, lay, data, fixed, poisson_prior = (
        setup.problem,
        setup.layout,
        setup.data,
        setup.fixed,
        setup.poisson_prior,
    )
    warm = start if isinstance(start, FitResult) else None
    start_map = {} if isinstance(start, FitResult) else dict(start or {})
    for k in start_map:
        if k not in setup.fittable:
            raise ValueError(
                f"start: unknown parameter {k!r} for model {setup.model_name!r}; valid: "
                f"{', '.join(setup.fittable)}"
            )
    if poisson_prior is not None and "poisson" not in start_map:
        # E/√(1−ν²) is all the histories determine, so the optimum has ν at the prior mean:
        # start there rather than crawl along the curved E–ν valley.
        start_map["poisson"] = poisson_prior[0]
    nu0 = fixed.get("poisson", start_map.get("poisson", 0.45))
    values = (
        {}
        if isinstance(model, Model)
        else start_values(problem, setup.candidate, setup.ball, setup.fit_mask, nu0)
    )
    if isinstance(model, Model):
        values["poisson"] = (
            nu0 if ("poisson" in fixed or "poisson" in start_map) else as_float(setup.ball.poisson)
        )
    values.update(start_map)
    values.update({k: v for k, v in fixed.items() if k in setup.fittable})
    delay = (2.613 / (2 * math.pi * data.lowpass_Hz) if data.lowpass_Hz else 0.0) + 0.016 * float(
        np.nanmedian(problem.measured["contact_time_s"])
    )
    theta = lay.theta(setup.ball, setup.structure, data.onset_s - delay)
    for k, v in values.items():
        theta[lay.index(k)] = v
    auto_start = (
        warm is None
        and not isinstance(model, Model)
        and "youngs_Pa" not in start_map
        and "youngs_Pa" not in fixed
    )
    if warm is not None:
        if warm.model_name != setup.model_name or warm.theta.size != theta.size:
            raise ValueError(
                f"start: a FitResult of model {warm.model_name!r} ({warm.theta.size} "
                f"parameters) cannot start this {setup.model_name!r} fit ({theta.size})"
            )
        theta = warm.theta.copy()
        for k, v in fixed.items():
            if k in setup.fittable:
                theta[lay.index(k)] = v
    points = (
        [{}]
        if (warm is not None or isinstance(model, Model))
        else alternative_starts(setup.candidate, set(fixed) | set(start_map))
    )
    return StartPlan(theta, points, aligned=warm is not None, rescale_E=auto_start)


@dataclasses.dataclass(frozen=True, eq=False)
class Starts:
    """The starts of a fit (``points`` as in :class:`StartPlan`), aligned, with their
    evaluations (``outs``: residuals, Jacobian, force and features at each θ)."""

    points: list[dict]
    thetas: list[np.ndarray]
    outs: list[dict]


def evaluate_starts(setup: FitSetup, plan: StartPlan) -> Starts:
    """Every start evaluated, its onsets aligned with the records' (and E rescaled from the
    contact times where ``plan.rescale_E``) and evaluated again: all starts in one call each."""
    problem, lay, fit_mask, constants = setup.problem, setup.layout, setup.fit_mask, setup.constants
    free_none = np.zeros(len(lay.names), dtype=bool)
    thetas = []
    for alt in plan.points:
        th = plan.theta.copy()
        for k, v in alt.items():
            th[lay.index(k)] = v
        thetas.append(th)
    if not plan.aligned:
        outs = problem.run_batch(thetas, free_none, problem.weights(fit_mask), constants)
        thetas = [
            realign(
                problem,
                th,
                o["features"],
                np.ones(setup.data.n_records, bool),
                rescale_E=plan.rescale_E,
                fit_mask=fit_mask,
            )
            for th, o in zip(thetas, outs)
        ]
    outs = problem.run_batch(thetas, free_none, problem.weights(fit_mask, setup.extra), constants)
    return Starts(plan.points, thetas, outs)

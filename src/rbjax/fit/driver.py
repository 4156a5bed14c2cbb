"""Fitting the rubber's properties to measured blocked-force histories: the driver.

The paper's elastic model (Eqs. 1–10) with the literature values E = 1.6 MPa, ν = 0.5 (§4)
is too soft and too symmetric for measured pulses (§5: the measured contact is shorter and
rises faster than it falls). Here E, ν and the parameters of the model's terms are fitted to
force histories of several drop heights at once.

What is compared (the measuring chain is modelled, not inverted): for every record k the
model's floor force is sampled at the record's sample times shifted by an onset time s_k and
passed through the same causal 4th-order Butterworth low-pass as the data (JIS A 1418-2 / the
paper's §3 measuring chain: 1250 Hz for the shipped emulated recordings); see
:mod:`rbjax.fit.program` for the residuals and the compiled optimiser.

Parameters, their units, bounds and transforms come from the terms' declarations
(:mod:`rbjax.terms.parameters`): E = exp(φ), ν in (−1, 0.5] by a bounded map, damping parameters and
β = exp(φ) > 0, onset shifts free, optional drop-height errors |Δh_k| < 1 cm.

Identifiability: E and ν enter only through E/√(1−ν²) (see
:func:`rbjax.fit.uncertainty.identifiability`); this is detected from the Jacobian and said in
``FitResult.identifiability``; ν is then held at a stated value (default 0.5, the paper's, §4) or
given a prior.

The driver (on the host, between calls of the one compiled program of a
:class:`~rbjax.fit.problem.Problem`), one step each: the set-up (:mod:`~rbjax.fit.setup`), the
start values and the starts' onset alignment (:mod:`~rbjax.fit.start`), the identifiability
check and the free parameters (:mod:`~rbjax.fit.freedom`), rounds of Levenberg–Marquardt in
whitened coordinates until the remaining Gauss–Newton step is below 0.05 σ
(:mod:`~rbjax.fit.rounds`), the held-out records' alignment, the uncertainties
(:mod:`~rbjax.fit.estimates`), then the per-height table and the information criteria.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from .._progress import progress as say
from .._validate import check_choice
from .._x64 import require_x64
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.model import BLOCKED_FORCE_OPTIONS, GAS_OPTIONS, Model
from ..terms.parameters import replace
from .estimates import Estimates, estimates
from .freedom import Freedom, free_parameters, prior_row
from .options import FitOptions, options_or_default
from .physical import at_bounds, ball_mode_structure, series_structure
from .problem import STEPS_PER_ROUND, per_height_rows, realign
from .result import FitResult
from .rounds import MAX_ROUNDS, Rounds, optimise, pick_best
from .setup import FitSetup, set_up
from .start import Starts, evaluate_starts, start_plan


def fit(
    data,
    model: str | Model = "zener",
    *,
    blocked_force: str = "paper",
    gas: str = "adiabatic",
    ball: Ball = JIS_RUBBER_BALL,
    fix: Mapping[str, float] | None = None,
    start: Mapping[str, float] | FitResult | None = None,
    options: FitOptions | None = None,
    progress: bool = True,
) -> FitResult:
    """Fit E, ν and the parameters of ``model``'s terms to force histories of all records.

    The information criteria use the history residuals, AIC = N_eff ln(RSS/N) + 2p and
    BIC = N_eff ln(RSS/N) + p ln N_eff (p: free parameters incl. onsets), with the same
    N_eff = N/τ_noise for every model fitted to the same data (τ_noise: the integrated
    autocorrelation of the pre-contact noise), so that they are comparable across models.

    Args:
        data: a :class:`FitData`, Recording objects, or paths/a directory (see
            :func:`prepare_data`: per-height averages, 30 ms windows, measuring chain low-pass
            as declared).
        model: a model name (``paper`` (elastic, §2), ``kelvin-voigt``, ``hunt-crossley``,
            ``zener``, any registered damping law, each optionally ``+stiffening``) or an
            ``rbjax.Model``: every parameter of its damping laws and stiffening is fitted, its
            values are the start (with a name, the start comes from the records).
        blocked_force: for a model name: ``paper`` (F_B + F_G + F_d) or ``momentum`` (adds
            (M/2R)δ̇² in compression). A ``Model`` brings its own.
        gas: for a model name: ``adiabatic`` (Eq. 4, corrected) or ``none``. A ``Model``
            brings its own.
        ball: geometry and mass (R, h, M) and the starting E, ν for nothing else.
        fix: name → value of parameters held (E, ν, the terms' parameters, or R, h, M).
        start: name → start value, or a previous :class:`FitResult` of the same model and data
            (warm start).
        options: a :class:`~rbjax.fit.options.FitOptions` (default ``FitOptions()``): the
            optimiser and its step budget, the residual's scale, decimation and extra rows, the
            prediction's path and ``Solver``, ν held or given a prior, drop-height errors, the
            heights fitted, a shared structure (one compiled program).
        progress: print one line per optimiser round to stderr.

    Returns:
        The :class:`FitResult`: the fitted ball and model, each parameter's estimate and
        uncertainty, what the data determine, the per-height table, the information
        criteria and the measured and fitted records.

    Raises:
        RuntimeError: float64 was switched off after importing rbjax.
        ValueError: ``model`` is not a model name; ``blocked_force`` or ``gas`` is not an
            option; ``ball`` is not an ``rbjax.Ball``; ``fix`` names a parameter the model
            lacks or holds a value outside its range; ν is both fixed and given a prior;
            ``start`` names a parameter the model lacks, or is a :class:`FitResult` of
            another model or number of records; ``options`` is not a
            :class:`~rbjax.fit.options.FitOptions`;
            ``fit_heights`` names a height without records; the ``structure`` lacks a term
            of the model or has another gas.
        TypeError: ``model`` neither a str nor an ``rbjax.Model``; data
            that are neither paths nor recordings.
        DataError: the records cannot be prepared (see :func:`prepare_data`).
    """
    require_x64()
    options = options_or_default(options)
    _check_arguments(blocked_force=blocked_force, gas=gas, ball=ball)
    setup = set_up(
        data, model, blocked_force=blocked_force, gas=gas, ball=ball, fix=fix, options=options
    )
    plan = start_plan(setup, model, start)
    if setup.why_ode:
        say(f"{setup.label}: on the diffrax ODE ({setup.why_ode})", enabled=progress)
    starts = evaluate_starts(setup, plan)
    freedom = free_parameters(setup, starts, options.hold_poisson)
    optimum = _optimise(setup, starts, freedom, options, progress=progress)
    optimum = _align_held_out(setup, optimum)
    return _result(
        setup,
        freedom,
        optimum,
        estimates(setup, freedom, optimum.theta, optimum.out),
        options.optimizer,
    )


def _check_arguments(*, blocked_force, gas, ball) -> None:
    """The arguments of :func:`fit` that qualify a model name, and the ball, checked (its
    options are checked by :class:`~rbjax.fit.options.FitOptions`)."""
    check_choice("blocked_force", blocked_force, BLOCKED_FORCE_OPTIONS)
    check_choice("gas", gas, GAS_OPTIONS)
    if not isinstance(ball, Ball):
        raise ValueError(f"ball={ball!r} must be an rbjax.Ball")


@dataclasses.dataclass(frozen=True, eq=False)
class _Optimum:
    """The best start after the optimiser's rounds: its θ and evaluation ``out``, the optimiser
    steps it took, whether it converged and the message, how many starts converged, and the
    ν prior's row at the optimum."""

    theta: np.ndarray
    out: dict
    steps: int
    converged: bool
    message: str
    n_starts: int
    n_converged_starts: int
    prior: tuple[float, float, float]


def _optimise(
    setup: FitSetup, starts: Starts, freedom: Freedom, options: FitOptions, *, progress: bool
) -> _Optimum:
    """Every start optimised (ν in each as the identifiability check left it): rounds of LM
    in the whitened frame of each round's start; the best converged start is kept."""
    problem, lay, fit_mask = setup.problem, setup.layout, setup.fit_mask
    inu = lay.index("poisson")
    # ν now held at another value than the starts were evaluated at: evaluate them again
    nu_moved = any(th[inu] != freedom.nu for th in starts.thetas)
    thetas = [th.copy() for th in starts.thetas]
    for th in thetas:
        th[inu] = freedom.nu
    lanes = optimise(
        setup,
        thetas,
        starts.outs,
        freedom.free,
        freedom.free_idx,
        weights_of=lambda r: problem.weights(fit_mask, setup.extra, prior_row(setup, freedom, r)),
        reevaluate=nu_moved or setup.poisson_prior is not None,
        settings=Rounds(
            optimizer=options.optimizer,
            max_steps=options.steps_budget(STEPS_PER_ROUND * MAX_ROUNDS),
            progress=progress,
            label=setup.label,
            shown=tuple(freedom.physical_free),
        ),
    )
    best = pick_best(lanes)
    n_ok = sum(lane.converged for lane in lanes)
    message = best.message
    if len(lanes) > 1:
        origin = (
            ", ".join(f"{k}={v:g}" for k, v in starts.points[lanes.index(best)].items())
            or "the start values"
        )
        message += f"; {n_ok} of {len(lanes)} starts converged, the best from {origin}"
    return _Optimum(
        best.theta,
        best.out,
        best.steps,
        best.converged,
        message,
        len(lanes),
        n_ok,
        prior_row(setup, freedom, best.out["r"]),
    )


def _align_held_out(setup: FitSetup, optimum: _Optimum) -> _Optimum:
    """The held-out records' onsets aligned with the fitted model (nothing else is fitted to
    them) and the optimum evaluated again; the optimum itself where every record is fitted."""
    if np.all(setup.fit_mask):
        return optimum
    problem, lay = setup.problem, setup.layout
    theta = realign(
        problem,
        optimum.theta,
        optimum.out["features"],
        ~setup.fit_mask,
        rescale_E=False,
        fit_mask=setup.fit_mask,
    )
    weights = problem.weights(setup.fit_mask, setup.extra, optimum.prior)
    out = problem.run(theta, np.zeros(len(lay.names), dtype=bool), weights, setup.constants)
    return dataclasses.replace(optimum, theta=theta, out=out)


def _result(
    setup: FitSetup, freedom: Freedom, optimum: _Optimum, est: Estimates, optimizer: str
) -> FitResult:
    """The :class:`FitResult`: the fitted ball and model read in physical terms, the notes, the
    per-height table and the information criteria (a common N_eff for every candidate)."""
    problem, lay, theta, out = setup.problem, setup.layout, optimum.theta, optimum.out
    notes = (
        [f"Predicted on the diffrax ODE: {setup.why_ode}."] if setup.why_ode else []
    ) + freedom.notes
    ident = " ".join(notes) + " " + est.conditioning
    if freedom.ident_msg:
        ident += " " + freedom.ident_msg
    n_hist, p = est.residuals.size, freedom.free_idx.size
    n_eff = n_hist / problem.tau_noise
    rss = float(est.residuals @ est.residuals)
    loglik_term = n_eff * math.log(rss / n_hist) if rss > 0 and math.isfinite(rss) else float("nan")
    aic = loglik_term + 2 * p
    bic = loglik_term + p * math.log(n_eff)

    values = {n: float(theta[lay.index(n)]) for n in setup.fittable}
    _, fitted_ball, fitted_model = replace(values, 1.0, setup.ball, setup.candidate)
    physical_free = est.correlations[0]
    structures = (ball_mode_structure(fitted_ball, fitted_model), series_structure(fitted_model))
    reading = " ".join(
        x for x in (*structures, at_bounds({n: values[n] for n in physical_free})) if x
    )
    if reading:
        ident += " " + reading
    data = setup.data
    return FitResult(
        model_name=setup.model_name,
        blocked_force=setup.candidate.blocked_force,
        gas=setup.candidate.gas,
        ball=fitted_ball,
        model=fitted_model,
        parameters=est.parameters,
        correlations=est.correlations,
        identifiability=ident.strip(),
        per_height=tuple(per_height_rows(problem, out["force"], out["features"], setup.fit_mask)),
        residual_rms_N=problem.history_rms_N(out["force"], setup.fit_mask),
        converged=bool(optimum.converged),
        message=optimum.message,
        iterations=int(optimum.steps),
        optimizer=optimizer,
        n_eff_factor=float(est.tau),
        n_residuals=int(n_hist),
        n_free=int(p),
        aic=float(aic),
        bic=float(bic),
        time_s=data.time_s,
        measured_N=data.force_N,
        predicted_N=out["force"],
        heights_m=data.height_m,
        in_fit=setup.fit_mask,
        onset_shift_s=theta[lay.shift_slice].copy(),
        theta=theta,
        n_starts=optimum.n_starts,
        n_converged_starts=optimum.n_converged_starts,
    )

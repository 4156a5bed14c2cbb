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

Identifiability: E and ν enter only through E/√(1−ν²) (see :func:`rbjax.fit.uncertainty.identifiability`);
this is detected from the Jacobian and said in ``FitResult.identifiability``; ν is then held at
a stated value (default 0.5, the paper's, §4) or given a prior.

The driver (on the host, between calls of the one compiled program of a
:class:`~rbjax.fit.problem.Problem`): start values from the
records, onset alignment, the identifiability check, rounds of Levenberg–Marquardt in
whitened coordinates until the remaining Gauss–Newton step is below 0.05 σ, then the
uncertainties, the held-out records' alignment and the per-height table.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .._progress import progress as say
from .._validate import as_float, check_choice, check_range
from .._x64 import require_x64
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.model import GAS_OPTIONS, Model, Solver
from ..terms.parameters import replace
from . import uncertainty as unc
from .layout import CONSTANT_PARAMETERS, fitted_parameter_names
from .physical import at_bounds, ball_mode_structure
from .problem import (
    STEPS_PER_ROUND,
    Problem,
    candidate_model,
    embed,
    fit_path,
    fit_solver,
    per_height_rows,
    realign,
)
from .program import OPTIMIZERS
from .records import FitData, prepare_data
from .result import FitResult, ParameterEstimate
from .rounds import MAX_ROUNDS, alternative_starts, optimise, pick_best, start_values

SCALES = ("noise", "peak")
BLOCKED_FORCES = ("paper", "momentum")
EXTRA_TERMS = ("contact_time", "peak_force", "lfe")
#: Parameters that may be held at 0 (the ball mode off, μ = 0, or lossless, η = 0).
NON_NEGATIVE_FIX = ("mode_mass_ratio", "mode_loss_factor")


def validate_fix(names, fix):
    out = {}
    for k, v in (fix or {}).items():
        if k not in names:
            raise ValueError(f"fix: unknown parameter {k!r} for this model; valid: {', '.join(sorted(names))}")
        try:
            value = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"fix: {k}={v!r} is not a number") from None
        out[k] = value
    if "poisson" in out and not -1.0 < out["poisson"] <= 0.5:
        raise ValueError(f"fix: poisson={out['poisson']!r} is outside the valid range (-1, 0.5]")
    for k, v in out.items():
        if k in NON_NEGATIVE_FIX:
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"fix: {k}={v!r} must be non-negative and finite (valid range: [0, inf))")
        elif k != "poisson" and not (math.isfinite(v) and v > 0):
            raise ValueError(f"fix: {k}={v!r} must be positive and finite (valid range: (0, inf))")
    return out


def _height_mask(data: FitData, heights) -> np.ndarray:
    if heights is None:
        return np.ones(data.n_records, dtype=bool)
    wanted = np.atleast_1d(np.asarray(heights, dtype=float))
    mask = np.zeros(data.n_records, dtype=bool)
    for h in wanted:
        hit = np.isclose(data.height_m, h, atol=5e-4)
        if not hit.any():
            raise ValueError(f"fit_heights: no record at height {h:g} m; heights in the data: {', '.join(f'{x:g}' for x in data.heights_m)}")
        mask |= hit
    return mask


def fit(
    data,
    model: str | Model = "zener",
    *,
    blocked_force: str = "paper",
    gas: str = "adiabatic",
    ball: Ball = JIS_RUBBER_BALL,
    fix: Mapping[str, float] | None = None,
    start: Mapping[str, float] | FitResult | None = None,
    hold_poisson: float = 0.5,
    poisson_prior: tuple[float, float] | None = None,
    optimizer: str = "lm",
    fit_heights: Sequence[float] | None = None,
    height_error: bool = False,
    scale: str = "noise",
    decimate: int = 1,
    extra_weights: Mapping[str, float] | None = None,
    max_steps: int | None = None,
    progress: bool = True,
    solver: Solver | None = None,
    superset: Model | None = None,
    method: str = "auto",
) -> FitResult:
    """Fit E, ν and the parameters of ``model``'s terms to force histories of all records.

    Args:
        data: a :class:`FitData`, Recording objects, or paths/a directory (see
            :func:`prepare_data`: per-height averages, 30 ms windows, measuring chain low-pass
            as declared).
        model: a model name (``paper`` (elastic, §2), ``kelvin-voigt``, ``hunt-crossley``,
            ``zener``, any registered damping law, each optionally ``+stiffening``) or an
            ``rbjax.Model``: every parameter of its damping laws and stiffening is fitted, its
            values are the start (with a name, the start comes from the records).
        blocked_force, gas: for a model name: ``paper`` (F_B + F_G + F_d) or ``momentum``
            (adds (M/2R)δ̇² in compression); ``adiabatic`` (Eq. 4, corrected) or ``none``.
            A ``Model`` brings its own.
        ball: geometry and mass (R, h, M) and the starting E, ν for nothing else.
        fix: name → value of parameters held (E, ν, the terms' parameters, or R, h, M).
        start: name → start value, or a previous :class:`FitResult` of the same model and data
            (warm start).
        hold_poisson: value at which ν is held when the Jacobian shows E and ν are not
            separately identifiable (always, for this model: §2.1 Eqs. 1–3).
        poisson_prior: (mean, std) of a Gaussian prior on ν instead of holding it.
        optimizer: ``lm`` (optimistix Levenberg–Marquardt) or ``gauss-newton`` (optimistix).
        fit_heights: heights (m) whose records enter the fit (default all); the others are
            predicted (onset-aligned, nothing fitted to them) and reported as held out.
        height_error: also fit each record's drop-height error, bounded by ±1 cm.
        scale: residual of record k divided by its noise rms (``noise``) or peak (``peak``).
        decimate: use every n-th sample in the residual.
        extra_weights: {"contact_time": w, "peak_force": w, "lfe": w}: extra residual rows
            w·(relative error) for contact time and peak, w·(ΔL_FE in dB) per octave band.
        max_steps: optimiser steps in all (default 40 per round, at most 8 rounds; 0 evaluates
            the start only).
        progress: print one line per optimiser round to stderr.
        solver: an ``rbjax.Solver`` (forced to ``adjoint="forward"``): the prediction then runs
            on the diffrax ODE.
        method: ``auto`` (default: the force at the records' own samples by fixed steps,
            :mod:`rbjax.fit.record_forces`, where the model allows it; the diffrax ODE with its
            events for moving floors or when a ``solver`` is given, the reason in the notes),
            ``samples`` or ``ode`` (the reference).
        superset: a model containing every term of ``model`` (e.g.
            ``rbjax.terms.model.superset_model``): the fit runs in its compiled program with the
            terms ``model`` lacks held at their values, so fits of different models share one
            program (model selection does this).

    The information criteria use the history residuals, AIC = N_eff ln(RSS/N) + 2p and
    BIC = N_eff ln(RSS/N) + p ln N_eff (p: free parameters incl. onsets), with the same
    N_eff = N/τ_noise for every model fitted to the same data (τ_noise: the integrated
    autocorrelation of the pre-contact noise), so that they are comparable across models.
    """
    require_x64()
    check_choice("blocked_force", blocked_force, BLOCKED_FORCES)
    check_choice("gas", gas, GAS_OPTIONS)
    check_choice("optimizer", optimizer, OPTIMIZERS)
    check_choice("scale", scale, SCALES)
    if not isinstance(ball, Ball):
        raise ValueError(f"ball={ball!r} must be an rbjax.Ball")
    if not (isinstance(decimate, int) and decimate >= 1):
        raise ValueError(f"decimate={decimate!r} must be an integer >= 1")
    if not -1.0 < hold_poisson <= 0.5:
        raise ValueError(f"hold_poisson={hold_poisson!r} is outside the valid range (-1, 0.5]")
    if poisson_prior is not None:
        mean, std = (float(x) for x in poisson_prior)
        if not (-1.0 < mean < 0.5 and std > 0):
            raise ValueError(f"poisson_prior={poisson_prior!r}: need (mean, std) with -1 < mean < 0.5 and std > 0")
        poisson_prior = (mean, std)
    for k, weight in (extra_weights or {}).items():
        if k not in EXTRA_TERMS:
            raise ValueError(f"extra_weights: unknown term {k!r}; valid: {', '.join(EXTRA_TERMS)}")
        check_range(f"extra_weights[{k!r}]", weight, lower=0.0, lower_open=False)
    if max_steps is None:
        max_steps = STEPS_PER_ROUND * MAX_ROUNDS
    elif not (isinstance(max_steps, (int, np.integer)) and not isinstance(max_steps, bool) and max_steps >= 0):
        raise ValueError(f"max_steps={max_steps!r} is outside the valid range: an integer ≥ 0 (0: evaluate the start only)")
    model_name, candidate = candidate_model(model, blocked_force, gas)
    fittable = fitted_parameter_names(candidate)
    fixed = validate_fix(set(fittable) | set(CONSTANT_PARAMETERS[:3]), fix)
    if "poisson" in fixed and poisson_prior is not None:
        raise ValueError("poisson is both fixed and given a prior; choose one")
    data = prepare_data(data)
    ball = ball.replace(**{k: v for k, v in fixed.items() if k in CONSTANT_PARAMETERS})
    fit_mask = _height_mask(data, fit_heights)
    structure = embed(candidate, superset, ball)
    path, why_ode = fit_path(method, structure, solver)
    problem = Problem(data, ball, structure, fit_solver(solver), height_error=height_error, decimate=decimate, scale=scale, path=path,
                      feature_rows=any(w > 0 for w in (extra_weights or {}).values()))
    lay = problem.layout
    constants = lay.constant_values(ball, structure)

    warm = start if isinstance(start, FitResult) else None
    start_map = {} if isinstance(start, FitResult) else dict(start or {})
    for k in start_map:
        if k not in fittable:
            raise ValueError(f"start: unknown parameter {k!r} for model {model_name!r}; valid: {', '.join(fittable)}")
    if poisson_prior is not None and "poisson" not in start_map:
        # E/√(1−ν²) is all the histories determine, so the optimum has ν at the prior mean:
        # start there rather than crawl along the curved E–ν valley.
        start_map["poisson"] = poisson_prior[0]
    nu0 = fixed.get("poisson", start_map.get("poisson", 0.45))
    values = {} if isinstance(model, Model) else start_values(problem, candidate, ball, fit_mask, nu0)
    if isinstance(model, Model):
        values["poisson"] = nu0 if ("poisson" in fixed or "poisson" in start_map) else as_float(ball.poisson)
    values.update(start_map)
    values.update({k: v for k, v in fixed.items() if k in fittable})
    delay = (2.613 / (2 * math.pi * data.lowpass_Hz) if data.lowpass_Hz else 0.0) + 0.016 * float(np.nanmedian(problem.measured["contact_time_s"]))
    theta = lay.theta(ball, structure, data.onset_s - delay)
    for k, v in values.items():
        theta[lay.index(k)] = v
    auto_start = warm is None and not isinstance(model, Model) and "youngs_Pa" not in start_map and "youngs_Pa" not in fixed
    if warm is not None:
        if warm.model_name != model_name or warm.theta.size != theta.size:
            raise ValueError(f"start: a FitResult of model {model_name!r} cannot start this {model_name!r} fit")
        theta = warm.theta.copy()
        for k, v in fixed.items():
            if k in fittable:
                theta[lay.index(k)] = v
    label = f"fit {model_name}/{candidate.blocked_force}"
    if why_ode:
        say(f"{label}: on the diffrax ODE ({why_ode})", enabled=progress)
    free_none = np.zeros(len(lay.names), dtype=bool)

    def evaluate(th, mask=fit_mask, extra=None, prior=(0.0, 1.0, 0.0)):
        return problem.run(th, free_none, problem.weights(mask, extra, prior), constants)

    # 1. the starts (alternatives for parameters whose fit has several minima), each evaluated,
    # its onsets aligned (and E rescaled from the contact times): all starts in one call
    starts = [{}] if (warm is not None or isinstance(model, Model)) else alternative_starts(candidate, set(fixed) | set(start_map))
    thetas = []
    for alt in starts:
        th = theta.copy()
        for k, v in alt.items():
            th[lay.index(k)] = v
        thetas.append(th)
    extra = dict(extra_weights or {})
    if warm is None:  # a warm start's onsets are aligned already
        outs = problem.run_batch(thetas, free_none, problem.weights(fit_mask), constants)
        thetas = [realign(problem, th, o["features"], np.ones(data.n_records, bool), rescale_E=auto_start, fit_mask=fit_mask) for th, o in zip(thetas, outs)]
    outs = problem.run_batch(thetas, free_none, problem.weights(fit_mask, extra), constants)
    theta, out = thetas[0], outs[0]

    # 2. identifiability from the Jacobian with ν free
    physical_free = [n for n in fittable if n not in fixed]
    ie, inu = lay.index("youngs_Pa"), lay.index("poisson")
    shift_cols = list(np.arange(len(lay.names))[lay.shift_slice][fit_mask])
    cols = [lay.index(n) for n in fittable if n in physical_free or n in ("youngs_Pa", "poisson")] + shift_cols
    jac_hist = problem.history_jacobian(out["jac_theta"], fit_mask)
    ident_msg, nu_flagged, cos_e_nu = unc.identifiability(jac_hist, ie, inu, cols)
    prior_held = False
    notes = [f"Predicted on the diffrax ODE: {why_ode}."] if why_ode else []
    if "poisson" in physical_free and "youngs_Pa" not in physical_free:
        notes.append("E held as given; ν alone sets the stiffness and is fitted.")
    elif "poisson" in physical_free and poisson_prior is None:
        if nu_flagged:
            physical_free.remove("poisson")
            theta[inu] = hold_poisson
            notes.append(
                f"E and ν are not separately identifiable: their Jacobian columns are parallel "
                f"(|cos| = {cos_e_nu:.8f}); the data determine only E/√(1−ν²) (Reissner stiffness, "
                f"Eqs. 1–3; the gas force does not involve E or ν). ν is held at {hold_poisson:g}"
                + (" (the paper's value, §4; the bound of the model's range)" if hold_poisson == 0.5 else "")
                + " and effective_modulus_Pa = E/√(1−ν²) is the fitted quantity."
            )
        else:
            notes.append(f"E and ν: |cos| of their Jacobian columns {cos_e_nu:.6f}; both fitted.")
    elif "poisson" in physical_free and poisson_prior is not None:
        notes.append(
            f"E and ν are not separately identifiable from the histories (|cos| = {cos_e_nu:.8f}); "
            f"ν is determined by its prior N({poisson_prior[0]:g}, {poisson_prior[1]:g}²)."
        )
        if nu_flagged:
            # The histories fix only E/√(1−ν²), so the posterior mode has ν at the prior mean
            # exactly: optimise with ν held there (the curved E–ν valley is a trap for LM) and
            # fold the prior into the covariance afterwards.
            prior_held = True
            physical_free.remove("poisson")
            theta[inu] = poisson_prior[0]
    else:
        notes.append(f"ν held at {theta[inu]:g} as given; E/√(1−ν²) is what the data determine.")

    free_names = physical_free + [lay.names[i] for i in shift_cols]
    if height_error:
        free_names += [lay.names[i] for i in np.arange(len(lay.names))[lay.dh_slice][fit_mask]]
    free_idx = np.array([lay.index(n) for n in free_names], dtype=int)
    free = np.zeros(len(lay.names), dtype=bool)
    free[free_idx] = True

    def prior_row(r):
        # The history rows are not whitened (their scale is 1/peak or 1/noise, and the noise is
        # correlated), so the prior row is put in their units: one prior σ weighs as much as one
        # σ̂√τ of the history residuals (σ̂, τ taken at the start of a round).
        if poisson_prior is None or "poisson" not in physical_free:
            return (0.0, 1.0, 0.0)
        hist = problem.history_rows(r, fit_mask)
        unit = math.sqrt(unc.integrated_autocorrelation(hist) * float(np.sum(hist**2)) / max(hist.size, 1))
        return (poisson_prior[0], poisson_prior[1], unit)

    # 3. optimise every start: rounds of LM in the whitened frame of each round's start; the
    # best converged start is kept
    nu_moved = any(th[inu] != theta[inu] for th in thetas)  # ν now held at another value
    for th in thetas:
        th[inu] = theta[inu]
    lanes = optimise(
        problem, thetas, outs, free, free_idx, constants, fit_mask,
        weights_of=lambda r: problem.weights(fit_mask, extra, prior_row(r)), reevaluate=nu_moved or poisson_prior is not None,
        optimizer=optimizer, max_steps=max_steps, progress=progress, label=label,
        shown=[n for n in physical_free],
    )
    best = pick_best(lanes)
    theta, out, steps, converged, message = best.theta, best.out, best.steps, best.converged, best.message
    prior = prior_row(out["r"])
    if len(lanes) > 1:
        n_ok = sum(lane.converged for lane in lanes)
        origin = ", ".join(f"{k}={v:g}" for k, v in starts[lanes.index(best)].items()) or "the start values"
        message += f"; {n_ok} of {len(lanes)} starts converged, the best from {origin}"

    # 4. held-out records: align their onsets with the fitted model (nothing else is fitted)
    if not np.all(fit_mask):
        theta = realign(problem, theta, out["features"], ~fit_mask, rescale_E=False, fit_mask=fit_mask)
        out = evaluate(theta, extra=extra, prior=prior)

    # 5. uncertainties from the history rows at the optimum
    hist_r = problem.history_rows(out["r"], fit_mask)
    n_hist = hist_r.size
    tau = unc.integrated_autocorrelation(hist_r)
    hist_r = hist_r.reshape(-1)
    phi_hat = lay.to_phi(theta)
    dtheta = lay.from_phi(phi_hat)[1]
    jac_phi_hist = problem.history_jacobian(out["jac_theta"], fit_mask)[:, free_idx] * dtheta[free_idx][None, :]
    p = free_idx.size
    prior_index = free_names.index("poisson") if (poisson_prior is not None and "poisson" in physical_free) else None
    prior_precision = (dtheta[inu] / poisson_prior[1]) ** 2 if (poisson_prior is not None and prior_index is not None) else 0.0
    cov_phi = unc.covariance(jac_phi_hist, hist_r, tau, prior_index, prior_precision)
    if prior_held:
        free_names, physical_free, cov_phi = unc.fold_in_poisson_prior(
            free_names, physical_free, list(lay.physical), cov_phi, float(theta[inu]), poisson_prior, float(dtheta[inu])
        )
    std_phi = np.sqrt(np.clip(np.diag(cov_phi), 0, None))

    parameters = {}
    phys_idx = [free_names.index(n) for n in physical_free]
    for n in fittable:
        i = lay.index(n)
        spec = lay.specs[i]
        if n in physical_free:
            j = free_names.index(n)
            lo = float(spec.from_unconstrained(phi_hat[i] - 1.96 * std_phi[j]))
            hi = float(spec.from_unconstrained(phi_hat[i] + 1.96 * std_phi[j]))
            parameters[n] = ParameterEstimate(float(theta[i]), float(abs(dtheta[i]) * std_phi[j]), (lo, hi), spec.unit)
        else:
            parameters[n] = ParameterEstimate(float(theta[i]), 0.0, (float(theta[i]), float(theta[i])), spec.unit, fixed=True)
    nu = theta[inu]
    factor = 1.0 / math.sqrt(1.0 - nu**2)
    e_est = parameters["youngs_Pa"]
    e_eff = float(theta[ie] * factor)
    if "poisson" in physical_free:
        # delta method through E/√(1−ν²) with the (E, ν) covariance block
        je, jn = free_names.index("youngs_Pa"), free_names.index("poisson")
        grad = np.array([factor * dtheta[ie], theta[ie] * nu * factor**3 * dtheta[inu]])
        eff_std = float(math.sqrt(max(grad @ cov_phi[np.ix_([je, jn], [je, jn])] @ grad, 0.0)))
        eff_ci = (e_eff - 1.96 * eff_std, e_eff + 1.96 * eff_std)
    else:  # ν held: E/√(1−ν²) is E times a constant
        eff_std, eff_ci = e_est.std * factor, (e_est.ci95[0] * factor, e_est.ci95[1] * factor)
    parameters["effective_modulus_Pa"] = ParameterEstimate(e_eff, eff_std, eff_ci, "Pa", fixed=e_est.fixed and "poisson" not in physical_free)
    d_std = np.sqrt(np.clip(np.diag(cov_phi)[phys_idx], 1e-300, None))
    corr = np.clip(cov_phi[np.ix_(phys_idx, phys_idx)] / np.outer(d_std, d_std), -1.0, 1.0)

    ident = " ".join(notes) + " " + unc.conditioning_note(jac_phi_hist, free_names, physical_free, corr)
    if ident_msg:
        ident += " " + ident_msg

    # 6. per-height summary and information criteria (a common N_eff for every candidate)
    per_height = per_height_rows(problem, out["force"], out["features"], fit_mask)
    n_eff = n_hist / problem.tau_noise
    rss = float(hist_r @ hist_r)
    loglik_term = n_eff * math.log(rss / n_hist) if rss > 0 and math.isfinite(rss) else float("nan")
    aic = loglik_term + 2 * p
    bic = loglik_term + p * math.log(n_eff)

    values = {n: float(theta[lay.index(n)]) for n in fittable}
    _, fitted_ball, fitted_model = replace(values, 1.0, ball, candidate)
    reading = " ".join(x for x in (ball_mode_structure(fitted_ball, fitted_model), at_bounds({n: values[n] for n in physical_free})) if x)
    if reading:
        ident += " " + reading
    return FitResult(
        model_name=model_name,
        blocked_force=candidate.blocked_force,
        gas=candidate.gas,
        ball=fitted_ball,
        model=fitted_model,
        parameters=parameters,
        correlations=(tuple(physical_free), corr),
        identifiability=ident.strip(),
        per_height=tuple(per_height),
        residual_rms_N=problem.history_rms_N(out["force"], fit_mask),
        converged=bool(converged),
        message=message,
        iterations=int(steps),
        optimizer=optimizer,
        n_eff_factor=float(tau),
        n_residuals=int(n_hist),
        n_free=int(p),
        aic=float(aic),
        bic=float(bic),
        time_s=data.time_s,
        measured_N=data.force_N,
        predicted_N=out["force"],
        heights_m=data.height_m,
        in_fit=fit_mask,
        onset_shift_s=theta[lay.shift_slice].copy(),
        theta=theta,
        n_starts=len(lanes),
        n_converged_starts=sum(lane.converged for lane in lanes),
    )

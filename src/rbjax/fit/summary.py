"""Fitting a ball to summary figures (contact time, peak force, restitution, L_FE per band, per
drop height), what a calibration certificate or a paper gives instead of force histories.

Weighted least squares: the residual of figure j at height i is (model − measured)/σ_ij with σ
the table's uncertainty (:mod:`rbjax.fit.summary_table`), minimised over the unconstrained
coordinates φ of the free parameters (the same parameter layer and transforms as the history
fit, :mod:`rbjax.fit.layout`) by ``scipy.optimize.least_squares`` (trust-region reflective)
with the exact Jacobian (``jax.jacfwd`` through the fast exact paths,
:mod:`rbjax.fit.summary_model`).

Uncertainty: C_φ = (JᵀJ)⁻¹ of the whitened Jacobian (the stated σ are the uncertainties),
inflated by χ²/(N − p) where the misfit exceeds them (the Birge ratio); standard deviations by
the delta method, 95 % intervals through the transform. Identifiability as for histories: E and
ν enter only through E/√(1−ν²) (Eqs. 1–3), so ν is held (default 0.5, §4) and
``effective_modulus_Pa`` is reported; a parameter the figures do not pin down (its column of
the scaled Jacobian dependent on the others, condition > :data:`CONDITION_LIMIT`, or a
damping coefficient run to 0) is held at its value and the result says so. More free
parameters than figures is an error naming the table.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence

import numpy as np

from .._progress import progress as say
from .._validate import as_float, check_choice
from ..solve.outcome import G_N_PER_KG
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.forces import reissner_stiffness_N_per_m
from ..terms.model import BLOCKED_FORCE_OPTIONS, GAS_OPTIONS
from ..terms.parameters import replace
from .layout import CONSTANT_PARAMETERS, fit_declaration, fitted_parameter_names
from .problem import candidate_model
from .result import ParameterEstimate
from .setup import validate_fix
from .summary_model import FigureProgram
from .summary_result import SummaryFitResult
from .summary_table import SummaryTable, SummaryTableError, read_summary

#: A parameter is held when the column-scaled Jacobian's condition number exceeds this.
CONDITION_LIMIT = 1e7
#: Optimiser tolerances (relative change of the cost and of φ).
TOLERANCE = 1e-10


def as_table(table) -> SummaryTable:
    return table if isinstance(table, SummaryTable) else read_summary(table)


def _entry_mask(table: SummaryTable, held_out) -> np.ndarray:
    """(heights, figures) bool: the measured figures that enter the fit."""
    figures = table.figures
    mask = np.stack([np.isfinite(table.values[f]) for f in figures], axis=-1)
    for h, f in held_out or ():
        hits = np.flatnonzero(np.isclose(table.heights_m, float(h), atol=5e-4))
        if f not in figures or hits.size == 0 or not mask[hits[0], figures.index(f)]:
            raise ValueError(
                f"held_out: ({h!r}, {f!r}) is not a figure of {table.source}; it has "
                f"{', '.join(figures)} at {', '.join(f'{x:g}' for x in table.heights_m)} m"
            )
        mask[hits[0], figures.index(f)] = False
    return mask


def start_values(table: SummaryTable, model, ball: Ball, nu: float) -> dict:
    """Start values from the figures: E from the contact time of the lowest height (a linear
    spring, t_c ≈ π√(M/k); else from the peak force, F ≈ v0√(kM); else the ball's), k → E by
    Eqs. 1–3; each term's ``start`` rule from the restitution (median, else 0.85)."""

    mass = as_float(ball.mass_kg)
    v0 = np.sqrt(2 * G_N_PER_KG * table.heights_m)
    values = table.values
    k = None
    if "contact_time_s" in values and np.any(np.isfinite(values["contact_time_s"])):
        i = int(np.flatnonzero(np.isfinite(values["contact_time_s"]))[0])
        tc = float(values["contact_time_s"][i])
        k = mass * (math.pi / tc) ** 2
    elif "peak_force_N" in values and np.any(np.isfinite(values["peak_force_N"])):
        i = int(np.flatnonzero(np.isfinite(values["peak_force_N"]))[0])
        k = (float(values["peak_force_N"][i]) / v0[i]) ** 2 / mass
    e_young = (
        as_float(ball.youngs_Pa)
        if k is None
        else k
        * as_float(ball.radius_m)
        * math.sqrt(3 * (1 - nu**2))
        / (4 * as_float(ball.wall_m) ** 2)
    )
    tc = math.pi * math.sqrt(mass / k) if k else 0.02
    e = float(np.nanmedian(values["restitution"])) if "restitution" in values else 0.85
    e = min(max(e, 0.05), 0.99)
    out = {"youngs_Pa": e_young, "poisson": nu}
    k_shell = float(
        reissner_stiffness_N_per_m(ball.replace(youngs_Pa=e_young, poisson=min(nu, 0.4999)))
    )
    speed = float(np.median(v0))
    out.update(model.term_starts(k_shell, mass, e, tc, speed))
    if model.stiffening is not None:
        out["beta"] = 0.05
    return out


def _solve(program: FigureProgram, phi0, measured, sd, mask):
    # lazy: scipy.optimize costs 0.3–0.8 s at import
    from scipy.optimize import least_squares

    def residual(phi):
        return ((program.value(phi) - measured) / sd)[mask]

    def jacobian(phi):
        return (program.value_and_jacobian(phi)[1] / sd[..., None])[mask]

    if len(phi0) == 0:
        return np.asarray(phi0, float), residual(phi0), True, "nothing free"
    r0 = residual(phi0)
    if not np.all(np.isfinite(r0)):
        raise RuntimeError(
            f"the model's figures at the start values are not finite ({program.names} = {phi0}); "
            "give start values"
        )
    sol = least_squares(
        residual,
        phi0,
        jac=jacobian,
        method="trf",
        x_scale="jac",
        ftol=TOLERANCE,
        xtol=TOLERANCE,
        gtol=TOLERANCE,
        max_nfev=200,
    )
    ok = bool(sol.success) and np.all(np.isfinite(sol.fun))
    return sol.x, sol.fun, ok, str(sol.message)


def fit_summary(
    table,
    model="paper",
    *,
    blocked_force: str = "paper",
    gas: str = "adiabatic",
    ball: Ball = JIS_RUBBER_BALL,
    fix: Mapping[str, float] | None = None,
    start: Mapping[str, float] | None = None,
    hold_poisson: float = 0.5,
    held_out: Sequence[tuple[float, str]] = (),
    progress: bool = False,
) -> SummaryFitResult:
    """Fit E (ν held: only E/√(1−ν²) is determined) and the parameters of ``model``'s terms to
    summary figures by weighted least squares.

    Args:
        table: a :class:`SummaryTable` or the path of a ``.csv`` / ``.toml`` table.
        model: a model name (``paper``, ``kelvin-voigt``, ``hunt-crossley``, ``zener``, …,
            ``+stiffening``, ``+ball-mode``; :func:`rbjax.fit.all_model_names`) or an
            ``rbjax.Model`` (its values are the start).
        blocked_force: the model name's blocked force (as :func:`rbjax.fit.fit`).
        gas: the model name's gas law (as :func:`rbjax.fit.fit`).
        ball: geometry and mass (R, h, M; held) and the starting E.
        fix: name → value of parameters held (E, ν, the terms' parameters, R, h, M).
        start: name → start value of free parameters.
        hold_poisson: ν where it is not fixed (it is never separately identifiable).
        held_out: (height_m, figure) pairs of the table left out of the fit and predicted.
        progress: one line on stderr when done.

    Returns:
        A :class:`~rbjax.fit.summary_result.SummaryFitResult`: the fitted ball and model, each
        parameter with its standard deviation, each figure fitted and predicted, χ².

    Raises:
        ValueError: an option outside its range, an unknown parameter in ``fix`` or
            ``start`` (the message names it and lists the valid ones).
        SummaryTableError: a table that cannot be read, or fewer figures than free parameters.
    """
    t0 = time.perf_counter()
    table = as_table(table)
    check_choice("blocked_force", blocked_force, BLOCKED_FORCE_OPTIONS)
    check_choice("gas", gas, GAS_OPTIONS)
    if not -1.0 < hold_poisson <= 0.5:
        raise ValueError(f"hold_poisson={hold_poisson!r} is outside the valid range (-1, 0.5]")
    model_name, candidate = candidate_model(model, blocked_force, gas)
    fittable = fitted_parameter_names(candidate)
    fixed = validate_fix(set(fittable) | set(CONSTANT_PARAMETERS[:3]), fix)
    ball = ball.replace(**{k: v for k, v in fixed.items() if k in CONSTANT_PARAMETERS})
    nu = fixed.get("poisson", hold_poisson)
    values = (
        start_values(table, candidate, ball, nu)
        if not hasattr(model, "damping")
        else {"youngs_Pa": as_float(ball.youngs_Pa), "poisson": nu}
    )
    for k, v in (start or {}).items():
        if k not in fittable:
            raise ValueError(
                f"start: unknown parameter {k!r} for model {model_name!r}; valid: "
                f"{', '.join(fittable)}"
            )
        values[k] = float(v)
    values.update({k: v for k, v in fixed.items() if k in fittable})
    values = {k: v for k, v in values.items() if k in fittable}
    _, ball, candidate = replace(values, 1.0, ball, candidate)

    mask = _entry_mask(table, held_out)
    n_fit = int(mask.sum())
    free = [n for n in fittable if n not in fixed and n != "poisson"]
    if len(free) > n_fit:
        raise SummaryTableError(
            f"{table.source}: {n_fit} figures in the fit cannot determine {len(free)} parameters "
            f"of model {model_name!r} ({', '.join(free)}); hold some (fix=, --fix NAME=VALUE) or "
            "give more figures"
        )
    notes = list(table.notes)
    notes.append(
        f"ν held at {nu:g}"
        + (" as given" if "poisson" in fixed else (" (the paper's value, §4)" if nu == 0.5 else ""))
        + ": the figures, like histories, determine only E/√(1−ν²) (Reissner stiffness, Eqs. "
        "1–3; the gas force does not involve E or ν)."
    )
    specs_all = {n: fit_declaration(n, ball, candidate) for n in fittable}
    figures = table.figures
    measured = np.stack([table.values[f] for f in figures], axis=-1)
    sd = np.stack([table.sd[f] for f in figures], axis=-1)
    held: dict[str, str] = {}
    widened = False
    for _attempt in range(len(free) + 2):
        specs = [specs_all[n] for n in free]
        phi0 = np.array([float(s.to_unconstrained(values[n])) for n, s in zip(free, specs)])
        _, ball_now, model_now = replace(values, 1.0, ball, candidate)
        program = FigureProgram(table.heights_m, ball_now, model_now, free, specs, figures)
        phi, r, ok, message = _solve(program, phi0, measured, sd, mask)
        values.update({n: float(s.from_unconstrained(p)) for n, s, p in zip(free, specs, phi)})
        value, jac = program.value_and_jacobian(phi)
        if not np.all(np.isfinite(value[mask])):
            if program.num_samples and not widened:
                widened = (
                    True  # a contact outlasted the L_FE window: rebuild it from the fitted model
                )
                continue
            raise RuntimeError(
                f"summary fit of {model_name!r}: the fitted model's figures are not finite (a "
                f"failed solve) at {values}"
            )
        jw = (jac / sd[..., None])[mask]
        drop = _undetermined(jw, free, specs, phi)
        if not drop:
            break
        for n, why in drop.items():
            held[n] = why
            free.remove(n)
    _, fitted_ball, fitted_model = replace(values, 1.0, ball, candidate)
    for n, why in held.items():
        notes.append(
            f"{n} is not pinned down by these figures ({why}); held at {values[n]:.4g} "
            f"{specs_all[n].unit}."
        )

    chi2 = float(r @ r)
    dof = n_fit - len(free)
    birge = max(1.0, chi2 / dof) if dof > 0 else 1.0
    cov_phi = np.linalg.pinv(jw.T @ jw, hermitian=True) * birge if free else np.zeros((0, 0))
    if birge > 1.0:
        notes.append(
            f"χ²/(N − p) = {chi2 / dof:.3g} > 1: the model misses the figures by more than their "
            "uncertainties; the covariance is scaled by it."
        )
    elif dof == 0 and free:
        notes.append(
            "As many free parameters as figures: the fit passes through them, and the "
            "uncertainties are those of the figures alone."
        )
    std_phi = np.sqrt(np.clip(np.diag(cov_phi), 0.0, None))
    parameters = {}
    for n in fittable:
        spec = specs_all[n]
        v = values[n]
        if n in free:
            j = free.index(n)
            p = phi[j]
            lo, hi = (float(spec.from_unconstrained(p + s * 1.96 * std_phi[j])) for s in (-1, 1))
            parameters[n] = ParameterEstimate(
                v, float(abs(spec.slope(p)) * std_phi[j]), (lo, hi), spec.unit
            )
        else:
            parameters[n] = ParameterEstimate(v, 0.0, (v, v), spec.unit, fixed=True)
    factor = 1.0 / math.sqrt(1.0 - nu**2)
    e = parameters["youngs_Pa"]
    parameters["effective_modulus_Pa"] = ParameterEstimate(
        e.value * factor,
        e.std * factor,
        (e.ci95[0] * factor, e.ci95[1] * factor),
        "Pa",
        fixed=e.fixed,
    )
    d = np.sqrt(np.maximum(np.diag(cov_phi), 1e-300))
    corr = np.clip(cov_phi / np.outer(d, d), -1.0, 1.0) if free else np.zeros((0, 0))
    if len(free) > 1:
        c = np.abs(corr - np.eye(len(free)))
        a, b = (int(x) for x in np.unravel_index(np.argmax(c), c.shape))
        notes.append(f"Largest correlation {corr[a, b]:+.3f} ({free[a]}–{free[b]}).")
    # prediction uncertainty of every figure (delta method in φ)
    pred_sd = (
        np.sqrt(np.maximum(np.einsum("hfp,pq,hfq->hf", jac, cov_phi, jac), 0.0))
        if free
        else np.zeros_like(value)
    )
    rows = []
    for i, h in enumerate(table.heights_m):
        for j, f in enumerate(figures):
            if np.isfinite(measured[i, j]):
                rows.append(
                    {
                        "height_m": float(h),
                        "figure": f,
                        "measured": float(measured[i, j]),
                        "sd": float(sd[i, j]),
                        "fitted": float(value[i, j]),
                        "fitted_sd": float(pred_sd[i, j]),
                        "normalised_error": float((value[i, j] - measured[i, j]) / sd[i, j]),
                        "in_fit": bool(mask[i, j]),
                    }
                )
    elapsed = time.perf_counter() - t0
    say(
        f"fit_summary {model_name}: χ² = {chi2:.3g} on {n_fit} figures, {len(free)} free "
        f"({elapsed:.1f} s)",
        enabled=progress,
    )
    return SummaryFitResult(
        model_name=model_name,
        blocked_force=candidate.blocked_force,
        gas=candidate.gas,
        ball=fitted_ball,
        model=fitted_model,
        parameters=parameters,
        correlations=(tuple(free), corr),
        identifiability=" ".join(notes),
        rows=tuple(rows),
        chi2=chi2,
        n_figures=n_fit,
        n_free=len(free),
        converged=ok,
        message=message,
        source=table.source,
        heights_m=table.heights_m.copy(),
        figures=figures,
        time_s=elapsed,
    )


def _undetermined(jw, free, specs, phi) -> dict[str, str]:
    """Free parameters the figures do not pin down, with the reason: a damping or mode
    coefficient run to its bound 0 (its column vanishes), or the last pivot of a column-scaled
    Jacobian whose condition number exceeds ``CONDITION_LIMIT``."""
    # lazy: scipy.linalg costs 0.3 s at import
    import scipy.linalg

    if not free:
        return {}
    norms = np.linalg.norm(jw, axis=0)
    out = {}
    for j, (n, s) in enumerate(zip(free, specs)):
        if (
            s.lower == 0.0
            and not s.lower_open
            and float(s.from_unconstrained(phi[j]))
            < 1e-9 * max(1.0, abs(float(s.from_unconstrained(phi[j] + 1.0))))
        ):
            out[n] = "it ran to its bound 0: the figures ask for none of it"
    if out:
        return out
    if len(free) < 2:
        return {}
    _, r, piv = scipy.linalg.qr(jw / np.maximum(norms, 1e-300), pivoting=True, mode="economic")
    d = np.abs(np.diag(r))
    if d[-1] * CONDITION_LIMIT < d[0]:
        return {
            free[piv[-1]]: (
                "its Jacobian column depends on the others: condition number "
                f"{d[0] / max(d[-1], 1e-300):.2g}"
            )
        }
    return {}

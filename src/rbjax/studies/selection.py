"""Choosing the impact model the force histories support: cross-validation over drop heights.

Each candidate (damping model × blocked-force definition, see :mod:`rbjax.fit`) is fitted to
all heights, then refitted once per height with that height left out and asked to predict it
(leave-one-height-out cross-validation; the held-out record's onset is aligned with the
prediction's, nothing else is fitted to it). The held-out error of a candidate is the rms of
predicted − measured force over the held-out record, in % of its measured peak, averaged
over the folds; its contact time, peak force and octave-band L_FE errors (paper Eq. 11) are
reported too. AIC/BIC of the full fits are given alongside (see :func:`rbjax.fit.fit`).

Rule (a paired one-standard-error rule): let B be the candidate with the smallest mean
held-out error. A candidate is "within the noise of B" when its mean fold-by-fold excess
over B is no larger than the standard error of that excess (std of the paired differences
over the folds / √folds). The recommended model is the candidate within the noise of B with
the fewest fitted physical parameters (ties: the smaller held-out error).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence

import numpy as np

from .._progress import progress as say
from .._validate import check_choice
from .._x64 import require_x64
from ..fit import (
    MODEL_NAMES,
    FitResult,
    fit,
    parse_model_name,
    parse_model_terms,
    predict,
    prepare_data,
)
from ..fit.options import OLD_KEYWORDS, options_from_keywords
from ..spectrum.bands import OCTAVE_BANDS
from ..terms.model import BLOCKED_FORCE_OPTIONS, Model, superset_model
from ..text import fmt, format_table
from .executors import Parallel, Task, run_tasks

__all__ = [
    "HeldOut",
    "Candidate",
    "Selection",
    "HoldOutComparison",
    "cross_validate",
    "select_model",
    "held_out_comparison",
    "BLOCKED_FORCES",
    "candidate_pairs",
    "recommend",
]

BLOCKED_FORCES = BLOCKED_FORCE_OPTIONS  # one definition: rbjax.terms.model
RULE = (
    "paired one-standard-error rule on the leave-one-height-out history error: among the "
    "candidates whose mean fold-by-fold excess error over the best candidate is at most the "
    "standard error of that excess, take the one with the fewest fitted physical parameters "
    "(ties: smaller held-out error)"
)


@dataclasses.dataclass(frozen=True)
class HeldOut:
    """Errors of the prediction of one held-out height (predicted − measured)."""

    height_m: float
    history_error_pct: float
    contact_time_pct: float
    peak_force_pct: float
    lfe_octave_dB: tuple
    converged: bool = True

    def to_dict(self) -> dict:
        return dataclasses.asdict(self) | {"lfe_octave_dB": list(self.lfe_octave_dB)}


def held_out_rows(result, heights) -> list[HeldOut]:
    """Held-out errors at ``heights`` from a FitResult or a Prediction."""
    rows = []
    for h in heights:
        k = np.isclose(result.heights_m, h, atol=5e-4)
        row = next(r for r in result.per_height if abs(r["height_m"] - h) < 5e-4)
        rms = float(np.sqrt(np.mean((result.predicted_N[k] - result.measured_N[k]) ** 2)))
        peak = float(np.mean(np.max(result.measured_N[k], axis=1)))
        rows.append(
            HeldOut(
                height_m=float(h),
                history_error_pct=100.0 * rms / peak,
                contact_time_pct=row["error"]["contact_time_pct"],
                peak_force_pct=row["error"]["peak_force_pct"],
                lfe_octave_dB=tuple(float(x) for x in row["error"]["lfe_octave_dB"]),
                converged=result.converged,
            )
        )
    return rows


def fit_task(data, model, blocked_force, fit_heights, start, fit_kwargs) -> FitResult:
    """One fit of a selection as a task of its own (a module-level function, so that a worker
    process or a Dask worker can run it): :func:`rbjax.fit.fit` without progress lines, its
    ``options`` (in ``fit_kwargs``) with ``fit_heights`` and the ``superset`` of ``fit_kwargs``."""
    kwargs = dict(fit_kwargs)
    superset = kwargs.pop("superset", None)
    old = {k: kwargs.pop(k) for k in list(kwargs) if k in OLD_KEYWORDS}  # deprecated keywords
    options = options_from_keywords("select_model", kwargs.pop("options", None), old)
    options = options.replace(fit_heights=fit_heights, superset=superset)
    return fit(
        data,
        model,
        blocked_force=blocked_force,
        start=start,
        options=options,
        progress=False,
        **kwargs,
    )


def _without(data, height_m: float) -> list[float]:
    return [x for x in data.heights_m if abs(x - height_m) > 5e-4]


def _fold_tasks(data, model, blocked_force, base: FitResult, heights, fit_kwargs, cost=1.0):
    """The leave-one-height-out refits of one candidate, warm-started from ``base``, one task a
    fold (the base fit's evaluations times ``cost`` estimate each fold's work)."""
    return [
        Task(
            f"{model}/{blocked_force} without {h:g} m",
            fit_task,
            (data, model, blocked_force, _without(data, h), base, fit_kwargs),
            cost=cost * max(base.iterations, 1),
        )
        for h in heights
    ]


def _fold_row(model, blocked_force, h, res: FitResult, progress: bool) -> HeldOut:
    row = held_out_rows(res, [h])[0]
    say(
        f"cv {model}/{blocked_force}: without {h:g} m: held-out error "
        f"{row.history_error_pct:.2f} % of peak ({res.iterations} evaluations)",
        enabled=progress,
    )
    return row


def _check_folds(data) -> None:
    if len(data.heights_m) < 2:
        raise ValueError(
            f"cross-validation needs at least 2 drop heights; the data have {len(data.heights_m)}"
        )


def cross_validate(
    data,
    model: str,
    *,
    blocked_force: str = "paper",
    base: FitResult | None = None,
    heights: Sequence[float] | None = None,
    workers: int | Parallel | None = 1,
    progress: bool = True,
    **fit_kwargs,
) -> tuple[HeldOut, ...]:
    """Leave-one-height-out: refit without each height (warm start from ``base``), predict it.

    The folds are independent tasks, run where ``workers`` says.

    Args:
        data: a :class:`~rbjax.fit.FitData`, recordings or paths (see
            :func:`rbjax.fit.prepare_data`).
        model: the model name (:mod:`rbjax.fit`).
        blocked_force: the blocked-force definition, ``"paper"`` or ``"momentum"``.
        base: the full fit the folds start from (default: fitted here to every height, with
            ``fit_kwargs``).
        heights: the heights held out in turn, m (default: every height in the data).
        workers: where the folds run: 1 (default: in this process), a worker count, ``None``
            (every usable core) or a :class:`~rbjax.studies.executors.Parallel`.
        progress: one line per fold on stderr.
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        One :class:`HeldOut` per held-out height, a tuple in the order of ``heights``.

    Raises:
        ValueError: data with fewer than two drop heights, a held-out height that is not one
            of the data's, or data that cannot be prepared (``rbjax.data.DataError``).
        rbjax.studies.executors.TaskError: a fold's fit failed (named).
    """
    data = prepare_data(data)
    _check_folds(data)
    folds = data.heights_m if heights is None else np.atleast_1d(np.asarray(heights, dtype=float))
    absent = [float(h) for h in folds if not np.any(np.isclose(data.heights_m, h, atol=5e-4))]
    if absent:
        raise ValueError(
            f"heights={absent} m are not drop heights of the data; valid: "
            f"{[float(h) for h in data.heights_m]} m"
        )
    if base is None:
        base = fit(data, model, blocked_force=blocked_force, progress=False, **fit_kwargs)
    tasks = _fold_tasks(data, model, blocked_force, base, folds, fit_kwargs)
    results = run_tasks(workers, tasks, label=f"cv {model}/{blocked_force}")
    return tuple(
        _fold_row(model, blocked_force, h, res, progress) for h, res in zip(folds, results)
    )


@dataclasses.dataclass(frozen=True, eq=False)
class Candidate:
    """One candidate model: its full fit and its cross-validated (held-out) errors.

    Attributes:
        model_name: the model name (:mod:`rbjax.fit`).
        blocked_force: its blocked-force definition, ``"paper"`` or ``"momentum"``.
        fit: its full fit to every height (:class:`~rbjax.fit.FitResult`).
        folds: its :class:`HeldOut` errors, one per height left out.
    """

    model_name: str
    blocked_force: str
    fit: FitResult
    folds: tuple

    @property
    def label(self) -> str:
        return f"{self.model_name}/{self.blocked_force}"

    @property
    def n_physical(self) -> int:
        """Fitted physical parameters (E and the damping/stiffening ones; ν is held)."""
        return len(self.fit.correlations[0])

    @property
    def fold_errors_pct(self) -> np.ndarray:
        return np.array([f.history_error_pct for f in self.folds])

    @property
    def cv_error_pct(self) -> float:
        return float(np.mean(self.fold_errors_pct))

    @property
    def cv_se_pct(self) -> float:
        e = self.fold_errors_pct
        return float(np.std(e, ddof=1) / math.sqrt(e.size)) if e.size > 1 else float("nan")

    def mean_abs(self, name: str):
        values = np.array([getattr(f, name) for f in self.folds], dtype=float)
        return np.mean(np.abs(values), axis=0)

    def to_dict(self) -> dict:
        return {
            "model_name": self.model_name,
            "blocked_force": self.blocked_force,
            "n_physical": self.n_physical,
            "converged": self.fit.converged,
            "residual_rms_N": self.fit.residual_rms_N,
            "aic": self.fit.aic,
            "bic": self.fit.bic,
            "cv_history_error_pct": self.cv_error_pct,
            "cv_history_error_se_pct": self.cv_se_pct,
            "cv_mean_abs_contact_time_pct": float(self.mean_abs("contact_time_pct")),
            "cv_mean_abs_peak_force_pct": float(self.mean_abs("peak_force_pct")),
            "cv_mean_abs_lfe_octave_dB": self.mean_abs("lfe_octave_dB").tolist(),
            "parameters": {k: v.to_dict() for k, v in self.fit.parameters.items()},
            "folds": [f.to_dict() for f in self.folds],
        }


@dataclasses.dataclass(frozen=True, eq=False)
class Selection:
    """The outcome of :func:`select_model`.

    Attributes:
        candidates: every :class:`Candidate`, in the order they were tried.
        recommended: the :class:`Candidate` the rule recommends.
        within_noise: the candidates within the noise of the best (:func:`recommend`).
        rule: the rule, in words.
        blocked_force_note: what the held-out errors say about the blocked-force definition
            of the recommended model.
        baseline: the unfitted paper model's :class:`HeldOut` errors at every height.
        elapsed_s: how long the selection took, s.
    """

    candidates: tuple
    recommended: Candidate
    within_noise: tuple
    rule: str
    blocked_force_note: str
    baseline: tuple
    elapsed_s: float

    def table(self) -> str:

        header = [
            "model",
            "blocked force",
            "p",
            "conv",
            "rms (N)",
            "CV err (%)",
            "± SE",
            "|Δt_c| (%)",
            "|Δpeak| (%)",
        ]
        header += [f"|ΔL| {b}" for b in OCTAVE_BANDS] + ["AIC", "BIC", ""]
        rows = []
        for c in self.candidates:
            mark = (
                "recommended"
                if c is self.recommended
                else ("within noise" if c in self.within_noise else "")
            )
            rows.append(
                [
                    c.model_name,
                    c.blocked_force,
                    str(c.n_physical),
                    "yes" if c.fit.converged else "no",
                    fmt(c.fit.residual_rms_N, ".1f"),
                    fmt(c.cv_error_pct, ".2f"),
                    fmt(c.cv_se_pct, ".2f"),
                    fmt(c.mean_abs("contact_time_pct"), ".2f"),
                    fmt(c.mean_abs("peak_force_pct"), ".2f"),
                ]
                + [fmt(x, ".2f") for x in c.mean_abs("lfe_octave_dB")]
                + [fmt(c.fit.aic, ".0f"), fmt(c.fit.bic, ".0f"), mark]
            )
        base = self.baseline
        rows.append(
            [
                "paper (unfitted)",
                "paper",
                "0",
                "—",
                "—",
                fmt(np.mean([b.history_error_pct for b in base]), ".2f"),
                "—",
                fmt(np.mean([abs(b.contact_time_pct) for b in base]), ".2f"),
                fmt(np.mean([abs(b.peak_force_pct) for b in base]), ".2f"),
            ]
            + [fmt(x, ".2f") for x in np.mean([np.abs(b.lfe_octave_dB) for b in base], axis=0)]
            + ["—", "—", "JIS ball, E = 1.6 MPa"]
        )
        lines = [
            format_table(header, rows),
            "",
            f"held-out errors: leave-one-height-out over {len(self.recommended.folds)} heights "
            "(|Δ|: mean over the folds).",
            f"rule: {self.rule}.",
            f"recommended: {self.recommended.label}.",
            self.blocked_force_note,
            f"selection took {self.elapsed_s:.0f} s.",
        ]
        return "\n".join(lines)

    def to_dict(self) -> dict:

        return {
            "recommended": {
                "model_name": self.recommended.model_name,
                "blocked_force": self.recommended.blocked_force,
            },
            "within_noise": [c.label for c in self.within_noise],
            "rule": self.rule,
            "blocked_force_note": self.blocked_force_note,
            "octave_bands_Hz": list(OCTAVE_BANDS),
            "candidates": [c.to_dict() for c in self.candidates],
            "baseline_paper_unfitted": [b.to_dict() for b in self.baseline],
            "elapsed_s": self.elapsed_s,
        }


def _paired(a: Candidate, b: Candidate) -> tuple[float, float]:
    d = a.fold_errors_pct - b.fold_errors_pct
    se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else float("inf")
    return float(np.mean(d)), se


def recommend(candidates: Sequence[Candidate]) -> tuple[Candidate, tuple]:
    """(recommended, candidates within the noise of the best) by the rule in :data:`RULE`.

    Args:
        candidates: the cross-validated :class:`Candidate` objects; those with a non-finite
            held-out error are left out.

    Returns:
        ``(recommended, within)``: the recommended :class:`Candidate` and the tuple of the
        candidates within the noise of the best (the best among them).

    Raises:
        ValueError: no candidates, or none with a finite held-out error.
    """
    if not candidates:
        raise ValueError("no candidates to choose from")
    failed = [c for c in candidates if not math.isfinite(c.cv_error_pct)]
    candidates = [c for c in candidates if math.isfinite(c.cv_error_pct)]
    if not candidates:
        raise ValueError(
            "every candidate failed cross-validation (non-finite held-out error): "
            f"{', '.join(c.label for c in failed)}"
        )
    best = min(candidates, key=lambda c: c.cv_error_pct)
    within = tuple(c for c in candidates if c is best or _paired(c, best)[0] <= _paired(c, best)[1])
    chosen = min(within, key=lambda c: (c.n_physical, c.cv_error_pct))
    return chosen, within


def _blocked_force_note(candidates, chosen: Candidate) -> str:
    pair = [c for c in candidates if c.model_name == chosen.model_name]
    if len(pair) < 2:
        return f"blocked force: only {chosen.blocked_force!r} was tried for {chosen.model_name}."
    a, b = (
        (c for c in pair if c.blocked_force == "momentum"),
        (c for c in pair if c.blocked_force == "paper"),
    )
    mom, pap = next(a, None), next(b, None)
    if mom is None or pap is None:
        return "blocked force: not compared."
    mean, se = _paired(pap, mom)
    verdict = (
        "the data support 'momentum' (the floor also takes the momentum flux (M/2R)δ̇² in "
        "compression)"
        if mean > 2 * se
        else "the data support 'paper' (F_B + F_G + F_d)"
        if mean < -2 * se
        else "the data do not distinguish the two definitions"
    )
    return (
        f"blocked force ({chosen.model_name}): held-out error {mom.cv_error_pct:.2f} % with "
        f"'momentum', {pap.cv_error_pct:.2f} % with 'paper' (paper − momentum = {mean:+.2f} ± "
        f"{se:.2f} %): {verdict}."
    )


def shared_structure(names: Sequence[str], gas: str = "adiabatic") -> Model:
    """One model holding the terms of every candidate named (their damping laws, and the
    stiffening, the ball mode and the series element if any candidate has them): the structure
    of the one compiled fit program that all candidates and folds run through, each with the
    terms it lacks held off (the ball mode at μ = 0, the series element at C = 0)."""
    laws, stiff, mode, series = [], False, False, False
    for name in names:
        terms = parse_model_terms(name)
        laws += [t for t in terms.laws if t not in laws]
        stiff = stiff or terms.stiffening
        mode = mode or terms.ball_mode
        series = series or terms.series
    return superset_model(Model(gas=gas), laws, stiffening=stiff, ball_mode=mode, series=series)


def shared_structures(
    names: Sequence[str], gas: str = "adiabatic", given: Model | None = None
) -> dict[str, Model]:
    """The structure each candidate named is fitted in (``given``, if one is given, for all):
    one :func:`shared_structure` for the candidates without the series element and one for
    those with it. The element's closed-form coupling makes every solve of a program that
    holds it, even held off, ~2.7× as costly (the force's rate dF_c/dt is differentiated
    again for the Jacobian), so the other candidates do not carry it."""
    if given is not None:
        return {name: given for name in names}
    groups: dict[bool, list[str]] = {}
    for name in names:
        groups.setdefault(parse_model_terms(name).series, []).append(name)
    out = {}
    for group in groups.values():
        structure = shared_structure(group, gas)
        out.update({name: structure for name in group})
    return out


def candidate_pairs(
    candidates: Sequence[str], blocked_forces: Sequence[str]
) -> list[tuple[str, str]]:
    """(model, blocked force) pairs: ``"name"`` pairs with every blocked force,
    ``"name/paper"`` or ``"name/momentum"`` with that one only."""

    if not candidates or not blocked_forces:
        raise ValueError("give at least one candidate model and one blocked-force definition")
    for bf in blocked_forces:
        check_choice("blocked_force", bf, BLOCKED_FORCES)
    pairs = []
    for c in candidates:
        name, sep, bf = str(c).partition("/")
        parse_model_name(name)
        if sep:
            check_choice("blocked_force", bf, BLOCKED_FORCES)
            pairs.append((name, bf))
        else:
            pairs += [(name, b) for b in blocked_forces]
    return list(dict.fromkeys(pairs))


def _baseline_task(data, superset: Model):
    """The unfitted paper model's held-out rows at every height (a task, see :func:`fit_task`)."""
    return tuple(held_out_rows(predict(data, superset=superset), data.heights_m))


def _structure_cost(name: str) -> float:
    """A candidate's relative cost per evaluation (the order in which work starts, nothing
    else): the ball mode and the series element make every solve several times dearer."""
    terms = parse_model_terms(name)
    return 1.0 + 3.0 * terms.ball_mode + 2.0 * terms.series + 0.5 * len(terms.laws)


def select_model(
    data,
    candidates: Sequence[str] = MODEL_NAMES,
    *,
    blocked_forces: Sequence[str] = BLOCKED_FORCES,
    workers: int | Parallel | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    **fit_kwargs,
) -> Selection:
    """Fit every candidate, cross-validate it over the heights, and recommend one (see the
    module docstring for the rule).

    Args:
        data: a :class:`~rbjax.fit.FitData`, recordings or paths (see
            :func:`rbjax.fit.prepare_data`).
        candidates: model names of :mod:`rbjax.fit`, each tried with every one of
            ``blocked_forces`` (``paper``, ``momentum``), or ``"name/paper"``,
            ``"name/momentum"`` for one pairing.
        workers: worker processes the fits run in (default: every core this process may use;
            1: one fit after another in this process; or a
            :class:`~rbjax.studies.executors.Parallel`). The full fits are tasks, and each
            fold, warm-started from its candidate's full fit, is a task of its own as soon as
            that fit is done, the costliest first; the results are those of ``workers=1``,
            bit for bit (the same programs on the same inputs).
        scheduler: address of a Dask scheduler to send the fits to instead (``rbjax[cluster]``;
            see :mod:`rbjax.studies.executors`).
        progress: one line per full fit and per fold on stderr.
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        The :class:`Selection`.

    Raises:
        ValueError: bad candidates, data or worker count.
        rbjax.studies.executors.TaskError: a fit failed on a worker (named: candidate, fold).
    """
    require_x64()
    t0 = time.perf_counter()
    parallel = workers if isinstance(workers, Parallel) else Parallel(workers, scheduler)
    pairs = candidate_pairs(candidates, blocked_forces)
    data = prepare_data(data)
    _check_folds(data)
    structures = shared_structures(
        [name for name, _ in pairs],
        fit_kwargs.get("gas", "adiabatic"),
        fit_kwargs.pop("superset", None),
    )
    costs = {name: _structure_cost(name) for name, _ in pairs}
    # The first fit of each shared structure starts first: workers then trace different
    # programs at the same time instead of the same one twice.
    first = {id(structures[name]): (name, bf) for name, bf in reversed(pairs)}
    tasks = [
        Task(
            f"{name}/{bf} (all heights)",
            fit_task,
            (data, name, bf, None, None, {**fit_kwargs, "superset": structures[name]}),
            cost=costs[name] * (1e6 if first[id(structures[name])] == (name, bf) else 1.0),
        )
        for name, bf in pairs
    ]
    tasks.append(
        Task("the unfitted paper model", _baseline_task, (data, structures[pairs[0][0]]), 0.0)
    )
    folds_of: dict[int, tuple[int, float]] = {}  # task index → (pair index, held-out height)

    def then(i: int, result):
        if i == len(pairs):
            return []
        if i > len(pairs):
            k, h = folds_of[i]
            _fold_row(*pairs[k], h, result, progress)
            return []
        name, bf = pairs[i]
        say(
            f"select: {name}/{bf}: rms {result.residual_rms_N:.2f} N, {result.message}",
            enabled=progress,
        )
        kwargs = {**fit_kwargs, "superset": structures[name]}
        new = _fold_tasks(data, name, bf, result, data.heights_m, kwargs, costs[name])
        start = len(tasks) + len(folds_of)
        folds_of.update({start + j: (i, h) for j, h in enumerate(data.heights_m)})
        return new

    say(f"select: {len(pairs)} candidates, fitted in {parallel.describe()}", enabled=progress)
    results = run_tasks(parallel, tasks, then=then, label="select")
    out = []
    for k, (name, bf) in enumerate(pairs):
        mine = sorted((j, h) for j, (kk, h) in folds_of.items() if kk == k)
        folds = tuple(held_out_rows(results[j], [h])[0] for j, h in mine)
        out.append(Candidate(name, bf, results[k], folds))
    chosen, within = recommend(out)
    return Selection(
        candidates=tuple(out),
        recommended=chosen,
        within_noise=within,
        rule=RULE,
        blocked_force_note=_blocked_force_note(out, chosen),
        baseline=results[len(pairs)],
        elapsed_s=time.perf_counter() - t0,
    )


@dataclasses.dataclass(frozen=True, eq=False)
class HoldOutComparison:
    """Errors at heights left out of the fit, per candidate, with the unfitted paper model."""

    fit_heights_m: tuple
    predict_heights_m: tuple
    rows: dict  # label -> tuple[HeldOut]

    def table(self) -> str:

        header = ["model", "h (m)", "history (%)", "Δt_c (%)", "Δpeak (%)"] + [
            f"ΔL {b} (dB)" for b in OCTAVE_BANDS
        ]
        rows = []
        for label, held in self.rows.items():
            for r in held:
                rows.append(
                    [
                        label,
                        f"{r.height_m:.2f}",
                        fmt(r.history_error_pct, ".2f"),
                        fmt(r.contact_time_pct, "+.2f"),
                        fmt(r.peak_force_pct, "+.2f"),
                    ]
                    + [fmt(x, "+.2f") for x in r.lfe_octave_dB]
                )
        fitted = ", ".join(f"{h:g}" for h in self.fit_heights_m)
        return (
            format_table(header, rows)
            + f"\n(fitted to {fitted} m; errors are predicted − measured at the other heights)"
        )

    def to_dict(self) -> dict:
        return {
            "fit_heights_m": list(self.fit_heights_m),
            "predict_heights_m": list(self.predict_heights_m),
            "rows": {k: [r.to_dict() for r in v] for k, v in self.rows.items()},
        }


def held_out_comparison(
    data,
    fit_heights: Sequence[float],
    candidates: Sequence[str] = MODEL_NAMES,
    *,
    blocked_forces: Sequence[str] = BLOCKED_FORCES,
    starts: dict | None = None,
    workers: int | Parallel | None = None,
    progress: bool = True,
    **fit_kwargs,
) -> HoldOutComparison:
    """Fit each candidate to ``fit_heights`` only and predict the other heights; the unfitted
    paper model (``JIS_RUBBER_BALL``, adiabatic gas, ``paper`` blocked force) is the baseline.

    Args:
        data: a :class:`~rbjax.fit.FitData`, recordings or paths (see
            :func:`rbjax.fit.prepare_data`).
        fit_heights: the heights fitted, m; the other heights of the data are predicted.
        candidates: model names, as in :func:`select_model`.
        blocked_forces: the blocked-force definitions each name is tried with, as in
            :func:`select_model`.
        starts: optional warm starts, {(model, blocked_force): FitResult}.
        workers: as in :func:`select_model` (each candidate's fit is a task).
        progress: one line per fit on stderr.
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        The :class:`HoldOutComparison`: the errors at the held-out heights per candidate
        (``"model/blocked force"``) and of ``"paper (unfitted)"``.

    Raises:
        ValueError: every height of the data is in ``fit_heights``, bad candidate names or
            blocked forces, or data that cannot be prepared (``rbjax.data.DataError``).
        rbjax.studies.executors.TaskError: a candidate's fit failed (named).
    """
    pairs = candidate_pairs(candidates, blocked_forces)
    data = prepare_data(data)
    structures = shared_structures(
        [name for name, _ in pairs],
        fit_kwargs.get("gas", "adiabatic"),
        fit_kwargs.pop("superset", None),
    )
    fit_heights = tuple(float(h) for h in fit_heights)
    rest = tuple(
        float(h) for h in data.heights_m if not any(abs(h - f) < 5e-4 for f in fit_heights)
    )
    if not rest:
        raise ValueError("held_out_comparison: every height is in fit_heights; nothing is held out")
    tasks = [
        Task(
            f"{name}/{bf} fitted to {len(fit_heights)} heights",
            fit_task,
            (
                data,
                name,
                bf,
                fit_heights,
                (starts or {}).get((name, bf)),
                {**fit_kwargs, "superset": structures[name]},
            ),
            cost=_structure_cost(name),
        )
        for name, bf in pairs
    ]

    def then(i: int, res: FitResult):
        if i < len(pairs):
            say(f"held-out: {tasks[i].name} ({res.message})", enabled=progress)
        return []

    results = run_tasks(workers, tasks, then=then, label="held-out comparison")
    rows = {f"{name}/{bf}": tuple(held_out_rows(r, rest)) for (name, bf), r in zip(pairs, results)}
    rows["paper (unfitted)"] = tuple(
        held_out_rows(predict(data, superset=structures[pairs[0][0]]), rest)
    )
    return HoldOutComparison(fit_heights, rest, rows)

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

By default the selection races (:mod:`rbjax.studies.selection.race`): after the full fits the
folds run in rounds, and a candidate that every contender beats at every height (its fold's
error, or where the fold has not run, its full fit's in-sample error, a lower bound of it) is
dropped, its remaining folds never started: it can be neither the best nor within the noise of
the best, so the recommendation, the candidates within the noise and the recommended model's
held-out errors are those of the exhaustive run (``exhaustive=True``: every fold of every
candidate, the full table).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

from ..._progress import progress as say
from ..._validate import settings_or_default
from ..._x64 import require_x64
from ...fit import MODEL_NAMES, predict, prepare_data
from ...solve.parallel import Parallel, parallel_or_default
from ...terms.model import BLOCKED_FORCE_OPTIONS, Model
from ..parallel.executors import Task, run_tasks
from .candidates import candidate_pairs, shared_structures, structure_cost
from .cross_validation import (
    check_folds,
    fit_task,
    fold_row,
    fold_tasks,
    held_out_rows,
)
from .race import Race
from .race_driver import run_race
from .results import Candidate, Selection
from .rule import RULE, blocked_force_note, recommend

__all__ = ["select_model"]


def _baseline_task(data, structure: Model, *, batcher=None):
    """The unfitted paper model's held-out rows at every height (a task, see :func:`fit_task`)."""
    prediction = predict(data, structure=structure, batcher=batcher)
    return tuple(held_out_rows(prediction, data.heights_m))


def select_model(
    data,
    candidates: Sequence[str] = MODEL_NAMES,
    *,
    blocked_forces: Sequence[str] = BLOCKED_FORCE_OPTIONS,
    parallel: Parallel | None = None,
    progress: bool = True,
    exhaustive: bool = False,
    race: Race | None = None,
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
        parallel: where the fits run, an :class:`rbjax.Parallel` (default ``Parallel()``: worker
            processes on every core this process may use, or one batch per fit program where
            JAX's default device is not a CPU; ``Parallel(workers=1)``: one fit after another in
            this process; ``Parallel(scheduler=ADDRESS)``: a Dask cluster, ``rbjax[cluster]``,
            see :mod:`rbjax.studies.parallel.executors`). The full fits are tasks, and each
            fold, warm-started from its candidate's full fit, is a task of its own as soon as
            that fit is done, the costliest first; the results are those of
            ``Parallel(workers=1)``, bit for bit (the same programs on the same inputs).
        progress: one line per full fit and per fold on stderr, and per round of the race:
            what is still in it, what was dropped and why, an estimate of the time left.
        exhaustive: run every fold of every candidate (default ``False``: race, see the module
            docstring; the same recommendation, fewer folds).
        race: the race's settings (a :class:`~rbjax.studies.selection.race.Race`; default
            ``Race()``).
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        The :class:`Selection` (its ``race``: the rounds and the candidates dropped, each with
        the folds it ran, its partial held-out error and why it left; its ``ran_in``: the
        process each fit ran in).

    Raises:
        ValueError: bad candidates or data; ``parallel`` not an ``rbjax.Parallel``;
            ``exhaustive`` not a bool, or ``exhaustive=True`` with ``race`` settings (they would
            not apply); ``race`` not a :class:`~rbjax.studies.selection.race.Race`.
        rbjax.studies.parallel.executors.TaskError: a fit failed on a worker (named: candidate,
            fold).
    """
    require_x64()
    t0 = time.perf_counter()
    if not isinstance(exhaustive, bool):
        raise ValueError(f"exhaustive={exhaustive!r} must be True or False")
    if exhaustive and race is not None:
        raise ValueError(
            f"race={race!r} with exhaustive=True: an exhaustive selection runs every fold, the "
            "race's settings would not apply; give one or the other"
        )
    race = None if exhaustive else settings_or_default("race", Race, race)
    parallel = parallel_or_default(parallel)
    pairs = candidate_pairs(candidates, blocked_forces)
    data = prepare_data(data)
    check_folds(data)
    # computed here, once: the tasks' copies of the data carry them to the workers
    data.measured_features, data.lowpass_sos  # noqa: B018  (cached properties)
    structures = shared_structures(
        [name for name, _ in pairs],
        fit_kwargs.get("gas", "adiabatic"),
        fit_kwargs.pop("structure", None),
    )
    costs = {name: structure_cost(name) for name, _ in pairs}
    # The first fit of each shared structure starts first: workers then trace different
    # programs at the same time instead of the same one twice.
    first = {id(structures[name]): (name, bf) for name, bf in reversed(pairs)}
    kwargs_of = [{**fit_kwargs, "structure": structures[name]} for name, _ in pairs]
    tasks = [
        Task(
            f"{name}/{bf} (all heights)",
            fit_task,
            (data, name, bf, None, None, kwargs_of[k]),
            cost=costs[name] * (1e6 if first[id(structures[name])] == (name, bf) else 1.0),
        )
        for k, (name, bf) in enumerate(pairs)
    ]
    tasks.append(
        Task("the unfitted paper model", _baseline_task, (data, structures[pairs[0][0]]), 0.0)
    )
    say(f"select: {len(pairs)} candidates, fitted in {parallel.describe()}", enabled=progress)
    summary = None
    ran_in: list[tuple[str, int]] = []
    if race is None:
        fits, folds, baseline = _every_fold(
            parallel, data, pairs, tasks, kwargs_of, progress, ran_in
        )
        out = [Candidate(name, bf, fits[k], folds[k]) for k, (name, bf) in enumerate(pairs)]
    else:
        outcome = run_race(parallel, data, pairs, tasks, kwargs_of, race, progress, ran_in)
        out = [
            Candidate(name, bf, outcome.fits[k], outcome.folds[k], outcome.dropped[k])
            for k, (name, bf) in enumerate(pairs)
        ]
        baseline, summary = outcome.baseline, outcome.summary
    chosen, within = recommend(out)
    return Selection(
        candidates=tuple(out),
        recommended=chosen,
        within_noise=within,
        rule=RULE,
        blocked_force_note=blocked_force_note(out, chosen),
        baseline=baseline,
        elapsed_s=time.perf_counter() - t0,
        race=summary,
        ran_in=tuple(ran_in),
    )


def _every_fold(parallel, data, pairs, tasks, kwargs_of, progress, ran_in):
    """The exhaustive selection's fits: every candidate's full fit, and each of its folds as a
    task as soon as that fit is done, the costliest first. Returns (full fits, folds per
    candidate in the order of the heights, the baseline task's result)."""
    folds_of: dict[int, tuple[int, float]] = {}  # task index → (pair index, held-out height)

    def then(i: int, result):
        if i == len(pairs):
            return []
        if i > len(pairs):
            k, h = folds_of[i]
            fold_row(pairs[k][0], pairs[k][1], h, result, progress)
            return []
        name, bf = pairs[i]
        say(
            f"select: {name}/{bf}: rms {result.residual_rms_N:.2f} N, {result.message}",
            enabled=progress,
        )
        new = fold_tasks(data, name, bf, result, data.heights_m, kwargs_of[i], structure_cost(name))
        start = len(tasks) + len(folds_of)
        folds_of.update({start + j: (i, h) for j, h in enumerate(data.heights_m)})
        return new

    results = run_tasks(parallel, tasks, then=then, label="select", ran_in=ran_in)
    folds = []
    for k in range(len(pairs)):
        mine = sorted((j, h) for j, (kk, h) in folds_of.items() if kk == k)
        folds.append(tuple(held_out_rows(results[j], [h])[0] for j, h in mine))
    return results[: len(pairs)], folds, results[len(pairs)]

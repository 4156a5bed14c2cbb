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

import time
from collections.abc import Sequence

from ..._progress import progress as say
from ..._x64 import require_x64
from ...fit import MODEL_NAMES, predict, prepare_data
from ...terms.model import BLOCKED_FORCE_OPTIONS, Model
from ..parallel.executors import Parallel, Task, run_tasks
from .candidates import candidate_pairs, shared_structures, structure_cost
from .cross_validation import (
    check_folds,
    fit_task,
    fold_row,
    fold_tasks,
    held_out_rows,
)
from .results import Candidate, Selection
from .rule import RULE, blocked_force_note, recommend

__all__ = ["select_model"]


def _baseline_task(data, structure: Model):
    """The unfitted paper model's held-out rows at every height (a task, see :func:`fit_task`)."""
    return tuple(held_out_rows(predict(data, structure=structure), data.heights_m))


def select_model(
    data,
    candidates: Sequence[str] = MODEL_NAMES,
    *,
    blocked_forces: Sequence[str] = BLOCKED_FORCE_OPTIONS,
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
            :class:`~rbjax.studies.parallel.executors.Parallel`). The full fits are tasks, and each
            fold, warm-started from its candidate's full fit, is a task of its own as soon as
            that fit is done, the costliest first; the results are those of ``workers=1``,
            bit for bit (the same programs on the same inputs).
        scheduler: address of a Dask scheduler to send the fits to instead (``rbjax[cluster]``;
            see :mod:`rbjax.studies.parallel.executors`).
        progress: one line per full fit and per fold on stderr.
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        The :class:`Selection`.

    Raises:
        ValueError: bad candidates, data or worker count.
        rbjax.studies.parallel.executors.TaskError: a fit failed on a worker (named: candidate,
            fold).
    """
    require_x64()
    t0 = time.perf_counter()
    parallel = workers if isinstance(workers, Parallel) else Parallel(workers, scheduler)
    pairs = candidate_pairs(candidates, blocked_forces)
    data = prepare_data(data)
    check_folds(data)
    structures = shared_structures(
        [name for name, _ in pairs],
        fit_kwargs.get("gas", "adiabatic"),
        fit_kwargs.pop("structure", None),
    )
    costs = {name: structure_cost(name) for name, _ in pairs}
    # The first fit of each shared structure starts first: workers then trace different
    # programs at the same time instead of the same one twice.
    first = {id(structures[name]): (name, bf) for name, bf in reversed(pairs)}
    tasks = [
        Task(
            f"{name}/{bf} (all heights)",
            fit_task,
            (data, name, bf, None, None, {**fit_kwargs, "structure": structures[name]}),
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
            fold_row(*pairs[k], h, result, progress)
            return []
        name, bf = pairs[i]
        say(
            f"select: {name}/{bf}: rms {result.residual_rms_N:.2f} N, {result.message}",
            enabled=progress,
        )
        kwargs = {**fit_kwargs, "structure": structures[name]}
        new = fold_tasks(data, name, bf, result, data.heights_m, kwargs, costs[name])
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
        blocked_force_note=blocked_force_note(out, chosen),
        baseline=results[len(pairs)],
        elapsed_s=time.perf_counter() - t0,
    )

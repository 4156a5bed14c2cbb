"""The race's rounds run over one :func:`~rbjax.studies.parallel.executors.run_tasks`
(:func:`run_race`; the decisions are :class:`~rbjax.studies.selection.race.RaceState`'s, the
criterion is stated in :mod:`rbjax.studies.selection.race`)."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ..._progress import progress as say
from ...fit.options import options_or_default
from ...solve.parallel import Parallel
from ..parallel.executors import Task, run_tasks
from .candidates import structure_cost
from .cross_validation import HeldOut, fold_row, fold_tasks, held_out_rows
from .race import (
    RACE_CRITERION,
    Dropped,
    Race,
    RaceRound,
    RaceState,
    RaceSummary,
    in_sample_floor,
    mean_or_inf,
)

__all__ = ["RaceOutcome", "run_race", "timed"]


def timed(fn, *args, **kwargs):
    """``(fn(*args, **kwargs), seconds)``: a task's result with its run time (module level:
    picklable; ``kwargs``: the ``batcher=`` of batched fits)."""
    start = time.perf_counter()
    result = fn(*args, **kwargs)
    return result, time.perf_counter() - start


@dataclasses.dataclass(frozen=True, eq=False)
class RaceOutcome:
    """What :func:`run_race` returns: the full fits, each candidate's folds (HeldOut, in the
    order of the heights), why each dropped one left (``None`` for the others), the baseline
    task's result and the :class:`RaceSummary`."""

    fits: list
    folds: list[tuple[HeldOut, ...]]
    dropped: list[Dropped | None]
    baseline: object
    summary: RaceSummary


def _slots(parallel: Parallel) -> int | None:
    """How many tasks ``parallel`` runs at once, where it is bounded (``None``: a cluster, an
    executor or lanes take every task given at once)."""
    if parallel.in_process:
        return 1
    if parallel.scheduler is not None or parallel.executor is not None or parallel.batches_fits:
        return None
    return parallel.local_workers


def run_race(
    parallel: Parallel,
    data,
    pairs,
    full_tasks: list[Task],
    fold_kwargs: list[dict],
    race: Race,
    progress: bool,
    ran_in: list | None = None,
) -> RaceOutcome:
    """Run ``full_tasks`` (one full fit per candidate of ``pairs``, then the baseline task) and
    the race's folds where ``parallel`` says (see the module docstring); ``fold_kwargs``: each
    candidate's fit keywords (its shared structure among them); ``ran_in``: where each task ran
    (:func:`~rbjax.studies.parallel.executors.run_tasks`)."""
    return _Driver(parallel, data, pairs, full_tasks, fold_kwargs, race, progress).run(ran_in)


class _Driver:
    """The race's rounds over one :func:`run_tasks`: the folds are handed to it as slots free
    (those of the current round first, costliest first; then, ahead of their round, those of
    the most promising contenders); a dropped candidate's folds are never handed over."""

    def __init__(self, parallel, data, pairs, full_tasks, fold_kwargs, race, progress):
        self.parallel, self.data, self.pairs = parallel, data, pairs
        self.fold_kwargs, self.race, self.progress = fold_kwargs, race, progress
        self.tasks = [Task(t.name, timed, (t.fn, *t.args), t.cost) for t in full_tasks]
        self.slots = _slots(parallel)
        self.n_pairs = len(pairs)
        self.fits: list = [None] * self.n_pairs
        self.fit_s = [math.nan] * self.n_pairs
        self.in_sample: list = [None] * self.n_pairs
        self.cache: dict[tuple[int, int], tuple[HeldOut, float]] = {}
        self.started: set[tuple[int, int]] = set()
        self.task_of: dict[int, tuple[int, int]] = {}
        self.total, self.completed = len(self.tasks), 0
        self.state: RaceState | None = None
        self.requested: list[tuple[int, int]] = []
        self.round_no = 0
        self.rounds: list[RaceRound] = []
        self.baseline = None
        self.t0 = time.perf_counter()
        self._said_bound = False

    def run(self, ran_in: list | None = None) -> RaceOutcome:
        run_tasks(self.parallel, self.tasks, then=self.then, label="select", ran_in=ran_in)
        state = self.state
        assert state is not None  # every full fit ran
        if state.live():  # never silently: a candidate neither complete nor dropped
            raise RuntimeError(
                "select: the race ended with folds still to run for "
                + ", ".join(state.labels[k] for k in state.live())
            )
        folds = [
            tuple(self.cache[(k, j)][0] for j in sorted(state.obs[k])) for k in range(self.n_pairs)
        ]
        summary = RaceSummary(
            self.race.margin,
            RACE_CRITERION,
            tuple(self.rounds),
            sum(len(o) for o in state.obs),
            state.n * self.n_pairs,
            state.bound_failed,
        )
        return RaceOutcome(self.fits, folds, list(state.dropped), self.baseline, summary)

    def then(self, i: int, outcome) -> list[Task]:
        """A task is done (run_tasks calls this in this process): keep its result, close the
        round when it was the round's last, and hand over the folds to run next."""
        self.completed += 1
        result, seconds = outcome
        if i < self.n_pairs:
            self.fits[i], self.fit_s[i] = result, seconds
            rows = held_out_rows(result, self.data.heights_m)
            self.in_sample[i] = [r.history_error_pct for r in rows]
            name, bf = self.pairs[i]
            say(
                f"select: {name}/{bf}: rms {result.residual_rms_N:.2f} N, {result.message}",
                enabled=self.progress,
            )
            if all(f is not None for f in self.fits):
                options = options_or_default(self.fold_kwargs[0].get("options"))
                self.state = RaceState(
                    [f"{name}/{bf}" for name, bf in self.pairs],
                    self.data.heights_m,
                    self.in_sample,
                    [in_sample_floor(fit, self.data, options) for fit in self.fits],
                    self.race.margin,
                )
                self._advance()
        elif i == self.n_pairs:
            self.baseline = result
        else:
            k, j = self.task_of[i]
            name, bf = self.pairs[k]
            row = fold_row(name, bf, self.data.heights_m[j], result, self.progress)
            self.cache[(k, j)] = (row, seconds)
            if (k, j) in self.requested:
                self._advance()
        return self._feed()

    def _advance(self) -> None:
        """While the current round's folds are all in: record them, decide, ask for the next."""
        state = self.state
        assert state is not None
        while all(key in self.cache for key in self.requested):
            for k, j in self.requested:
                state.record(k, j, self.cache[(k, j)][0].history_error_pct)
            dropped = state.decide(self.round_no)
            live = state.live()
            self.rounds.append(
                RaceRound(
                    self.round_no,
                    tuple((state.labels[k], state.heights[j]) for k, j in self.requested),
                    tuple((state.labels[k], _reason(state, k)) for k in dropped),
                    tuple(state.labels[k] for k in live),
                )
            )
            asked = state.requests() if live else {}
            self.requested = sorted(
                ((k, j) for k, js in asked.items() for j in js),
                key=lambda kj: (-self._cost(kj[0]), kj),
            )
            self._say_round(dropped, live)
            if not self.requested:
                return
            self.round_no += 1

    def _cost(self, k: int) -> float:
        """A fold's relative cost (as :func:`fold_tasks` sets it): the costliest start first."""
        return structure_cost(self.pairs[k][0]) * max(self.fits[k].iterations, 1)

    def _say_round(self, dropped, live) -> None:
        state = self.state
        if not self.progress or state is None:
            return
        what = "the full fits" if self.round_no == 0 else f"round {self.round_no}"
        say(f"select: race: {what} done ({time.perf_counter() - self.t0:.1f} s)")
        if state.bound_failed is not None and not self._said_bound:
            self._said_bound = True
            say(
                f"select: race: the bound failed ({state.bound_failed}): no bound from here on; "
                "the candidates dropped on it run their folds"
            )
        for k in dropped:
            say(f"select: race: dropped {state.labels[k]}: {_reason(state, k)}")
        if not self.requested:
            say("select: race: over")
            return
        folds = len(self.requested)
        say(
            f"select: race: {len(live)} in the race ({', '.join(state.labels[k] for k in live)}); "
            f"round {self.round_no + 1}: {folds} fold{'s' if folds > 1 else ''}; about "
            f"{self._seconds_left():.0f} s left"
        )

    def _seconds_left(self) -> float:
        """The round's folds not done yet and the contenders' other folds (they run), each at
        its candidate's mean fold time so far, else at the folds' time per unit of cost so
        far (half the typical full fit's time before any fold is done)."""
        state = self.state
        assert state is not None
        spent: dict[int, list[float]] = {}
        for (k, _), (_, s) in self.cache.items():
            spent.setdefault(k, []).append(s)
        mean = {k: sum(v) / len(v) for k, v in spent.items()}
        per_cost = (
            sum(sum(v) for v in spent.values())
            / sum(self._cost(k) * len(v) for k, v in spent.items())
            if spent
            else None
        )
        typical = 0.5 * float(np.median(self.fit_s))  # a first fit's time holds its compilation
        todo = {kj for kj in self.requested if kj not in self.cache}
        for k in state.contenders():
            todo |= {(k, j) for j in state.remaining(k) if (k, j) not in self.cache}
        seconds = sum(
            mean.get(k, typical if per_cost is None else per_cost * self._cost(k)) for k, _ in todo
        )
        return seconds / (self.slots or max(len(todo), 1))

    def _feed(self) -> list[Task]:
        """The folds to hand over now: the round's first, then (bounded slots only) ahead of
        their round."""
        waiting = [kj for kj in self.requested if kj not in self.started]
        if self.slots is None:
            chosen = waiting
        else:
            free = self.slots - (self.total - self.completed)
            chosen = waiting[: max(free, 0)]
            chosen += self._ahead(free - len(chosen))
        new = []
        for k, j in chosen:
            name, bf = self.pairs[k]
            h = self.data.heights_m[j]
            (task,) = fold_tasks(self.data, name, bf, self.fits[k], [h], self.fold_kwargs[k], 1.0)
            self.started.add((k, j))
            self.task_of[self.total] = (k, j)
            self.total += 1
            new.append(Task(task.name, timed, (task.fn, *task.args), self._cost(k)))
        return new

    def _ahead(self, count: int) -> list[tuple[int, int]]:
        """Up to ``count`` folds not yet asked for, of the most promising contenders (before
        the full fits are all done: of the candidates whose full fit is)."""
        if count <= 0:
            return []
        state = self.state
        if state is None:
            ready = [k for k in range(self.n_pairs) if self.fits[k] is not None]
            promise = {k: mean_or_inf(self.in_sample[k]) for k in ready}
            order = sorted(ready, key=lambda k: (promise[k], k))
        else:
            live = set(state.live())
            order = sorted(
                (k for k in state.contenders() if k in live), key=lambda k: (state.promise[k], k)
            )
        out = []
        for k in order:
            for j in range(len(self.data.heights_m)):
                if (k, j) not in self.started and (k, j) not in self.cache:
                    out.append((k, j))
                    if len(out) == count:
                        return out
        return out


def _reason(state: RaceState, k: int) -> str:
    dropped = state.dropped[k]
    return "" if dropped is None else dropped.reason

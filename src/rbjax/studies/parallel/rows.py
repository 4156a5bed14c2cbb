"""The rows of a study's design evaluated where an :class:`rbjax.Parallel` says: in this process
(:func:`batch_evaluator`: ``rbjax.solve.batch.evaluate`` split over its devices), or as tasks of
whole ``chunk_size`` steps (:meth:`rbjax.Parallel.task_rows`), each a picklable call
(:func:`evaluate_chunk`) run by :func:`rbjax.studies.parallel.executors.run_tasks` on local
worker processes, a Dask cluster or a given executor, joined in order here.
:func:`row_evaluator` is the evaluator a study of ``rbjax.studies.sensitivity`` runs its design
with.

Every impact is computed by itself, so the outputs do not depend on the split, but for the one
choice ``rbjax.solve.batch.evaluate`` makes for a whole batch: the L_FE history's window and
sub-steps, from the longest and the shortest contact. With L_FE, a first pass of tasks
(:func:`contact_times`) gives the contact time of every row, and every chunk is evaluated with
the rows of the design's shortest and longest contact beside its own (and dropped after): the
whole design's window in every chunk. :func:`evaluate_rows` also evaluates one slice of the
rows that way (a part of a job array, ``rbjax.studies.sweeps.parts.run_part``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from tqdm import tqdm

from ...solve.batch import evaluate, evaluate_jacobian
from ...solve.options import EvaluationSpec
from ...solve.parallel import Parallel, parallel_or_default
from .executors import Task, run_tasks

__all__ = [
    "batch_evaluator",
    "row_evaluator",
    "evaluate_chunk",
    "contact_times",
    "evaluate_rows",
    "task_evaluator",
    "flatten",
    "unflatten",
    "row_count",
]

#: Prefix of a derivative's key in a chunk's flat outputs.
_D = "d:"


def batch_evaluator(samples: Mapping, gradients: bool = False, **settings):
    """Every row of ``samples`` in this process: ``rbjax.solve.batch.evaluate`` (output → (N,)
    array) or, with ``gradients``, ``evaluate_jacobian`` (``(values, jacobian)``), with
    ``settings`` as their keyword arguments (``parallel``: the devices and chunks)."""

    if gradients:
        return evaluate_jacobian(samples, **settings)
    return evaluate(samples, **settings)


def row_evaluator(parallel: Parallel | Callable | None, progress: bool = False) -> Callable:
    """The evaluator of a study's design, called as ``evaluator(samples, gradients,
    **settings)`` once per design (DGSM: once more for the gradients at the base points) and
    returning what :func:`batch_evaluator` returns: ``parallel`` itself where it is a callable
    (a sweep's planning or replaying evaluator); for a :class:`~rbjax.Parallel` (default
    ``Parallel(workers=1)``), every row in this process on its devices where its tasks run in
    this process, else the rows as tasks (:func:`evaluate_rows`)."""
    if callable(parallel) and not isinstance(parallel, Parallel):
        return parallel
    where = rows_parallel(parallel_or_default(parallel, Parallel(workers=1)))
    if where.in_process:

        def on_devices(samples, gradients, **settings):
            return batch_evaluator(samples, gradients, parallel=where, **settings)

        return on_devices
    return task_evaluator(where, progress)


def rows_parallel(parallel: Parallel) -> Parallel:
    """``parallel`` for a design's rows: without ``batch_fits`` (it gathers fits' program calls;
    rows run in this process or as tasks on worker processes)."""
    return parallel.replace(batch_fits=False) if parallel.batches_fits else parallel


def spec_of(settings: Mapping) -> EvaluationSpec:
    """The ``EvaluationSpec`` of an evaluator's ``settings`` (``evaluate``'s keywords)."""
    return settings.get("evaluation") or EvaluationSpec()


def task_settings(settings: Mapping, parallel: Parallel) -> dict:
    """``settings`` of a task: no progress bars, on every device of the process that runs it,
    in chunks of ``parallel.chunk_size``."""
    spec = spec_of(settings).replace(progress=False)
    return {**settings, "evaluation": spec, "parallel": Parallel(chunk_size=parallel.chunk_size)}


def evaluate_chunk(rows: dict, gradients: bool, settings: dict, n_rows: int) -> dict:
    """One task: ``batch_evaluator(rows, gradients, **settings)``, flat (a derivative's key
    prefixed ``d:``), for the first ``n_rows`` rows (the others: the rows of the design's
    shortest and longest contact, and padding to a whole step)."""
    out = flatten(batch_evaluator(rows, gradients, **settings), gradients)
    return {k: v[:n_rows] for k, v in out.items()}


def contact_times(rows: dict, settings: dict, n_rows: int) -> np.ndarray:
    """One task of the first pass: the contact times of the first ``n_rows`` rows (no L_FE)."""
    out = batch_evaluator(rows, False, **(settings | {"lfe": False}))
    return out["contact_time_s"][:n_rows]


def flatten(out, gradients: bool) -> dict:
    """An evaluator's result as one dict: ``evaluate``'s, or ``evaluate_jacobian``'s values and
    its derivatives under ``d:<output>``."""
    if not gradients:
        return dict(out)
    values, jacobian = out
    return {**values, **{_D + k: v for k, v in jacobian.items()}}


def unflatten(flat: dict, gradients: bool):
    """:func:`flatten`'s dict back as the evaluator's result."""
    if not gradients:
        return flat
    values = {k: v for k, v in flat.items() if not k.startswith(_D)}
    return values, {k[len(_D) :]: v for k, v in flat.items() if k.startswith(_D)}


def row_count(samples: Mapping) -> int:
    """The rows of a dict of equally long columns."""
    return len(np.asarray(next(iter(samples.values()))).reshape(-1))


def _take(samples: Mapping, index) -> dict:
    return {k: np.asarray(v, dtype=np.float64).reshape(-1)[index] for k, v in samples.items()}


def _describe(samples: Mapping, a: int, b: int, n: int) -> str:
    """``rows a–b−1 of n (first: name=value, ...)``: what a task's error names."""
    first = ", ".join(f"{k}={float(np.asarray(v).reshape(-1)[a]):.6g}" for k, v in samples.items())
    return f"rows {a}–{b - 1} of {n} (first: {first})"


def _extremes(tc: np.ndarray) -> np.ndarray:
    """Rows of the shortest and the longest finite contact (none if no contact is finite)."""
    ok = np.flatnonzero(np.isfinite(tc) & (tc > 0.0))
    if ok.size == 0:
        return np.array([], dtype=int)
    return np.unique([ok[np.argmin(tc[ok])], ok[np.argmax(tc[ok])]])


def _with_extra(samples: Mapping, a: int, b: int, extra: np.ndarray, least: int) -> dict:
    """Rows [a, b), then the rows ``extra``, padded with copies of row b − 1 to ``least``."""
    index = np.concatenate([np.arange(a, b), extra]).astype(int)
    if index.size < least:
        index = np.concatenate([index, np.full(least - index.size, b - 1)])
    return _take(samples, index)


def evaluate_rows(
    parallel: Parallel,
    samples: Mapping,
    gradients: bool,
    settings: dict,
    span: tuple[int, int] | None = None,
    *,
    progress: bool = False,
    label: str = "impacts",
) -> dict:
    """The flat outputs of rows ``span`` (default: all) of ``samples``, evaluated where
    ``parallel`` says (module docstring: chunks, and the first pass with L_FE); ``settings``:
    ``evaluate``'s keywords but ``parallel``."""
    parallel = rows_parallel(parallel)
    n = row_count(samples)
    a, b = (0, n) if span is None else span
    lfe = bool(settings.get("lfe"))
    local = parallel.scheduler is None and parallel.executor is None
    pieces = [(a, b)] if parallel.in_process else parallel.task_rows(a, b, 2 * lfe)
    least = min(parallel.task_step, n)  # a task of one step at least: one compiled shape
    here = {**settings, "parallel": parallel}
    if local and len(pieces) == 1:  # one chunk: in this process, on its devices
        if (a, b) == (0, n):  # every row: exactly the in-process path
            return flatten(batch_evaluator(samples, gradients, **here), gradients)
        extra = np.array([], dtype=int)
        if lfe:
            scalars = batch_evaluator(samples, False, **(here | {"lfe": False}))
            extra = _extremes(scalars["contact_time_s"])
        rows = _with_extra(samples, a, b, extra, least)
        out = flatten(batch_evaluator(rows, gradients, **here), gradients)
        return {k: v[: b - a] for k, v in out.items()}

    remote = task_settings(settings, parallel)

    def second_pass(extra: np.ndarray) -> list[Task]:
        return [
            Task(
                f"{label}: {_describe(samples, p, q, n)}",
                evaluate_chunk,
                (_with_extra(samples, p, q, extra, least), gradients, remote, q - p),
                cost=q - p,
            )
            for p, q in pieces
        ]

    first = []
    if lfe and (a, b, len(pieces)) != (0, n, 1):  # contact times first: the design's window
        first = [
            Task(
                f"contact times: {_describe(samples, p, q, n)}",
                contact_times,
                (_with_extra(samples, p, q, np.array([], dtype=int), least), remote, q - p),
                cost=q - p,
            )
            for p, q in parallel.task_rows(0, n)
        ]
    tasks = first or second_pass(np.array([], dtype=int))
    bar = tqdm(
        total=(n if first else 0) + b - a,
        desc=label,
        unit="eval",
        disable=not progress,
        leave=False,
    )
    times: dict[int, np.ndarray] = {}

    def then(i: int, result) -> list[Task]:
        if i < len(first):
            times[i] = result
            bar.update(len(result))
            if len(times) < len(first):
                return []
            return second_pass(_extremes(np.concatenate([times[j] for j in range(len(first))])))
        bar.update(len(next(iter(result.values()))))
        return []

    try:
        results = run_tasks(parallel, tasks, then=then, label=f"sweep ({parallel.describe()})")
    finally:
        bar.close()
    chunks = results[len(first) :]
    if len(chunks) != len(pieces):  # run_tasks returns every result or raises
        raise RuntimeError(f"{label}: {len(chunks)} chunks of {len(pieces)} came back")
    out = {k: np.concatenate([c[k] for c in chunks]) for k in chunks[0]}
    if any(len(v) != b - a for v in out.values()):
        raise RuntimeError(f"{label}: the chunks hold {len(out)} outputs of the wrong length")
    return out


def task_evaluator(parallel: Parallel, progress: bool) -> Callable:
    """The ``evaluator`` of a study whose rows run as tasks (``rbjax.studies.sensitivity``)."""

    def evaluator(samples, gradients, **settings):
        label = "gradients" if gradients else "impacts"
        flat = evaluate_rows(parallel, samples, gradients, settings, progress=progress, label=label)
        return unflatten(flat, gradients)

    return evaluator

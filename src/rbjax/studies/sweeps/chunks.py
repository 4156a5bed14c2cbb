"""The rows of a design evaluated as tasks: chunks of whole ``chunk_size`` steps, each a
picklable call (:func:`evaluate_chunk`) run by :func:`rbjax.studies.parallel.executors.run_tasks`
on local worker processes, a Dask cluster or a given executor, joined in order here.

Every impact is computed by itself, so the outputs do not depend on the split, but for the one
choice ``rbjax.solve.batch.evaluate`` makes for a whole batch: the L_FE history's window and
sub-steps, from the longest and the shortest contact. With L_FE, a first pass of tasks
(:func:`contact_times`) gives the contact time of every row, and every chunk is evaluated with
the rows of the design's shortest and longest contact beside its own (and dropped after): the
whole design's window in every chunk. :func:`evaluate_rows` also evaluates one slice of the
rows that way (a part of a job array, ``rbjax.studies.sweeps.parts.run_part``);
:func:`task_evaluator` is the ``evaluator`` the studies of ``rbjax.studies.sensitivity`` take.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from tqdm import tqdm

from ...solve.options import EvaluationSpec
from ..parallel.executors import Parallel, Task, run_tasks
from ..sensitivity import batch_evaluator

__all__ = [
    "evaluate_chunk",
    "contact_times",
    "evaluate_rows",
    "task_evaluator",
    "flatten",
    "unflatten",
    "row_count",
]

#: Chunks per worker a design is cut into (fewer where the rows run short: a chunk is at
#: least one ``chunk_size`` step), and the most steps one chunk holds.
CHUNKS_PER_WORKER = 4
MAX_STEPS_PER_CHUNK = 8
#: Workers assumed for a Dask cluster or a given executor when cutting the design.
CLUSTER_WIDTH = 16
#: Prefix of a derivative's key in a chunk's flat outputs.
_D = "d:"


def spec_of(settings: Mapping) -> EvaluationSpec:
    """The ``EvaluationSpec`` of an evaluator's ``settings`` (``evaluate``'s keywords)."""
    return settings.get("evaluation") or EvaluationSpec()


def on_devices(settings: Mapping, devices, progress: bool) -> dict:
    """``settings`` evaluated on ``devices`` (``None``: all of the process that runs them), with
    or without progress bars."""
    spec = spec_of(settings).replace(devices=devices, progress=progress)
    return {**settings, "evaluation": spec}


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


def _pieces(a: int, b: int, chunk_size: int, width: int, extra: int) -> list[tuple[int, int]]:
    """Rows [a, b) cut into chunks of whole ``chunk_size`` steps (less ``extra`` rows added to
    each), about ``CHUNKS_PER_WORKER`` per worker and at most ``MAX_STEPS_PER_CHUNK`` steps."""
    steps = (b - a) // (chunk_size * CHUNKS_PER_WORKER * max(width, 1))
    size = max(1, chunk_size * min(max(steps, 1), MAX_STEPS_PER_CHUNK) - extra)
    return [(s, min(s + size, b)) for s in range(a, b, size)]


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
    ``parallel`` says (module docstring: chunks, and the first pass with L_FE)."""
    n = row_count(samples)
    a, b = (0, n) if span is None else span
    lfe = bool(settings.get("lfe"))
    chunk = max(int(spec_of(settings).chunk_size or 1024), 1)  # a task: whole steps of this
    local = parallel.scheduler is None and parallel.executor is None
    width = parallel.local_workers if local else CLUSTER_WIDTH
    pieces = [(a, b)] if parallel.in_process else _pieces(a, b, chunk, width, 2 * lfe)
    least = min(chunk, n)  # a chunk of at least one step: the whole design's compiled shape
    if local and len(pieces) == 1:  # one chunk: in this process, on its devices
        if (a, b) == (0, n):  # every row: exactly the in-process path
            return flatten(batch_evaluator(samples, gradients, **settings), gradients)
        extra = np.array([], dtype=int)
        if lfe:
            scalars = batch_evaluator(samples, False, **(settings | {"lfe": False}))
            extra = _extremes(scalars["contact_time_s"])
        rows = _with_extra(samples, a, b, extra, least)
        out = flatten(batch_evaluator(rows, gradients, **settings), gradients)
        return {k: v[: b - a] for k, v in out.items()}

    remote = on_devices(settings, None, False)

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
            for p, q in _pieces(0, n, chunk, width, 0)
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

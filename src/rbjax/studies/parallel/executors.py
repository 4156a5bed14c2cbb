"""Where independent tasks run: one executor interface for fits, sweep chunks and studies.

The heavy studies are made of independent tasks: the full fits and the leave-one-height-out
folds of a model selection, the chunks of a sweep's design. Each is a picklable call
``fn(*args)`` handed to the :class:`concurrent.futures.Executor` an :class:`rbjax.Parallel`
describes (its task fields; its ``devices`` and ``chunk_size`` say how each process runs a
batch):

* ``Parallel(workers=1)``: in this process, one task after another (no start-up cost; the
  reference every other way is compared with).
* ``Parallel(workers=N)`` (default: the cores this process may use, ``os.sched_getaffinity``):
  N tasks at a time: one in a thread of this process (when its JAX is one CPU device, as a
  worker's: its imports are done and its programs loaded, so it starts at once) and the others
  in a local pool of N − 1 worker processes (``spawn``; ``host=False``: N processes and none
  in this one), each with one JAX CPU device and the same
  persistent compilation cache and fit program store as this process
  (:mod:`rbjax.fit.program_store`), so a program compiles once per machine, not once per
  worker. Workers see this process's environment (``JAX_*``, ``XLA_FLAGS``), so they build
  the same programs and the results are the in-process ones, bit for bit.
* ``Parallel(scheduler="tcp://host:8786")``: the tasks go to a running Dask distributed
  cluster (``pip install 'rbjax[cluster]'``); dask-jobqueue starts such a cluster on SLURM,
  PBS, SGE or LSF (``SLURMCluster(...).scheduler_address``). Dask runs a task again on
  another worker when its worker dies.
* ``Parallel(executor=ex)``: any executor the caller made (closed by the caller).
* ``Parallel(batch_fits=True)`` (the default where JAX's default device is not a CPU): the fits
  run in threads of this process and every call of the fit program is gathered into one batch
  per program (:mod:`rbjax.fit.batching`): an accelerator steps 64 lanes of it for about the
  cost of one. Each task is called with the keyword ``batcher=`` (the
  :class:`~rbjax.fit.batching.FitBatcher` its fits are given, ``FitOptions(batcher=...)``), so
  a task run this way takes it.

A task that raises is reported with its name (the candidate and fold, the chunk's rows); a
local worker that dies has its unfinished tasks run again in a new pool (``retries`` times),
then the run fails naming the task: never a silently missing result. A task that kills this
process itself (its share with ``host=True``) ends the run with it.
"""

from __future__ import annotations

import concurrent.futures as cf
import concurrent.futures.process  # noqa: F401  (cf.process.BrokenProcessPool, also before any pool)
import contextlib
import dataclasses
import heapq
import os
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ..._progress import progress as say
from ...solve.parallel import Parallel, parallel_or_default
from .worker_pool import (
    HostAndPool,
    drop_pool,
    local_pool,
    warm,
    worker_start,
)

__all__ = [
    "Task",
    "TaskError",
    "run_tasks",
    "open_executor",
    "prestart",
]

#: Seconds to wait for a Dask scheduler to answer before the run fails.
CONNECT_TIMEOUT_S = 5.0


class TaskError(RuntimeError):
    """A task failed (it raised, or its worker died more often than allowed); names the task."""


@dataclasses.dataclass(frozen=True)
class Task:
    """One independent call ``fn(*args)``.

    Attributes:
        name: what the task is, in errors and progress (e.g.
            ``"hunt-crossley/momentum without 0.4 m"``).
        fn: the callable (picklable, e.g. a module-level function, for worker processes and
            Dask workers).
        args: its positional arguments.
        cost: the relative cost: of the ready tasks, the larger ``cost`` runs first.
    """

    name: str
    fn: Callable
    args: tuple = ()
    cost: float = 1.0


class _InProcess(cf.Executor):
    """Runs each task when it is submitted, in this process."""

    def submit(self, fn, /, *args, **kwargs):
        future: cf.Future = cf.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as err:  # noqa: BLE001  (handed to the caller through the future)
            future.set_exception(err)
        return future


def _dask_client(address: str):
    try:
        from distributed import Client  # lazy: optional (rbjax[cluster]); 0.8 s at import
    except ImportError as err:
        raise ValueError(
            f"scheduler={address!r}: sending work to a Dask cluster needs the 'distributed' "
            "package: pip install 'rbjax[cluster]'"
        ) from err
    try:
        return Client(address, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as err:
        raise ValueError(
            f"scheduler={address!r}: no Dask scheduler answered within {CONNECT_TIMEOUT_S:g} s "
            f"({type(err).__name__}: {err})"
        ) from None


@contextlib.contextmanager
def open_executor(parallel: Parallel) -> Iterator[cf.Executor]:
    """The executor ``parallel`` describes, closed on leaving (unless the caller gave it)."""
    if parallel.executor is not None:
        yield parallel.executor
    elif parallel.batches_fits:
        # lazy: the fit package only where fits run batched (sweeps use this module too)
        from ...fit.batching import BatchedFitExecutor

        batched = BatchedFitExecutor()
        try:
            yield batched
        except BaseException:
            batched.shutdown(wait=False, cancel_futures=True)  # a failed run: the others stop
            raise
        batched.shutdown(wait=False)
    elif parallel.scheduler is not None:
        client = _dask_client(parallel.scheduler)
        try:
            client.run(worker_start, {})  # x64 and one CPU device on every worker
            yield client.get_executor(pure=False)
        finally:
            client.close()
    elif parallel.in_process:
        yield _InProcess()
    else:
        host = parallel.host_runs_tasks
        pool = local_pool(parallel.local_workers - host)
        executor = HostAndPool(pool) if host else pool
        try:
            yield executor
        except cf.process.BrokenProcessPool:
            drop_pool(pool)
            raise
        finally:
            if host:
                executor.shutdown(wait=False)


def prestart(parallel: Parallel) -> None:
    """Start ``parallel``'s local workers now and have them import rbjax, while this process
    does other work (reads the data); nothing for the other kinds of executor."""
    if (
        parallel.scheduler is None
        and parallel.executor is None
        and not parallel.in_process
        and not parallel.batches_fits
    ):
        n = parallel.local_workers - parallel.host_runs_tasks
        pool = local_pool(n)
        for _ in range(n):
            pool.submit(warm)


def _in_process_of(fn, /, *args, **kwargs) -> tuple[int, Any]:
    """``(os.getpid(), fn(*args, **kwargs))``: a task's result with the id of the process that
    ran it (module level: picklable; ``kwargs``: the ``batcher=`` of batched fits)."""
    return os.getpid(), fn(*args, **kwargs)


def run_tasks(
    parallel: Parallel | None,
    tasks: Sequence[Task],
    *,
    then: Callable[[int, Any], Sequence[Task]] | None = None,
    label: str = "tasks",
    ran_in: list | None = None,
) -> list:
    """Run ``tasks`` where ``parallel`` says; the results in the tasks' order.

    Ready tasks start costliest first, at most as many at once as there are workers.
    ``then(i, result)``, called in this process when task ``i`` is done, may return further
    tasks (e.g. the folds warm-started from a full fit); their results follow the given tasks'
    in the order they were added. A task that raises fails the run with a :class:`TaskError`
    naming it.

    Args:
        parallel: where the tasks run: an :class:`rbjax.Parallel` (default ``Parallel()``: every
            usable core).
        tasks: the :class:`Task` objects to run.
        then: ``then(i, result)``, called in this process when task ``i`` is done; it returns
            the further tasks to run (an empty sequence for none).
        label: what the tasks are, in errors and progress.
        ran_in: a list to which ``(task name, process id)`` is appended as each task finishes:
            the ``os.getpid()`` of the process that ran it (this one's for a task run in this
            process or its host thread, a local worker's, a Dask worker's on its own host).
            A record of where the work went, not a result: the results are the same.

    Returns:
        The results, a list: those of ``tasks`` in their order, then those of the tasks
        ``then`` added, in the order they were added.

    Raises:
        TaskError: a task raised (named, with its error), or a local worker died more than
            ``parallel.retries`` times (the unfinished tasks named).
        ValueError: ``parallel`` not an ``rbjax.Parallel``, or a Dask scheduler that cannot be
            reached (or ``distributed`` not installed).
    """
    parallel = parallel_or_default(parallel)
    all_tasks: list[Task] = list(tasks)
    results: dict[int, Any] = {}
    attempts = 0
    while True:
        try:
            with open_executor(parallel) as executor:
                _drive(executor, parallel, all_tasks, results, then, label, ran_in)
            break
        except cf.process.BrokenProcessPool:
            attempts += 1
            missing = [all_tasks[i].name for i in range(len(all_tasks)) if i not in results]
            if attempts > parallel.retries:
                raise TaskError(
                    f"{label}: a worker process died {attempts} times; not finished: "
                    + "; ".join(missing)
                ) from None
            say(
                f"{label}: a worker process died; running {len(missing)} unfinished task(s) "
                "again in a new pool",
                enabled=True,
            )
    return [results[i] for i in range(len(all_tasks))]


def _drive(executor, parallel, all_tasks, results, then, label, ran_in) -> None:
    """Submit ready tasks costliest first (as many in flight as workers), collect results,
    add the tasks ``then`` makes; the tasks already in ``results`` are not run again."""
    width = 1 if parallel.in_process else max(parallel.local_workers, 1)
    if parallel.scheduler is not None or parallel.executor is not None or parallel.batches_fits:
        width = 1 << 30  # a cluster has its own queue; batched fits step together: all at once
    ready: list[tuple[float, int]] = []
    for i, task in enumerate(all_tasks):
        if i not in results:
            heapq.heappush(ready, (-task.cost, i))
    running: dict[cf.Future, int] = {}
    try:
        _loop(executor, all_tasks, results, then, label, width, ready, running, ran_in)
    finally:
        for future in running:  # after a failure: nothing more of this run starts
            future.cancel()


def _loop(executor, all_tasks, results, then, label, width, ready, running, ran_in) -> None:
    while ready or running:
        while ready and len(running) < width:
            _, i = heapq.heappop(ready)
            task = all_tasks[i]
            if ran_in is None:
                running[executor.submit(task.fn, *task.args)] = i
            else:
                running[executor.submit(_in_process_of, task.fn, *task.args)] = i
        done, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
        for future in sorted(done, key=lambda f: running[f]):
            i = running.pop(future)
            try:
                result = future.result()
            except cf.process.BrokenProcessPool:
                raise
            except Exception as err:
                raise TaskError(
                    f"{label}: {all_tasks[i].name} failed: {type(err).__name__}: {err}"
                ) from err
            if ran_in is not None:
                pid, result = result
                ran_in.append((all_tasks[i].name, pid))
            results[i] = result
            for new in then(i, result) if then is not None else ():
                all_tasks.append(new)
                heapq.heappush(ready, (-new.cost, len(all_tasks) - 1))

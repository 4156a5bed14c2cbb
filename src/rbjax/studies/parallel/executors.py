"""Where independent work runs: one executor interface for fits, sweep chunks and studies.

The heavy studies are made of independent tasks: the full fits and the leave-one-height-out
folds of a model selection, the chunks of a sweep's design. Each is a picklable call
``fn(*args)`` handed to a :class:`concurrent.futures.Executor`:

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
* ``Parallel(lanes=True)`` (the default where JAX's default device is not a CPU): the fits run
  in threads of this process and every call of the fit program is gathered into one batch per
  program, the fits as lanes of it (:mod:`rbjax.fit.lanes`): an accelerator steps 64 lanes
  for about the cost of one.

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

import jax

from ..._progress import progress as say
from .worker_pool import (
    HostAndPool,
    drop_pool,
    local_pool,
    warm,
    worker_start,
)

__all__ = [
    "Parallel",
    "Task",
    "TaskError",
    "usable_cores",
    "run_tasks",
    "open_executor",
    "prestart",
]

#: Seconds to wait for a Dask scheduler to answer before the run fails.
CONNECT_TIMEOUT_S = 5.0


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity; ``os.cpu_count()`` elsewhere)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


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


@dataclasses.dataclass(frozen=True)
class Parallel:
    """Where a study's independent tasks run (see the module docstring).

    Args:
        workers: local worker processes; ``None``: the usable cores; ``1``: in this process.
        scheduler: address of a Dask scheduler (``tcp://host:port``); given, it is used and
            ``workers`` is not (the cluster has its own).
        executor: an executor made by the caller, used as it is (and not closed here); given,
            ``workers`` is not used either.
        retries: how often the unfinished tasks of a local pool whose worker died are run
            again in a new pool before the run fails.
        lanes: run the fits as lanes of one batched program per structure, in this process
            (:mod:`rbjax.fit.lanes`); ``None`` (default): so where JAX's default device is not
            a CPU and neither ``workers``, ``scheduler`` nor ``executor`` is given.
        host: with several local workers, this process runs one task at a time beside
            ``workers − 1`` worker processes, where its JAX is one CPU device as theirs is
            (default ``True``); ``False``: ``workers`` processes run every task, so a task that
            kills the process it runs in (a crash, the OOM killer) costs a retry, never this
            process.

    Raises:
        ValueError: both ``scheduler`` and ``executor`` given; ``lanes=True`` with a scheduler,
            an executor or ``workers`` other than 1; ``workers`` not an integer ≥ 1; ``retries``
            not an integer ≥ 0; ``host`` not a bool.
    """

    workers: int | None = None
    scheduler: str | None = None
    executor: cf.Executor | None = None
    retries: int = 1
    lanes: bool | None = None
    host: bool = True

    def __post_init__(self):
        given = [x is not None for x in (self.scheduler, self.executor)]
        if sum(given) > 1:
            raise ValueError("Parallel: give a scheduler or an executor, not both")
        if self.lanes and (sum(given) or self.workers not in (None, 1)):
            raise ValueError(
                "Parallel: lanes=True runs the fits in this process; give no scheduler, "
                f"executor or worker count (got workers={self.workers!r})"
            )
        if self.workers is not None and (
            isinstance(self.workers, bool) or not isinstance(self.workers, int) or self.workers < 1
        ):
            raise ValueError(
                f"workers={self.workers!r} is outside the valid range: an integer ≥ 1 "
                f"(this machine lets this process use {usable_cores()} cores)"
            )
        if not (isinstance(self.retries, int) and self.retries >= 0):
            raise ValueError(f"retries={self.retries!r} must be an integer ≥ 0")
        if not isinstance(self.host, bool):
            raise ValueError(f"host={self.host!r} must be True or False")

    @property
    def local_workers(self) -> int:
        """Local worker processes this runs with: ``workers`` clamped to the usable cores."""
        return min(self.workers or usable_cores(), usable_cores())

    @property
    def use_lanes(self) -> bool:
        """Whether the fits run as lanes of batched programs (see ``lanes``)."""
        if self.lanes is not None:
            return self.lanes
        if self.workers is not None or self.scheduler is not None or self.executor is not None:
            return False
        return jax.default_backend() != "cpu"

    @property
    def in_process(self) -> bool:
        return (
            self.scheduler is None
            and self.executor is None
            and self.local_workers == 1
            and not self.use_lanes
        )

    def describe(self) -> str:
        if self.use_lanes:
            return f"lanes of one batched program per structure on {jax.default_backend()}"
        if self.scheduler is not None:
            return f"the Dask cluster at {self.scheduler}"
        if self.executor is not None:
            return f"the given executor ({type(self.executor).__name__})"
        n = self.local_workers
        if n == 1:
            return "this process"
        if host_takes_part(self):
            return f"this process and {n - 1} local worker process{'es' if n > 2 else ''}"
        return f"{n} local worker processes"


def as_parallel(parallel: Parallel | int | None) -> Parallel:
    """A :class:`Parallel` from itself, a worker count, or ``None`` (every usable core)."""
    if isinstance(parallel, Parallel):
        return parallel
    return Parallel(workers=parallel)


def host_takes_part(parallel: Parallel) -> bool:
    """Whether this process runs tasks beside its local workers: with several local workers,
    where this process's JAX is one CPU device, as each worker's (the same programs, so the
    same bits); the pool then has one worker fewer."""
    if not parallel.host or parallel.local_workers < 2 or parallel.use_lanes:
        return False
    if parallel.scheduler is not None or parallel.executor is not None:
        return False
    return jax.default_backend() == "cpu" and jax.local_device_count() == 1


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
    elif parallel.use_lanes:
        # lazy: the fit package only where its fits run as lanes (sweeps use this module too)
        from ...fit.lanes import LaneExecutor

        lanes = LaneExecutor()
        try:
            yield lanes
        except BaseException:
            lanes.shutdown(wait=False, cancel_futures=True)  # a failed run: the others stop
            raise
        lanes.shutdown(wait=False)
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
        host = host_takes_part(parallel)
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


def prestart(parallel: Parallel | int | None) -> None:
    """Start ``parallel``'s local workers now and have them import rbjax, while this process
    does other work (reads the data); nothing for the other kinds of executor."""
    parallel = as_parallel(parallel)
    if (
        parallel.scheduler is None
        and parallel.executor is None
        and not parallel.in_process
        and not parallel.use_lanes
    ):
        n = parallel.local_workers - host_takes_part(parallel)
        pool = local_pool(n)
        for _ in range(n):
            pool.submit(warm)


def run_tasks(
    parallel: Parallel | int | None,
    tasks: Sequence[Task],
    *,
    then: Callable[[int, Any], Sequence[Task]] | None = None,
    label: str = "tasks",
) -> list:
    """Run ``tasks`` where ``parallel`` says; the results in the tasks' order.

    Ready tasks start costliest first, at most as many at once as there are workers.
    ``then(i, result)``, called in this process when task ``i`` is done, may return further
    tasks (e.g. the folds warm-started from a full fit); their results follow the given tasks'
    in the order they were added. A task that raises fails the run with a :class:`TaskError`
    naming it.

    Args:
        parallel: where the tasks run: a :class:`Parallel`, a worker count, or ``None`` (every
            usable core).
        tasks: the :class:`Task` objects to run.
        then: ``then(i, result)``, called in this process when task ``i`` is done; it returns
            the further tasks to run (an empty sequence for none).
        label: what the tasks are, in errors and progress.

    Returns:
        The results, a list: those of ``tasks`` in their order, then those of the tasks
        ``then`` added, in the order they were added.

    Raises:
        TaskError: a task raised (named, with its error), or a local worker died more than
            ``parallel.retries`` times (the unfinished tasks named).
        ValueError: a worker count that is not an integer ≥ 1, or a Dask scheduler that cannot
            be reached (or ``distributed`` not installed).
    """
    parallel = as_parallel(parallel)
    all_tasks: list[Task] = list(tasks)
    results: dict[int, Any] = {}
    attempts = 0
    while True:
        try:
            with open_executor(parallel) as executor:
                _drive(executor, parallel, all_tasks, results, then, label)
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


def _drive(executor, parallel, all_tasks, results, then, label) -> None:
    """Submit ready tasks costliest first (as many in flight as workers), collect results,
    add the tasks ``then`` makes; the tasks already in ``results`` are not run again."""
    width = 1 if parallel.in_process else max(parallel.local_workers, 1)
    if parallel.scheduler is not None or parallel.executor is not None or parallel.use_lanes:
        width = 1 << 30  # a cluster has its own queue; lanes step together: all at once
    ready: list[tuple[float, int]] = []
    for i, task in enumerate(all_tasks):
        if i not in results:
            heapq.heappush(ready, (-task.cost, i))
    running: dict[cf.Future, int] = {}
    try:
        _loop(executor, all_tasks, results, then, label, width, ready, running)
    finally:
        for future in running:  # after a failure: nothing more of this run starts
            future.cancel()


def _loop(executor, all_tasks, results, then, label, width, ready, running) -> None:
    while ready or running:
        while ready and len(running) < width:
            _, i = heapq.heappop(ready)
            task = all_tasks[i]
            running[executor.submit(task.fn, *task.args)] = i
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
            results[i] = result
            for new in then(i, result) if then is not None else ():
                all_tasks.append(new)
                heapq.heappush(ready, (-new.cost, len(all_tasks) - 1))

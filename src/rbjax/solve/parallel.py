"""Where work runs, as one object (:class:`Parallel`), and the one planner that cuts rows.

Work spreads at two levels, and one ``Parallel`` says both:

* a batch of impacts in this process (``rbjax.simulate``, ``rbjax.solve.batch.evaluate``, the
  studies): cut in chunks of ``chunk_size`` rows, split over the local JAX ``devices``, each
  device running its own program (:mod:`rbjax.solve.devices`);
* independent tasks (the fits of a model selection, the chunks of a sweep's design): in this
  process, on ``workers`` local worker processes, on a Dask cluster (``scheduler``), on a given
  ``executor`` (:mod:`rbjax.studies.parallel.executors`), or the fits as one batch per fit
  program (``batch_fits``, :mod:`rbjax.fit.batching`).

:func:`cut_rows` cuts rows for all of them: a batch into device chunks
(:meth:`Parallel.device_plan`), a design into tasks (:meth:`Parallel.task_rows`) and into the
parts of a job array (``rbjax.studies.sweeps.parts``). The command line's flags map onto the
fields one to one (``--devices``, ``--chunk-size``, ``--workers``, ``--scheduler``,
``--batch-fits``).
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import math
import os
from collections.abc import Sequence

import jax

from .._validate import settings_or_default

__all__ = [
    "Parallel",
    "cut_rows",
    "usable_cores",
    "parallel_or_default",
    "default_chunk_size",
    "CPU_CHUNK_SIZE",
    "ACCELERATOR_CHUNK_SIZE",
    "ALIGN",
]

#: Rows per chunk on a CPU device, per path, below the size where the working set leaves the
#: caches (one core, 2¹⁸ rows in chunks: the quadrature runs 2.3 M/s at 4096–8192 rows a chunk,
#: 1.1 M/s at 65 536 or in one call; the phase-angle path 0.20 M/s up to 16 384, 0.15 M/s at
#: 32 768; the sampled L_FE history is best at 128–512). An ODE chunk is small, since a vmapped
#: while loop runs until its slowest row is done, and so that a batch of a few thousand splits
#: over many devices (one core: 34 000/s at 256 rows a chunk, 39 000/s at 1024, 28 000/s at 64).
#: Both fast paths take 16 384, where they still run at their best: at 8192 a batch of 10 000
#: impacts (the forward benchmark's) was cut in two padded chunks and ran ~0.8× (phase angle) and
#: ~0.7× (quadrature: 1.3 against 1.9 M/s) as fast on one device as in one call; at 2¹⁸ rows the
#: quadrature runs 2.32–2.40 M/s in chunks of 16 384 against 2.26–2.27 M/s in chunks of 8192
#: (2026-11-29, one core, quiet; issue 42, ``benchmarks/forward.py --only paired_forward``).
CPU_CHUNK_SIZE = {"quadrature": 16384, "angle": 16384, "sampled": 256, "ode": 512}
#: Rows per chunk on an accelerator (a GPU wants wide launches; one call below this size).
ACCELERATOR_CHUNK_SIZE = {
    "quadrature": 1 << 20,
    "angle": 1 << 20,
    "sampled": 1 << 14,
    "ode": 1 << 16,
}
#: A batch of several chunks has chunks of a multiple of this many rows (XLA:CPU's loops run
#: whole vectors; a chunk of 6667 rows of the phase-angle path ran 3× slower than one of 6672).
ALIGN = 128
#: Rows of a task's step where no ``chunk_size`` is given (a task holds whole steps).
TASK_STEP = 1024
#: Tasks per worker a design is cut into (fewer where the rows run short: a task is at least
#: one step), and the most steps one task holds.
TASKS_PER_WORKER = 4
MAX_STEPS_PER_TASK = 8
#: Workers assumed for a Dask cluster or a given executor when cutting a design into tasks.
CLUSTER_WIDTH = 16


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity; ``os.cpu_count()`` elsewhere)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def cut_rows(a: int, b: int, *, size: int | None = None, parts: int | None = None) -> list:
    """Rows [a, b) cut into consecutive pieces ``(lo, hi)``: of ``size`` rows each (the last may
    be shorter), or into ``parts`` pieces whose sizes differ by one at most. The one planner of
    device chunks, tasks and job-array parts."""
    if size is not None and parts is None:
        size = max(1, int(size))
        return [(s, min(s + size, b)) for s in range(a, b, size)]
    if parts is None or size is not None:
        raise ValueError("cut_rows: give size or parts, one of them")
    n = b - a
    return [(a + n * k // parts, a + n * (k + 1) // parts) for k in range(parts)]


def default_chunk_size(path: str, platform: str | None = None, width: int = 1) -> int:
    """Rows per chunk of ``path`` (``"quadrature"``, ``"angle"``, ``"sampled"``, ``"ode"``) on
    ``platform`` (default: JAX's default backend): ``CPU_CHUNK_SIZE`` on ``"cpu"``,
    ``ACCELERATOR_CHUNK_SIZE`` elsewhere, divided by ``width`` (a row carrying that many values:
    1 + the parameters of a forward Jacobian) and rounded down to a power of two (at least
    32)."""
    cpu = (jax.default_backend() if platform is None else platform) == "cpu"
    size = (CPU_CHUNK_SIZE if cpu else ACCELERATOR_CHUNK_SIZE)[path] // max(1, width)
    return max(32, 1 << (max(1, size).bit_length() - 1))


def _count(name: str, value, lowest: int, extra: str = "") -> None:
    ok = isinstance(value, int) and not isinstance(value, bool) and value >= lowest
    if not ok:
        raise ValueError(
            f"{name}={value!r} is outside the valid range: an integer ≥ {lowest}{extra}"
        )


@dataclasses.dataclass(frozen=True)
class Parallel:
    """Where work runs: a batch's devices and chunks, and where independent tasks go.

    Attributes:
        devices: the local JAX devices a batch of impacts is split over: a count (the first N
            of ``jax.local_devices()``), a sequence of devices, or ``None`` (default: all).
        chunk_size: rows per device chunk (default: sized for the solve path and the platform,
            :func:`default_chunk_size`); a sweep's tasks hold whole multiples of it (default
            1024 rows a step).
        workers: local worker processes for independent tasks; ``None`` (default): the usable
            cores; ``1``: in this process.
        scheduler: address of a Dask scheduler (``tcp://host:port``) to send the tasks to
            instead (the cluster has its own workers).
        executor: a ``concurrent.futures.Executor`` made by the caller, used as it is (and not
            closed here).
        retries: how often the unfinished tasks of a local pool whose worker died are run
            again in a new pool before the run fails.
        host: with several local workers, this process runs one task at a time beside
            ``workers − 1`` worker processes, where its JAX is one CPU device as theirs is
            (default ``True``); ``False``: ``workers`` processes run every task, so a task that
            kills the process it runs in costs a retry, never this process.
        batch_fits: run the fits of a study in threads of this process, every call of a fit
            program gathered into one batch of that program (:mod:`rbjax.fit.batching`);
            ``None`` (default): so where JAX's default device is not a CPU and neither
            ``workers``, ``scheduler`` nor ``executor`` is given.

    Raises:
        ValueError: ``devices`` neither a count ≥ 1, a non-empty sequence nor ``None``;
            ``chunk_size`` or ``workers`` not an integer ≥ 1; both ``scheduler`` and
            ``executor``; ``batch_fits=True`` with a scheduler, an executor or ``workers``
            other than 1; ``retries`` not an integer ≥ 0; ``host`` not a bool. The message
            names the field.
    """

    devices: int | Sequence | None = None
    chunk_size: int | None = None
    workers: int | None = None
    scheduler: str | None = None
    executor: cf.Executor | None = None
    retries: int = 1
    host: bool = True
    batch_fits: bool | None = None

    def __post_init__(self):
        if isinstance(self.devices, int) or isinstance(self.devices, bool):
            _count("devices", self.devices, 1)
        elif self.devices is not None and not (
            isinstance(self.devices, Sequence) and len(self.devices) > 0
        ):
            raise ValueError(
                f"devices={self.devices!r} must be a count ≥ 1, a non-empty sequence of JAX "
                "devices, or None (all)"
            )
        if self.chunk_size is not None:
            _count("chunk_size", self.chunk_size, 1)
        if self.workers is not None:
            _count("workers", self.workers, 1, f" (this process may use {usable_cores()} cores)")
        if self.scheduler is not None and self.executor is not None:
            raise ValueError("Parallel: give a scheduler or an executor, not both")
        if self.batch_fits and (
            self.scheduler is not None or self.executor is not None or self.workers not in (None, 1)
        ):
            raise ValueError(
                "Parallel: batch_fits=True runs the fits in this process; give no scheduler, "
                f"executor or worker count (got workers={self.workers!r})"
            )
        _count("retries", self.retries, 0)
        if not isinstance(self.host, bool):
            raise ValueError(f"host={self.host!r} must be True or False")
        if self.batch_fits is not None and not isinstance(self.batch_fits, bool):
            raise ValueError(f"batch_fits={self.batch_fits!r} must be True, False or None")

    def replace(self, **changes) -> Parallel:
        """A copy with ``changes`` (validated again)."""
        return dataclasses.replace(self, **changes)

    # --- a batch in this process: devices and chunks

    def local_devices(self) -> tuple:
        """The devices a batch is split over (see ``devices``)."""
        available = tuple(jax.local_devices())
        if self.devices is None:
            return available
        if isinstance(self.devices, int):
            if self.devices > len(available):
                raise ValueError(
                    f"devices={self.devices}: JAX has {len(available)} local device(s) here "
                    "(more CPU devices: JAX_NUM_CPU_DEVICES=N, or "
                    "jax.config.update('jax_num_cpu_devices', N) before JAX starts)"
                )
            return available[: self.devices]
        return tuple(self.devices)

    def chunk_rows(self, path: str, devices: Sequence, width: int = 1) -> int:
        """Rows per device chunk of ``path``: ``chunk_size``, else :func:`default_chunk_size`."""
        if self.chunk_size is not None:
            return self.chunk_size
        return default_chunk_size(path, devices[0].platform, width)

    @staticmethod
    def device_plan(n: int, n_devices: int, chunk_size: int) -> tuple[int, list]:
        """(devices used, the chunks' rows) of a batch of ``n`` rows: one chunk of ``n`` rows
        where ``n ≤ chunk_size``, else even chunks of a multiple of ``ALIGN`` rows (at most
        ``chunk_size``; the last one padded to that length by its caller), as many devices as
        chunks at most. The chunks do not depend on ``n_devices``, so every row is computed by
        the same program whatever the number of devices: the results are those of one
        device, bit for bit."""
        chunk_size = max(1, int(chunk_size))
        if n <= chunk_size:
            return 1, cut_rows(0, n, size=max(1, n))
        even = math.ceil(n / math.ceil(n / chunk_size))
        chunk = min(chunk_size, math.ceil(even / ALIGN) * ALIGN)
        return min(n_devices, math.ceil(n / chunk)), cut_rows(0, n, size=chunk)

    # --- independent tasks

    @property
    def local_workers(self) -> int:
        """Local worker processes this runs with: ``workers`` clamped to the usable cores."""
        return min(self.workers or usable_cores(), usable_cores())

    @property
    def batches_fits(self) -> bool:
        """Whether the fits run as one batch per fit program (see ``batch_fits``)."""
        if self.batch_fits is not None:
            return self.batch_fits
        if self.workers is not None or self.scheduler is not None or self.executor is not None:
            return False
        return jax.default_backend() != "cpu"

    @property
    def in_process(self) -> bool:
        """Whether the tasks run one after another in this process."""
        return (
            self.scheduler is None
            and self.executor is None
            and self.local_workers == 1
            and not self.batches_fits
        )

    @property
    def host_runs_tasks(self) -> bool:
        """Whether this process runs tasks beside its local workers: with several local
        workers, where its JAX is one CPU device, as each worker's (the same programs, so the
        same bits); the pool then has one worker fewer."""
        if not self.host or self.local_workers < 2 or self.batches_fits:
            return False
        if self.scheduler is not None or self.executor is not None:
            return False
        return jax.default_backend() == "cpu" and jax.local_device_count() == 1

    def task_rows(self, a: int, b: int, extra: int = 0) -> list:
        """Rows [a, b) cut into tasks of whole steps of ``chunk_size`` rows (default
        ``TASK_STEP``; less ``extra`` rows its caller adds to each), about ``TASKS_PER_WORKER``
        tasks per worker (``CLUSTER_WIDTH`` workers for a cluster or an executor) and at most
        ``MAX_STEPS_PER_TASK`` steps a task."""
        step = self.task_step
        local = self.scheduler is None and self.executor is None
        width = max(self.local_workers if local else CLUSTER_WIDTH, 1)
        steps = (b - a) // (step * TASKS_PER_WORKER * width)
        size = max(1, step * min(max(steps, 1), MAX_STEPS_PER_TASK) - extra)
        return cut_rows(a, b, size=size)

    @property
    def task_step(self) -> int:
        """Rows of a task's step: ``chunk_size``, else ``TASK_STEP``."""
        return self.chunk_size or TASK_STEP

    def describe(self) -> str:
        """Where the tasks run, in words (progress lines)."""
        if self.batches_fits:
            return f"one batch per fit program on {jax.default_backend()}"
        if self.scheduler is not None:
            return f"the Dask cluster at {self.scheduler}"
        if self.executor is not None:
            return f"the given executor ({type(self.executor).__name__})"
        n = self.local_workers
        if n == 1:
            return "this process"
        if self.host_runs_tasks:
            return f"this process and {n - 1} local worker process{'es' if n > 2 else ''}"
        return f"{n} local worker processes"


def parallel_or_default(parallel: Parallel | None, default: Parallel | None = None) -> Parallel:
    """``parallel``, or ``default`` (``Parallel()``) when it is ``None`` (anything else: a
    ``ValueError``)."""
    if parallel is None and default is not None:
        return default
    return settings_or_default("parallel", Parallel, parallel)

"""The local worker processes of a study: one pool per worker count, kept for the process.

Each worker is a ``spawn``-ed process with one JAX CPU device, float64 and the JAX options of
the process that starts it (the compilation cache's folder among them, so a program compiles
once per machine), and BLAS on one thread. ``local_pool(n)`` makes a pool on first use and keeps
it until the process ends (a second study finds its workers started and their programs
loaded); ``HostAndPool`` lets this process run one task at a time beside such a pool.
:mod:`rbjax.studies.parallel.executors` decides which executor a study's tasks go to.
"""

from __future__ import annotations

import atexit
import concurrent.futures as cf
import multiprocessing
import os

import jax
from threadpoolctl import threadpool_limits

from ..._exit import skip_final_collection


class HostAndPool(cf.Executor):
    """This process runs one task at a time in a thread beside a pool of local workers: the
    host's imports are done and its programs are loaded, so its core starts on the first task
    at once instead of waiting for a worker process to start."""

    def __init__(self, pool: cf.ProcessPoolExecutor):
        self._pool = pool
        self._host = cf.ThreadPoolExecutor(max_workers=1, thread_name_prefix="rbjax-task")
        self._current: cf.Future | None = None

    def submit(self, fn, /, *args, **kwargs):
        # ``done()`` holds from the moment a result is set, before any waiter wakes up, so the
        # next task submitted after ``cf.wait`` returns finds the host free
        if self._current is None or self._current.done():
            self._current = self._host.submit(fn, *args, **kwargs)
            return self._current
        return self._pool.submit(fn, *args, **kwargs)

    def shutdown(self, wait=True, *, cancel_futures=False):
        # the pool is this process's (``local_pool``) and stays; the host's task, if one still
        # runs after a failure, finishes in its thread (a thread cannot be stopped)
        self._host.shutdown(wait=wait, cancel_futures=cancel_futures)


#: JAX options a local worker takes from the process that starts it, so that it builds the
#: same programs (the compilation cache's folder among them: one compile a machine).
INHERITED_OPTIONS = (
    "jax_compilation_cache_dir",
    "jax_persistent_cache_min_compile_time_secs",
    "jax_disable_most_optimizations",
    "jax_default_matmul_precision",
)


#: Worker processes run one task at a time on one core: BLAS runs single-threaded in them.
#: (OpenBLAS's threads, started at import and left to roam, made two workers on two cores run
#: the fits of a selection slower than one process; one thread each, the same bits.)
_BLAS_LIMIT: list = []


#: The environment variables by which the BLAS libraries (and OpenMP) read their thread count
#: when they are loaded.
BLAS_THREAD_VARIABLES = (
    "OPENBLAS_NUM_THREADS",
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "BLIS_NUM_THREADS",
)


def single_threaded_blas() -> None:
    """One thread for every BLAS library (OpenBLAS, MKL, BLIS) of this process and of the worker
    processes it starts, for the rest of the process: those loaded already through
    ``threadpoolctl``, those loaded later (SciPy's own OpenBLAS, imported on first use) and the
    workers' through the environment (a count the user set is kept)."""
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    if not _BLAS_LIMIT:
        _BLAS_LIMIT.append(threadpool_limits(limits=1))


def worker_start(options: dict) -> None:
    """A worker process's JAX: one CPU device, float64, the parent's options; BLAS on one
    thread; a quick exit (:mod:`rbjax._exit`)."""
    single_threaded_blas()
    skip_final_collection()
    jax.config.update("jax_platforms", "cpu")
    try:
        jax.config.update("jax_num_cpu_devices", 1)
    except RuntimeError:  # a Dask worker whose JAX already runs (an earlier run): as it is
        pass
    jax.config.update("jax_enable_x64", True)
    for name, value in options.items():
        jax.config.update(name, value)


def _local_pool(n: int, options: dict) -> cf.ProcessPoolExecutor:
    return cf.ProcessPoolExecutor(
        max_workers=n,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=worker_start,
        initargs=(options,),
    )


#: The local pools of this process, by worker count and JAX options: kept until the process
#: ends, so that a second study (or the selection after its data are read) finds its workers
#: started, their imports done and their programs loaded.
_POOLS: dict[tuple, cf.ProcessPoolExecutor] = {}


def local_pool(n: int) -> cf.ProcessPoolExecutor:
    """This process's pool of ``n`` local workers with its current JAX options (made on first
    use, kept until the process ends or a worker dies)."""
    options = {k: jax.config.values[k] for k in INHERITED_OPTIONS if k in jax.config.values}
    key = (n, tuple(sorted(options.items())))
    pool = _POOLS.get(key)
    if pool is None:
        pool = _POOLS[key] = _local_pool(n, options)
    return pool


def drop_pool(pool: cf.ProcessPoolExecutor) -> None:
    for key, value in list(_POOLS.items()):
        if value is pool:
            del _POOLS[key]
    pool.shutdown(wait=False, cancel_futures=True)


@atexit.register
def shutdown_pools() -> None:
    """Stop every local pool of this process (at exit; or to free the workers' memory)."""
    for pool in list(_POOLS.values()):
        pool.shutdown(wait=True, cancel_futures=True)
    _POOLS.clear()


def warm() -> None:
    """Imports JAX and the fit (a worker's first task would otherwise wait for them)."""
    import rbjax.fit  # noqa: F401  (lazy: this import is the worker's warm-up)

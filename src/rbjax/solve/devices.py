"""Forward batches split over the local devices, each device running its own program: the engine
under ``simulate`` (concrete inputs) and ``rbjax.solve.batch.evaluate``.

A batch of N independent impacts is cut into chunks of at most ``Parallel.chunk_size`` rows
(:meth:`rbjax.solve.parallel.Parallel.device_plan`: even chunks, a multiple of ``ALIGN`` rows
where there are several, the last one padded with copies of the last row, so that every call
has one shape: one compiled program); the chunks go
round-robin to the devices, each chunk put on its device with ``jax.device_put`` and given to
the same ``jax.jit`` function. JAX dispatches asynchronously, so the devices run at once, each
its own program: no collective operation and no lockstep (a while loop of the ODE on one device
never waits for another device's rows). The outputs come back to the host in order.

* The chunks do not depend on the number of devices: every row is computed by the same program
  in the same chunk whatever the number of devices, so the results are those of a one-device
  run bit for bit. (XLA:CPU's result for a row can depend on the chunk's length: a length that
  is not a multiple of the vector width, or a split of the loop over threads, rounds some rows
  differently.) So a batch of one chunk runs on one device, and a batch uses at most as many
  devices as it has chunks.
* ``jax.jit`` compiles a program once per device (the executable is bound to its device). The
  first chunk of each device is dispatched from a thread of its own, so those compiles run at
  once; the command line's persistent compilation cache keeps each of them for the next run.
* The chunks also keep a CPU's working set in its caches: on one CPU device the quadrature
  runs about twice as fast in chunks of 16 384 impacts as in one call of 2¹⁸
  (``rbjax.solve.parallel.CPU_CHUNK_SIZE``).

(``jax.jit`` with a ``NamedSharding`` of the batch would compile one program for all devices,
but its partitioner turns a vmapped while loop's condition into an all-reduce over the devices,
so every device steps in lockstep with the slowest row anywhere; ``jax.shard_map`` avoids that,
but rounds a few operations differently from the one-device program, and the event root finder
of the ODE (lineax) fails inside it.)

Devices
-------
JAX gives a Python process ONE CPU device unless told otherwise, and one device runs one chunk
at a time (XLA's own threads add little to it). To split over every core, set the count before
JAX starts: in the shell, ::

    JAX_NUM_CPU_DEVICES=16 python my_study.py

or first thing in the script (before any JAX computation)::

    import jax
    jax.config.update("jax_num_cpu_devices", 16)  # or rbjax.commands.use_cpu_devices()

The command line (``rbjax simulate``, ``sweep``, ``sensitivity``, ``room``, ``design``) does it
for you: one CPU device per usable core (``--devices N`` where offered: N of them, and a batch
split over them, ``Parallel(devices=N)``). GPUs are used as JAX lists them
(``jax.local_devices()``; ``Parallel(devices=...)`` chooses among them).
"""

from __future__ import annotations

import functools
import sys
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import jax
import numpy as np
from tqdm import tqdm  # a text bar on stderr, also inside notebooks

from .parallel import Parallel, parallel_or_default

#: Chunks each device may have dispatched and not yet collected.
IN_FLIGHT_PER_DEVICE = 2


@functools.lru_cache(maxsize=64)
def cached_jit(fn: Callable) -> Callable:
    return jax.jit(fn)


def _host_leaves(inputs) -> tuple[list[np.ndarray], object, int]:
    leaves, treedef = jax.tree_util.tree_flatten(inputs)
    leaves = [np.asarray(x) for x in leaves]
    if not leaves or leaves[0].ndim == 0:
        raise ValueError("inputs must be a pytree of arrays with a leading batch axis")
    n = leaves[0].shape[0]
    if n == 0 or any(x.shape[:1] != (n,) for x in leaves):
        raise ValueError(
            f"inputs must share a non-empty leading axis; got shapes {[x.shape for x in leaves]}"
        )
    return leaves, treedef, n


def device_map(
    fn: Callable,
    inputs,
    shared=(),
    *,
    parallel: Parallel | None = None,
    path: str = "ode",
    width: int = 1,
    progress: bool = False,
    desc: str | None = None,
):
    """Apply a batched ``fn(inputs_chunk, shared)`` over the leading axis of ``inputs``, split
    over the local devices of ``parallel`` (default ``Parallel()``: all of them), each running
    its own program.

    ``inputs`` is a pytree of arrays with a common leading length N; ``shared`` a pytree of
    arrays given whole to every device. ``fn`` must be a pure JAX function of any batch length
    (e.g. vmapped) whose outputs all have the leading batch axis; it is jitted here (pass the
    same object again to reuse its compiled programs). Chunks of at most
    ``parallel.chunk_rows(path, devices, width)`` rows (:meth:`Parallel.device_plan`) go
    round-robin to the devices. Returns ``fn``'s output pytree as NumPy arrays of length N.

    Raises:
        RuntimeError: in a multi-process JAX runtime (``jax.distributed``): hosts share a study
            as independent tasks (``rbjax sweep --scheduler ADDRESS``, a Dask cluster, or
            ``--shard I/P`` and ``--merge``, a job array;
            :mod:`rbjax.studies.parallel.executors`), never as one program stepping in lockstep
            across them.
    """
    if jax.process_count() > 1:
        raise RuntimeError(
            f"this JAX runtime spans {jax.process_count()} processes (jax.distributed): rbjax "
            "runs a batch on one process's devices; share a study between hosts with "
            "`rbjax sweep --scheduler ADDRESS` (a Dask cluster) or `--shard I/P` and `--merge`"
        )
    parallel = parallel_or_default(parallel)
    devices = parallel.local_devices()
    leaves, treedef, n = _host_leaves(inputs)
    used, chunks = Parallel.device_plan(n, len(devices), parallel.chunk_rows(path, devices, width))
    chunk = chunks[0][1] - chunks[0][0]
    devices = devices[:used]
    n_chunks = len(chunks)
    program = cached_jit(fn)
    shared_leaves, shared_def = jax.tree_util.tree_flatten(shared)
    on_device = [
        jax.tree_util.tree_unflatten(
            shared_def, [jax.device_put(np.asarray(x), d) for x in shared_leaves]
        )
        for d in devices
    ]

    def dispatch(k: int):
        lo, hi = chunks[k]
        pad = chunk - (hi - lo)
        piece = [
            np.concatenate([x[lo:hi], np.repeat(x[hi - 1 : hi], pad, axis=0)]) if pad else x[lo:hi]
            for x in leaves
        ]
        device = k % used
        rows = jax.device_put(jax.tree_util.tree_unflatten(treedef, piece), devices[device])
        return program(rows, on_device[device])

    outs: list[np.ndarray] = []
    out_def = None

    def collect(k: int, result) -> None:
        nonlocal out_def
        got, out_def = jax.tree_util.tree_flatten(result)
        if not outs:
            outs.extend(np.empty((n, *np.shape(x)[1:]), dtype=x.dtype) for x in got)
        lo, hi = chunks[k]
        for full, part in zip(outs, got):
            full[lo:hi] = np.asarray(part)[: hi - lo]

    pending: deque = deque()
    with tqdm(
        total=n, desc=desc, unit="eval", file=sys.stderr, disable=not progress, leave=False
    ) as bar:

        def drain(keep: int) -> None:
            while len(pending) > keep:
                k, result = pending.popleft()
                collect(k, result)
                bar.update(chunks[k][1] - chunks[k][0])

        # the first chunk traces (and compiles for device 0) here; the other devices' first
        # chunks compile their own programs at once, one thread each
        pending.append((0, dispatch(0)))
        first = range(1, min(used, n_chunks))
        if len(first):
            with ThreadPoolExecutor(len(first)) as pool:
                pending.extend(zip(first, pool.map(dispatch, first)))
        for k in range(used, n_chunks):
            pending.append((k, dispatch(k)))
            drain(IN_FLIGHT_PER_DEVICE * used)
        drain(0)
    return jax.tree_util.tree_unflatten(out_def, outs)

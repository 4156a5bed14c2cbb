"""A batched map over every JAX device: the engine under ``rbjax.solve.batch``.

In one process, :func:`sharded_map` is :func:`rbjax.solve.devices.device_map`: chunks of
``chunk_size`` samples go round-robin to the local devices, each device running its own
program (no collective, no lockstep; the results are those of a one-device run bit for bit).

Over several processes (hosts), the samples are cut into steps of ``chunk_size × number of
devices``; each step is a global array laid out over a one-axis ``jax.sharding.Mesh`` (axis
``"batch"``) by a ``NamedSharding``, and ``jax.jit`` with those in/out shardings lets XLA's SPMD
partitioner split the vmapped work over the devices, every device computing its own
``chunk_size`` samples. The last step is padded with copies of the last sample and the padding
is dropped afterwards. Each sample is computed independently, so the results agree with a
one-device run to the last bits (not bit for bit: XLA compiles the partitioned program
separately, which can change the rounding of a few operations, ~1e-16 relative), but the
partitioner turns the condition of a vmapped while loop (the ODE) into an all-reduce, so the
devices step together. (``jax.shard_map`` is not used: inside it, the linear solve of the event
root finder (lineax, via optimistix) rejects its own operands, whose shape structs carry the
manual mesh axis.)

Devices
-------
One process, all local devices: nothing to do — ``jax.local_devices()`` is used. JAX gives a
process one CPU device unless told otherwise; to use several on a CPU, set the count before
JAX starts (the command line does, one per core)::

    JAX_NUM_CPU_DEVICES=4 python my_study.py

Several hosts (e.g. a GPU cluster): run the same program on every host, with the same config
and seed, and initialise JAX's distributed runtime before any computation. Under SLURM, Open MPI
or on Cloud TPU the coordinates are detected, and the command line does it with
``--distributed``::

    srun --nodes=4 --ntasks-per-node=1 rbjax sweep config.toml --distributed --out out.json

or, by hand, in a small launcher started once per host::

    import jax
    jax.distributed.initialize(coordinator_address="host0:1234", num_processes=4, process_id=RANK)
    from rbjax.studies.sweep import load_config, run_sweep, write_outputs
    config = load_config("config.toml")
    result = run_sweep(config)
    if jax.process_index() == 0:
        write_outputs(result, "out.json", config)

``jax.devices()`` then lists the devices of all hosts; every process draws the same samples
(the seed fixes them), builds each global batch with ``jax.make_array_from_callback`` (a
process supplies only the shards of its own devices) and gathers the outputs with
``jax.experimental.multihost_utils.process_allgather``, so every process ends with the full
result and one of them writes it.

"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable

import jax
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from .._validate import check_range
from .devices import device_map

BATCH_AXIS = "batch"


# ----------------------------------------------------------------------------------------------
# Sharded batched map.


def _global_array(x: np.ndarray, sharding) -> jax.Array:
    """A global array laid out by ``sharding`` (each process supplies its own shards)."""
    return jax.make_array_from_callback(x.shape, sharding, lambda index: x[index])


def _to_host(x: jax.Array) -> np.ndarray:
    if jax.process_count() > 1:
        from jax.experimental import multihost_utils

        return np.asarray(multihost_utils.process_allgather(x, tiled=True))
    return np.asarray(x)


@functools.lru_cache(maxsize=32)
def _sharded(fn: Callable, devices: tuple) -> Callable:
    mesh = Mesh(np.array(devices), (BATCH_AXIS,))
    batch, replicated = (
        NamedSharding(mesh, PartitionSpec(BATCH_AXIS)),
        NamedSharding(mesh, PartitionSpec()),
    )
    return jax.jit(fn, in_shardings=(batch, replicated), out_shardings=batch)


def sharded_map(
    fn: Callable,
    inputs,
    shared=(),
    *,
    chunk_size: int = 1024,
    devices=None,
    progress: bool = False,
    desc: str | None = None,
):
    """Apply a batched ``fn(inputs_chunk, shared)`` over the leading axis of ``inputs``, over
    the devices.

    ``inputs`` is a pytree of arrays with a common leading length N; ``shared`` a pytree of
    arrays given whole to every device. ``fn`` must be a pure JAX function of any batch
    length (e.g. vmapped). In one process: :func:`rbjax.solve.devices.device_map` over
    ``devices`` (default: ``jax.local_devices()``). Over several processes: steps of
    ``chunk_size × len(devices)`` samples split over a one-axis mesh of ``devices`` (default:
    ``jax.devices()``, all hosts); the last step is padded with the last sample. Returns
    ``fn``'s output pytree as NumPy arrays of length N. Pass the same ``fn`` object again to
    reuse its compiled program.
    """
    if jax.process_count() == 1:
        return device_map(
            fn,
            inputs,
            shared,
            chunk_size=chunk_size,
            devices=devices,
            progress=progress,
            desc=desc,
        )
    devices = tuple(jax.devices() if devices is None else devices)
    check_range("chunk_size", chunk_size, lower=0.0)
    chunk_size = int(chunk_size)
    leaves, treedef = jax.tree_util.tree_flatten(inputs)
    leaves = [np.asarray(x) for x in leaves]
    if not leaves or leaves[0].ndim == 0:
        raise ValueError("inputs must be a pytree of arrays with a leading batch axis")
    n = leaves[0].shape[0]
    if n == 0 or any(x.shape[:1] != (n,) for x in leaves):
        raise ValueError(
            f"inputs must share a non-empty leading axis; got shapes {[x.shape for x in leaves]}"
        )
    chunk_size = min(
        chunk_size, math.ceil(n / len(devices))
    )  # a small study pads no further than one chunk
    step = chunk_size * len(devices)
    n_steps = math.ceil(n / step)
    pad = n_steps * step - n
    leaves = [np.concatenate([x, np.repeat(x[-1:], pad, axis=0)]) if pad else x for x in leaves]

    mapped = _sharded(fn, devices)
    sharding = NamedSharding(Mesh(np.array(devices), (BATCH_AXIS,)), PartitionSpec(BATCH_AXIS))
    replicated = NamedSharding(sharding.mesh, PartitionSpec())
    shared = jax.tree_util.tree_map(lambda x: _global_array(np.asarray(x), replicated), shared)

    from tqdm import tqdm  # a text bar on stderr, also inside notebooks

    outs = []
    with tqdm(
        total=n, desc=desc, unit="eval", file=sys.stderr, disable=not progress, leave=False
    ) as bar:
        for k in range(n_steps):
            chunk = [_global_array(x[k * step : (k + 1) * step], sharding) for x in leaves]
            out = mapped(jax.tree_util.tree_unflatten(treedef, chunk), shared)
            outs.append(jax.tree_util.tree_map(_to_host, out))
            bar.update(min(step, n - k * step))
    return jax.tree_util.tree_map(lambda *xs: np.concatenate(xs)[:n], *outs)

"""A batched map over every local JAX device: the engine under ``rbjax.solve.batch``.

:func:`sharded_map` is :func:`rbjax.solve.devices.device_map`: chunks of ``chunk_size``
samples go round-robin to the local devices, each device running its own program (no
collective, no lockstep; the results are those of a one-device run bit for bit).

Devices
-------
JAX gives a process one CPU device unless told otherwise; to use several on a CPU, set the
count before JAX starts (the command line does, one per core)::

    JAX_NUM_CPU_DEVICES=4 python my_study.py

Several hosts
-------------
One JAX process runs one piece of work; hosts share a study as independent tasks, never as
one program stepping in lockstep across them: ``rbjax sweep --scheduler ADDRESS`` (a Dask
cluster; dask-jobqueue starts one on SLURM/PBS) or ``--shard I/P`` and ``--merge`` (a job
array), see :mod:`rbjax.studies.sweep` and :mod:`rbjax.studies.executors`. A process started
by ``jax.distributed.initialize`` is refused with that advice (the multi-host program that
was here ran untested).
"""

from __future__ import annotations

from collections.abc import Callable

import jax

from .devices import device_map


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
    the local devices (:func:`rbjax.solve.devices.device_map`).

    ``inputs`` is a pytree of arrays with a common leading length N; ``shared`` a pytree of
    arrays given whole to every device. ``fn`` must be a pure JAX function of any batch
    length (e.g. vmapped). Returns ``fn``'s output pytree as NumPy arrays of length N. Pass
    the same ``fn`` object again to reuse its compiled program.

    Raises:
        RuntimeError: in a multi-process JAX runtime (``jax.distributed``): see the module
            docstring for how several hosts share a study.
    """
    if jax.process_count() > 1:
        raise RuntimeError(
            f"this JAX runtime spans {jax.process_count()} processes (jax.distributed): rbjax "
            "runs a batch on one process's devices; share a study between hosts with "
            "`rbjax sweep --scheduler ADDRESS` (a Dask cluster) or `--shard I/P` and `--merge`"
        )
    return device_map(
        fn,
        inputs,
        shared,
        chunk_size=chunk_size,
        devices=devices,
        progress=progress,
        desc=desc,
    )

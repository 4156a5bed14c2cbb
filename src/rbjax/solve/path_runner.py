"""``simulate``'s engine: the scalar outputs of a batch of impacts on the path chosen for it.

:func:`scalar_outputs` runs one path (``"quadrature"``, ``"angle"`` or ``"ode"``, as
:func:`~rbjax.solve.path.resolve_path` chose it) over the broadcast inputs. Traced inputs,
or a call inside ``jax.jit``, are staged as one program like any JAX function. Concrete inputs
are solved on the host as one batch of rows (:class:`Rows`), cut in chunks split over the local
devices (``rbjax.solve.devices``: every row as on one device, bit for bit); there, with the
fallback on, the impacts a fast path flags ``solver_failed`` are solved again by the ODE.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._validate import is_traced
from .angle import impact_angle
from .devices import cached_jit, device_map
from .inputs import as_arrays, broadcast_inputs, padded_rows
from .ode import impact_batch
from .outcome import STATUS_CODES
from .parallel import ALIGN, Parallel, parallel_or_default
from .quadrature import DEFAULT_NODES, check_quadrature, impact_quadrature
from .solver import Solver


def scalar_outputs(
    path: str, height_m, ball, model, solver, fallback: bool, parallel: Parallel | None = None
):
    """(broadcast height, outputs, path) of the impacts of ``height_m``, ``ball`` and ``model``
    on ``path``: one staged program where the inputs are traced (or inside ``jax.jit``; no
    fallback, the path returned as given), else the concrete batch split over the devices of
    ``parallel`` (default ``Parallel()``: all local devices; ``path + "+ode"`` where the
    fallback solved some impacts again)."""
    if is_traced((height_m, ball, model)) or _staged():
        height, out = _traced_scalars(path, height_m, ball, model, solver)
        return height, out, path
    parallel = parallel_or_default(parallel)
    return _concrete_scalars(path, height_m, ball, model, solver, fallback, parallel)


def _staged() -> bool:
    """Inside ``jax.jit``, where even constants are staged: no concrete result to split."""
    return isinstance(jnp.zeros(()), jax.core.Tracer)


def _check_quadrature(path: str, height_m, ball, model) -> None:
    if path == "quadrature":
        check_quadrature(height_m, ball, model, DEFAULT_NODES)


@eqx.filter_jit
def fast_program(path: str, height_m, ball, model):
    """Broadcast, vmapped solve and reshape as ONE compiled program (one dispatch)."""

    shape, height, ball, model = broadcast_inputs(height_m, ball, model)
    solve = impact_quadrature if path == "quadrature" else impact_angle
    out = jax.vmap(solve)(height, ball, model)
    return height.reshape(shape), jax.tree_util.tree_map(lambda x: x.reshape(shape), out)


def _traced_scalars(path: str, height_m, ball, model, solver):
    """Traced inputs, or inside ``jax.jit``: one program, staged like any JAX function (no
    fallback)."""
    if path == "ode":
        shape, flat_height, flat_ball, flat_model = broadcast_inputs(height_m, ball, model)
        out = impact_batch(flat_height, flat_ball, flat_model, solver)
        return flat_height.reshape(shape), jax.tree_util.tree_map(lambda x: x.reshape(shape), out)
    _check_quadrature(path, height_m, ball, model)
    return fast_program(path, *as_arrays((height_m, ball, model)))


class Rows(NamedTuple):
    """Concrete (height, ball, model) as one batch axis on the host: the array leaves of the
    broadcast shape flattened to rows, the scalar leaves shared by every row."""

    shape: tuple
    spec: tuple  # (treedef, static part, which leaves are rows): hashable, keys the programs
    rows: tuple
    shared: tuple

    @classmethod
    def of(cls, height_m, ball, model) -> Rows:
        arrays, static = eqx.partition((height_m, ball, model), eqx.is_array_like)
        leaves, treedef = jax.tree_util.tree_flatten(arrays)
        leaves = [np.asarray(x, dtype=np.float64) for x in leaves]
        shape = np.broadcast_shapes(*(x.shape for x in leaves))
        is_row = tuple(x.ndim > 0 for x in leaves)
        rows = tuple(
            np.ascontiguousarray(np.broadcast_to(x, shape)).reshape(-1)
            for x, r in zip(leaves, is_row)
            if r
        )
        shared = tuple(x for x, r in zip(leaves, is_row) if not r)
        if not rows:  # a single impact: one row
            rows, shared, is_row = tuple(x.reshape(1) for x in leaves), (), (True,) * len(leaves)
        return cls(shape, (treedef, static, is_row), rows, shared)

    @property
    def size(self) -> int:
        return self.rows[0].shape[0]

    def take(self, index: np.ndarray) -> Rows:
        return self._replace(shape=index.shape, rows=tuple(x[index] for x in self.rows))


@functools.lru_cache(maxsize=64)
def rows_program(path: str, spec: tuple, solver: Solver):
    """The scalar solve of a chunk of rows on ``path`` (one function object per configuration:
    ``devices.device_map`` jits it once and compiles it once per device and chunk shape)."""

    treedef, static, is_row = spec

    def run(rows, shared):
        rows, shared = iter(rows), iter(shared)
        leaves = [next(rows) if r else next(shared) for r in is_row]
        height, ball, model = eqx.combine(jax.tree_util.tree_unflatten(treedef, leaves), static)
        _, height, ball, model = broadcast_inputs(height, ball, model)
        if path == "ode":
            return impact_batch(height, ball, model, solver)
        solve = impact_quadrature if path == "quadrature" else impact_angle
        return jax.vmap(solve)(height, ball, model)

    return run


def run_rows(path: str, batch: Rows, solver: Solver, parallel: Parallel):
    """ImpactScalars of the rows of ``batch`` (1-D): one call on the default device where the
    batch fits one chunk of one device (JAX arrays), else chunks split over the devices of
    ``parallel`` (NumPy arrays). One chunk of up to ``ALIGN`` rows is padded to
    :func:`bucket_rows` rows (repeating its first row; the outputs cut back), so that batches of 5
    to 8 impacts share one program."""

    fn = rows_program(path, batch.spec, solver)
    chunk = parallel.chunk_rows(path, parallel.local_devices())
    if batch.size <= chunk:  # one chunk
        n, size = batch.size, bucket_rows(batch.size, chunk)
        if size == n:
            return cached_jit(fn)(batch.rows, batch.shared)
        padded = batch.take(padded_rows(np.arange(n), size))
        return _first_rows(cached_jit(fn)(padded.rows, batch.shared), n)
    return device_map(fn, batch.rows, batch.shared, parallel=parallel, path=path)


def bucket_rows(n: int, chunk: int) -> int:
    """Rows one chunk of ``n`` rows is solved as: up to ``ALIGN`` (128) rows the next power of
    two (at most ``chunk``), so that small batches, whose sizes vary in interactive work, compile
    one program per power of two; a larger batch at its own size (a study's batch, run at one
    size, where padding would cost speed: 1 % at 10 000 heights, measured)."""
    return max(n, min(chunk, 1 << (n - 1).bit_length())) if n <= ALIGN else n


@functools.partial(jax.jit, static_argnums=1)
def _first_rows(tree, n: int):
    return jax.tree_util.tree_map(lambda x: x[:n], tree)


def _concrete_scalars(path: str, height_m, ball, model, solver, fallback: bool, parallel):
    """(broadcast height, outputs, path) of concrete inputs, split over the local devices
    (``rbjax.solve.devices``: every row as on one device, bit for bit). On a fast path with
    ``fallback``, the impacts it flags ``solver_failed`` are solved again by the ODE (the rows
    padded by ``inputs.padded_rows``, so that few shapes compile)."""
    if path != "ode":
        _check_quadrature(path, height_m, ball, model)
    # a list of heights is one array (as a pytree its floats would be leaves of their own)
    height_m = np.asarray(height_m, dtype=np.float64)
    batch = Rows.of(*as_arrays((height_m, ball, model)))
    reshape = lambda x: np.reshape(x, batch.shape)  # noqa: E731
    out = run_rows(path, batch, solver, parallel)
    failed = np.flatnonzero(np.asarray(out.status) == STATUS_CODES["solver_failed"])
    if path != "ode" and fallback and failed.size:
        redo = run_rows("ode", batch.take(padded_rows(failed)), solver, parallel)
        columns = {f.name: np.array(getattr(out, f.name)) for f in dataclasses.fields(out)}
        for name, column in columns.items():
            column[failed] = np.asarray(getattr(redo, name))[: failed.size]
        out, path = type(out)(**columns), path + "+ode"
    height = np.broadcast_to(np.asarray(height_m, dtype=np.float64), batch.shape)
    if isinstance(out.status, jax.Array):  # one call: the outputs are on the default device
        height, out = jax.device_put(height), _reshaped(out, batch.shape)
    else:  # NumPy outputs of the devices' chunks, on the default device at once
        height, out = jax.device_put((height, jax.tree_util.tree_map(reshape, out)))
    return height, out, path


@functools.partial(jax.jit, static_argnums=1)
def _reshaped(tree, shape: tuple):
    return jax.tree_util.tree_map(lambda x: x.reshape(shape), tree)

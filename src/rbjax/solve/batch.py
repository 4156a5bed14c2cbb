"""Batched impact evaluation sharded over every JAX device (the engine of sweeps and sensitivities).

A sweep evaluates the impact model (paper §2, Eq. 7) for N parameter samples: drop height,
ball parameters (§2.1–2.2) and damping/stiffening parameters. The samples are cut into steps of
``chunk_size × number of devices``; each step is a global array laid out over a one-axis
``jax.sharding.Mesh`` (axis ``"batch"``) by a ``NamedSharding``, and ``jax.jit`` with those
in/out shardings lets XLA's SPMD partitioner split the vmapped solve over the devices, every
device integrating its own ``chunk_size`` impacts. The last step is padded with copies of the
last sample and the padding is dropped afterwards. The same code runs on one CPU, several CPU
devices or GPUs; each impact is computed independently, so the results agree with a
one-device run to the last bits (not bit for bit: XLA compiles the partitioned program
separately, which can change the rounding of a few operations, ~1e-16 relative).
(``jax.shard_map`` is not used: inside it, the linear solve of the event root finder
(lineax, via optimistix) rejects its own operands, whose shape structs carry the manual
mesh axis.)

Scalar outputs (contact time, peak force, restitution, maximum deflection, status) come from
the ODE solve (``rbjax.solve.ode.impact_batch``) — or from the quadrature fast path
``rbjax.solve.quadrature.impact_quadrature_batch`` for elastic models.
The octave-band force exposure levels L_FE (§2.4, JIS A 1418-2) are computed from the blocked
force on the paper's 44.1 kHz × 1 s grid: only the contact window is integrated
(``rbjax.solve.ode.trajectory_batch``), the rest is zeros, and ``rbjax.spectrum.levels.lfe_octave_dB``
turns the record into bands. Flagged solves (status ≠ 0) give NaN outputs.

Devices
-------
One process, all local devices: nothing to do — ``jax.devices()`` is used. To try several
devices on a CPU, set the flag before JAX is imported::

    XLA_FLAGS=--xla_force_host_platform_device_count=4 rbjax sweep config.toml

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
from collections.abc import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from .._validate import check_range
from .._x64 import require_x64
from ..terms import parameters as params
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.model import Model, Solver
from .ode import impact_batch, trajectory_batch
from .simulate import PAPER_DURATION_S, PAPER_RATE_Hz, broadcast_inputs

BALL_PARAMETERS = tuple(Ball.PARAMETERS)
SCALAR_OUTPUTS = ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m")
BATCH_AXIS = "batch"


# ----------------------------------------------------------------------------------------------
# Parameters: names, and a (height, ball, model) with some of them replaced.


def parameter_names(model: Model | None = None) -> tuple[str, ...]:
    """Every continuous parameter of an impact with ``model`` (``rbjax.terms.parameters``)."""
    return params.parameter_names(1.0, JIS_RUBBER_BALL, model)


def canonical_name(name: str, model: Model | None = None) -> str:
    """The parameter called ``name`` in any letter case (``youngs_pa`` → ``youngs_Pa``)."""
    return params.canonical_name(name, JIS_RUBBER_BALL, model)


def assemble(values: Mapping, height_m, ball: Ball, model: Model):
    """(height, ball, model) with the named parameters of ``values`` replaced (arrays or tracers)."""
    return params.replace(values, height_m, ball, model)


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
    batch, replicated = NamedSharding(mesh, PartitionSpec(BATCH_AXIS)), NamedSharding(mesh, PartitionSpec())
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
    """Apply a batched ``fn(inputs_chunk, shared)`` over the leading axis of ``inputs``, sharded.

    ``inputs`` is a pytree of arrays with a common leading length N; ``shared`` a pytree of
    arrays given whole to every device. ``fn`` must be a pure JAX function of any batch
    length (e.g. vmapped). Steps of ``chunk_size × len(devices)`` samples are split over a
    one-axis mesh of ``devices`` (default: ``jax.devices()``, all hosts); the last step is
    padded with the last sample. Returns ``fn``'s output pytree as NumPy arrays of length N.
    Pass the same ``fn`` object again to reuse its compiled program.
    """
    devices = tuple(jax.devices() if devices is None else devices)
    check_range("chunk_size", chunk_size, lower=0.0)
    chunk_size = int(chunk_size)
    leaves, treedef = jax.tree_util.tree_flatten(inputs)
    leaves = [np.asarray(x) for x in leaves]
    if not leaves or leaves[0].ndim == 0:
        raise ValueError("inputs must be a pytree of arrays with a leading batch axis")
    n = leaves[0].shape[0]
    if n == 0 or any(x.shape[:1] != (n,) for x in leaves):
        raise ValueError(f"inputs must share a non-empty leading axis; got shapes {[x.shape for x in leaves]}")
    chunk_size = min(chunk_size, math.ceil(n / len(devices)))  # a small study pads no further than one chunk
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
    with tqdm(total=n, desc=desc, unit="eval", file=sys.stderr, disable=not progress, leave=False) as bar:
        for k in range(n_steps):
            chunk = [_global_array(x[k * step : (k + 1) * step], sharding) for x in leaves]
            out = mapped(jax.tree_util.tree_unflatten(treedef, chunk), shared)
            outs.append(jax.tree_util.tree_map(_to_host, out))
            bar.update(min(step, n - k * step))
    return jax.tree_util.tree_map(lambda *xs: np.concatenate(xs)[:n], *outs)


# ----------------------------------------------------------------------------------------------
# Impact sweeps.


def _quadrature_batch(model: Model):
    """The elastic-model fast path (``rbjax.solve.quadrature``); None for damped models."""
    if model.damping:
        return None
    from .quadrature import impact_quadrature_batch

    return impact_quadrature_batch


#: The history window is rounded up to a multiple of this many samples, so that sweeps with
#: slightly different longest contact times share one compiled program.
HISTORY_BLOCK = 128


@functools.lru_cache(maxsize=32)
def _impact_fn(solver: Solver, fast: bool, n_times: int, n_total: int, rate_Hz: float) -> Callable:
    """The per-device function of ``evaluate`` (cached: one compile per configuration).

    ``batch`` holds every parameter of ``parameter_names(model)`` (the varied ones and the
    nominal ones alike), so the program does not depend on which parameters vary.
    """

    def fn(batch, model):
        height, ball, model = assemble(batch, None, JIS_RUBBER_BALL, model)
        _, h, b, m = broadcast_inputs(height, ball, model)
        if n_times:  # L_FE per octave band from the zero-padded history (§2.4)
            from ..spectrum.levels import lfe_octave_dB

            times = jnp.arange(n_times) / rate_Hz
            force = trajectory_batch(h, b, m, solver, times).force_N
            force = jnp.pad(force, ((0, 0), (0, n_total - n_times)))
            return {"lfe_dB": jax.vmap(lambda f: lfe_octave_dB(f, rate_Hz))(force)}
        quadrature = _quadrature_batch(model) if fast else None
        out = quadrature(h, b, m) if quadrature else impact_batch(h, b, m, solver)
        return {"status": out.status, **{k: getattr(out, k) for k in SCALAR_OUTPUTS}}

    return fn


def nominal_parameters(height_m, ball: Ball, model: Model) -> dict[str, float]:
    """Every parameter of ``parameter_names(model)`` with its nominal value."""
    return {row.name: row.value for row in params.parameter_table(float(height_m), ball, model)}


def lfe_output_names() -> tuple[str, ...]:
    """Output names of the octave-band levels: ``lfe_31.5_dB`` … ``lfe_1000_dB`` (JIS A 1418-2)."""
    from ..spectrum.bands import OCTAVE_BANDS

    return tuple(f"lfe_{band}_dB" for band in OCTAVE_BANDS)


def evaluate(
    samples: Mapping,
    *,
    height_m=1.0,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    solver: Solver | None = None,
    lfe: bool = False,
    rate_Hz: float = PAPER_RATE_Hz,
    duration_s: float = PAPER_DURATION_S,
    fast: bool = True,
    chunk_size: int = 1024,
    devices=None,
    progress: bool = False,
) -> dict[str, np.ndarray]:
    """Impact outputs for N parameter samples, sharded over the devices.

    ``samples`` maps parameter names (``parameter_names(model)``, any case) to arrays of length N;
    the other parameters keep the values of ``height_m``, ``ball`` and ``model``. Returns NumPy
    arrays of length N: ``contact_time_s``, ``peak_force_N``, ``restitution``,
    ``max_deflection_m``, ``status`` and, with ``lfe=True``, ``lfe_<band>_dB`` per octave band.
    Outputs of flagged solves (status ≠ 0) are NaN.
    """
    require_x64()
    model = Model() if model is None else model
    solver = Solver() if solver is None else solver
    if not samples:
        raise ValueError("samples is empty: give at least one parameter with an array of values")
    named = {canonical_name(k, model): np.asarray(v, dtype=np.float64).reshape(-1) for k, v in samples.items()}
    n = {v.shape[0] for v in named.values()}
    if len(n) != 1:
        raise ValueError(f"samples must all have the same length; got {dict((k, v.shape[0]) for k, v in named.items())}")
    # the constructors validate concrete values (jointly: e.g. wall < radius) and name the parameter
    assemble(named, height_m, ball, model)
    check_range("height_m", named.get("height_m", height_m), lower=0.0)
    (size,) = n
    batch = {k: np.full(size, v) for k, v in nominal_parameters(height_m, ball, model).items()} | named
    run = functools.partial(sharded_map, chunk_size=chunk_size, devices=devices, progress=progress)
    out = run(_impact_fn(solver, fast, 0, 0, float(rate_Hz)), batch, model, desc="impacts")
    if lfe:
        n_total = int(round(rate_Hz * duration_s))
        tc = out["contact_time_s"]
        longest = float(np.nanmax(tc)) if np.any(np.isfinite(tc)) else 0.0
        n_times = min(n_total, HISTORY_BLOCK * math.ceil((math.ceil(longest * rate_Hz) + 2) / HISTORY_BLOCK))
        hist = run(_impact_fn(solver, False, n_times, n_total, float(rate_Hz)), batch, model, desc="L_FE")
        flagged = out["status"] != 0
        for i, name in enumerate(lfe_output_names()):
            out[name] = np.where(flagged, np.nan, hist["lfe_dB"][:, i])
    return out


# ----------------------------------------------------------------------------------------------
# Configuration files.

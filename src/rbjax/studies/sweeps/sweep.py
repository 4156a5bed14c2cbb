"""Sweep configuration files: a TOML file → a global sensitivity study (SALib: Sobol, Morris,
eFAST, PAWN, DGSM) or a conformance probability.

The batched, sharded evaluation itself is :mod:`rbjax.solve.batch`; the methods are
:mod:`rbjax.studies.sensitivity`.

Configuration files (TOML, read with ``tomllib``; see ``rbjax/examples/sweeps/*.toml``)::

    kind = "sobol"            # "sobol", "morris", "fast", "pawn", "dgsm" or "conformance"
    seed = 0
    height_m = 1.0            # the nominal drop height (also a parameter: see below)
    outputs = ["contact_time_s", "peak_force_N", "restitution", "lfe"]
    chunk_size = 8192         # impacts per device chunk and per task step (Parallel.chunk_size)

    [ball]                    # nominal ball (defaults: rbjax.JIS_RUBBER_BALL)
    youngs_Pa = 1.6e6

    [model]                   # as in the params JSON (rbjax.terms.serialize): gas, blocked_force,
    gas = "adiabatic"         # damping = {name = "kelvin-voigt", damping_Ns_per_m = 5.0}, ...

    [solver]                  # rbjax.Solver fields: asks for the diffrax ODE with them (without
    rtol = 1e-9               # this table: the fastest exact path the model allows)

    [ranges]                  # uniform ranges of the varied parameters
    youngs_Pa = [1.2e6, 2.0e6]
    mass_kg = [2.4, 2.6]

    [sobol]                   # kind = "sobol": N base points, a power of two;
    n_base = 8192             # N (d + 2) evaluations, N (2d + 2) with second_order = true
    second_order = false
    design = "sobol"          # or "random" (pseudo-random points, to compare)
    n_bootstrap = 100
    confidence = 0.95

    [morris]                  # kind = "morris": n_trajectories (d + 1) evaluations
    n_trajectories = 500
    n_levels = 4
    optimal_trajectories = 50 # optional: keep the 50 trajectories spread farthest apart

    [fast]                    # kind = "fast": n_per_parameter d evaluations (> 4 M²)
    n_per_parameter = 1000
    interference = 4

    [pawn]                    # kind = "pawn": n_samples evaluations (Latin hypercube)
    n_samples = 2000
    n_conditioning = 10

    [dgsm]                    # kind = "dgsm": n_base (d + 1) evaluations (finite differences)
    n_base = 1024             # and exact gradients at the n_base points
    delta = 1e-4

    [conformance]             # kind = "conformance"
    n_samples = 20000
    [distributions]           # each {kind = "uniform", low, high} | {kind = "normal", mean, sd}
    height_m = {kind = "uniform", low = 0.99, high = 1.01}   # | {kind = "lognormal", median, sigma}

A method's table holds its sample size and any of its options
(``rbjax.studies.sensitivity.analysis_options``).

Where the impacts run
---------------------
A sweep is design → evaluation → analysis: SALib draws the design (or the conformance draws),
the rows are evaluated, SALib analyses the outputs. :func:`run_sweep` runs the evaluation where
its ``parallel`` (an ``rbjax.Parallel``) says:

* in this process (``Parallel(workers=1)``, the Python default): ``rbjax.solve.batch.evaluate``
  on every row at once, split over this process's JAX ``devices``
  (``rbjax.commands.use_cpu_devices`` gives one CPU device per core; GPUs as they are);
* as tasks (``workers=N``, ``scheduler=ADDRESS`` or ``executor=``): the rows are cut into
  chunks of whole ``chunk_size`` steps (:meth:`rbjax.Parallel.task_rows`), each chunk is a
  task (``rbjax.studies.parallel.rows.evaluate_chunk``, a picklable call) of
  :func:`rbjax.studies.parallel.executors.run_tasks` — a local pool of worker processes with one JAX
  CPU device each, or a Dask distributed cluster — and the chunks' outputs are joined here, in
  order, before the analysis. A task that fails names its rows and their first values; a
  worker that dies has its chunks run again; a result is never analysed with a chunk missing.

The outputs do not depend on the split: every impact is computed by itself. The one choice
``evaluate`` makes for a whole batch, the L_FE history's window and sub-steps (from the
longest and the shortest contact), is the whole design's in every chunk: with L_FE outputs a
first pass of tasks computes the contact times of every row (~1 % of the work on the fast
paths), and every chunk is evaluated with the rows of the shortest and the longest contact
beside its own. A chunked or sharded sweep equals the in-process one to rounding (~1e-16,
bit for bit where both run on one device).

A Dask cluster (``pip install 'rbjax[cluster]'``) on a batch system comes from dask-jobqueue
(``pip install dask-jobqueue``), e.g. on SLURM (``PBSCluster``, ``SGECluster``, ``LSFCluster``
alike)::

    from dask_jobqueue import SLURMCluster
    cluster = SLURMCluster(cores=8, processes=8, memory="16GB", walltime="01:00:00")
    cluster.scale(jobs=4)                      # 4 SLURM jobs of 8 single-threaded workers
    print(cluster.scheduler_address)           # tcp://10.0.0.5:8786

    rbjax sweep cfg.toml --scheduler tcp://10.0.0.5:8786 --out result.json

(or ``run_sweep(config, parallel=Parallel(scheduler=cluster.scheduler_address))``); the
workers must be able to
import rbjax, in the same version. Without a scheduler, a plain job array runs one part each
(:func:`~rbjax.studies.sweeps.parts.run_part`, ``rbjax sweep cfg.toml --shard I/P``: rows cut
deterministically, each part written with the digest of the design) and
:func:`~rbjax.studies.sweeps.parts.merge_parts` (``--merge``) joins them, refusing a missing,
repeated or foreign part, and analyses the whole.
"""

from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ...solve.batch import (
    BALL_PARAMETERS,
)
from ...solve.options import EvaluationSpec
from ...solve.parallel import Parallel, parallel_or_default
from ...solve.solver import Solver
from ...terms.ball import JIS_RUBBER_BALL
from ...terms.serialize import model_from_dict, to_json
from .. import sensitivity as sens

SWEEP_KINDS = (*sens.ANALYSES, "conformance")
CONFIG_KEYS = (
    "kind",
    "seed",
    "height_m",
    "outputs",
    "chunk_size",
    "ball",
    "model",
    "solver",
    "ranges",
    "distributions",
    *SWEEP_KINDS,
)
#: Sample sizes of a method whose table does not give one.
DEFAULT_SIZES = {"sobol": 1024, "morris": 100, "fast": 1000, "pawn": 1000, "dgsm": 1024}


def load_config(path) -> dict:
    """Read a sweep configuration (TOML) into a dict (see the module docstring).

    Args:
        path: the TOML file (a path or a string).

    Returns:
        The configuration, a dict as ``tomllib`` reads it (not checked here: :func:`run_sweep`
        checks it).

    Raises:
        ValueError: the file cannot be read or is not valid TOML.
    """
    try:
        with open(path, "rb") as fh:
            config = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ValueError(f"config={str(path)!r}: cannot read TOML ({err})") from err
    return config


def _base(config: dict):

    ball_fields = config.get("ball", {})
    if not isinstance(ball_fields, dict):
        raise ValueError(f"ball = {ball_fields!r}: expected a [ball] table")
    unknown = set(ball_fields) - set(BALL_PARAMETERS)
    if unknown:
        raise ValueError(
            f"[ball] has unknown keys {sorted(unknown)}; valid: {', '.join(BALL_PARAMETERS)}"
        )
    ball = JIS_RUBBER_BALL.replace(**{k: float(v) for k, v in ball_fields.items()})
    model = model_from_dict(config.get("model", {}))
    if "solver" not in config:  # the fastest exact path
        return float(config.get("height_m", 1.0)), ball, model, None
    solver_fields = config["solver"]
    valid = [f.name for f in dataclasses.fields(Solver)]
    unknown = set(solver_fields) - set(valid)
    if unknown:
        raise ValueError(f"[solver] has unknown keys {sorted(unknown)}; valid: {', '.join(valid)}")
    return float(config.get("height_m", 1.0)), ball, model, Solver(**solver_fields)


def sweep_parallel(config: dict, parallel: Parallel | None) -> Parallel:
    """``parallel`` (default ``Parallel(workers=1)``) with the ``chunk_size`` of ``config``
    where it gives none itself."""
    parallel = parallel_or_default(parallel, Parallel(workers=1))
    if parallel.chunk_size is None and config.get("chunk_size") is not None:
        return parallel.replace(chunk_size=int(config["chunk_size"]))
    return parallel


def run_study(config: dict, *, parallel: Parallel | Callable, progress: bool):
    """Check ``config`` and run its study, the design's rows evaluated where ``parallel``
    says (an ``rbjax.Parallel``, or an evaluator: see
    :func:`rbjax.studies.sensitivity.global_sensitivity`)."""
    unknown = set(config) - set(CONFIG_KEYS)
    if unknown:
        raise ValueError(
            f"config has unknown keys {sorted(unknown)}; valid: {', '.join(CONFIG_KEYS)}"
        )
    kind = config.get("kind")
    if kind not in SWEEP_KINDS:
        raise ValueError(f"kind={kind!r} is not a known sweep; valid: {', '.join(SWEEP_KINDS)}")
    height_m, ball, model, solver = _base(config)
    common = dict(
        height_m=height_m,
        ball=ball,
        model=model,
        seed=int(config.get("seed", 0)),
        evaluation=EvaluationSpec(solver=solver, progress=progress),
        parallel=parallel,
    )
    if kind == "conformance":
        section = config.get("conformance", {})
        distributions = config.get("distributions")
        if not distributions:
            raise ValueError("a conformance sweep needs a [distributions] table")
        return sens.conformance_probability(
            int(section.get("n_samples", 10_000)),
            distributions,
            confidence=float(section.get("confidence", 0.95)),
            **common,
        )
    ranges = config.get("ranges")
    if not ranges:
        raise ValueError(f"a {kind} sweep needs a [ranges] table of [low, high] per parameter")
    outputs = config.get("outputs", ("contact_time_s", "peak_force_N", "restitution"))
    if isinstance(outputs, str) or not isinstance(outputs, (list, tuple)):
        raise ValueError(f"outputs = {outputs!r}: expected a list of output names")
    if not isinstance(config.get(kind, {}), dict):
        raise ValueError(f"{kind} = {config[kind]!r}: expected a [{kind}] table")
    options = dict(config.get(kind, {}))
    size = sens.size_name(kind)
    valid = (size, *sens.analysis_options(kind))
    unknown = set(options) - set(valid)
    if unknown:
        raise ValueError(f"[{kind}] has unknown keys {sorted(unknown)}; valid: {', '.join(valid)}")
    n = options.pop(size, DEFAULT_SIZES[kind])
    return sens.global_sensitivity(
        ranges, n, analysis=kind, outputs=tuple(outputs), **options, **common
    )


def run_sweep(
    config: dict,
    *,
    progress: bool = False,
    parallel: Parallel | None = None,
):
    """Run a sweep configuration (see the module docstring); returns the study's result object.

    Args:
        config: the configuration (``load_config``).
        progress: progress bars on stderr.
        parallel: where the rows run, an ``rbjax.Parallel`` (its ``chunk_size`` default: the
            configuration's). Default ``Parallel(workers=1)`` (a library call starts no
            processes, and the in-process evaluation already spreads over this process's
            ``devices``): every row in this process, exactly as ``rbjax.solve.batch.evaluate``;
            ``workers=N > 1``: chunks on a pool of N local worker processes (at most the usable
            cores), one JAX CPU device each; ``workers=None``: one worker per usable core (the
            command line's default); ``scheduler``: the address of a Dask scheduler
            (``"tcp://host:8786"``, e.g. a dask-jobqueue cluster's ``scheduler_address``:
            module docstring), the chunks run on its workers (one that does not answer within
            ``rbjax.studies.parallel.executors.CONNECT_TIMEOUT_S`` is a ``ValueError``);
            ``executor``: a ``concurrent.futures.Executor`` of the caller's (not closed here).

    Returns:
        The study's result, by ``kind``: ``"sobol"`` → ``rbjax.studies.sensitivity.SobolResult``,
        ``"morris"`` → ``MorrisResult``, ``"fast"`` → ``FastResult``, ``"pawn"`` →
        ``PawnResult``, ``"dgsm"`` → ``DGSMResult``, ``"conformance"`` →
        ``ConformanceProbability``. Each has ``.to_dict()`` (the JSON summary) and
        ``.samples`` (the inputs and outputs of every evaluation).

    Raises:
        ValueError: a configuration with unknown keys or tables, an unknown ``kind``, a
            missing ``[ranges]`` (or ``[distributions]``) table, a bad ``outputs`` list or
            analysis option; ``parallel`` not an ``rbjax.Parallel``, or a scheduler that does
            not answer.
        rbjax.studies.parallel.executors.TaskError: a chunk failed (the message names its rows and
            their first values), or its local worker died more often than allowed.
    """
    return run_study(config, parallel=sweep_parallel(config, parallel), progress=progress)


def write_outputs(result, path, config: dict | None = None) -> list[Path]:
    """Write a study's summary as JSON to ``path`` and its samples as ``.npz`` beside it.

    The summary is ``result.to_dict()``, with the ``config`` that produced it when given.

    JSON (the summary: indices, probabilities, confidence intervals) is plain text that any
    language reads; NumPy ``.npz`` keeps the N × (inputs + outputs) samples compact, in float64,
    with their names (``np.load``).

    Args:
        result: the study's result (:func:`run_sweep`): its ``to_dict()`` and ``samples``.
        path: the JSON file to write; the samples go beside it, its suffix replaced by
            ``.samples.npz``.
        config: the configuration to record in the summary (``None``: not recorded).

    Returns:
        The paths written: ``[path, samples]``.
    """
    path = Path(path)
    summary = result.to_dict() if config is None else {"config": config, **result.to_dict()}
    path.write_text(to_json(summary) + "\n")
    samples = path.with_suffix(".samples.npz")
    np.savez_compressed(samples, **result.samples)
    return [path, samples]

"""Sweep configuration files: a TOML file → a global sensitivity study (SALib: Sobol, Morris,
eFAST, PAWN, DGSM) or a conformance probability.

The batched, sharded evaluation itself is :mod:`rbjax.solve.batch`; the methods are
:mod:`rbjax.studies.sensitivity`.

Configuration files (TOML, read with ``tomllib``; see ``rbjax/examples/sweeps/*.toml``)::

    kind = "sobol"            # "sobol", "morris", "fast", "pawn", "dgsm" or "conformance"
    seed = 0
    height_m = 1.0            # the nominal drop height (also a parameter: see below)
    outputs = ["contact_time_s", "peak_force_N", "restitution", "lfe"]
    chunk_size = 8192         # impacts per device per step (default: sized per solve path)

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
(``rbjax.studies.sensitivity.method_options``).

Where the impacts run
---------------------
A sweep is design → evaluation → analysis: SALib draws the design (or the conformance draws),
the rows are evaluated, SALib analyses the outputs. :func:`run_sweep` runs the evaluation

* in this process (``workers=1``, the Python default): ``rbjax.solve.batch.evaluate`` on every
  row at once, sharded over this process's JAX devices (``rbjax.commands.use_cpu_devices``
  gives one CPU device per core; GPUs as they are);
* as tasks (``workers=N``, ``scheduler=ADDRESS`` or ``executor=``; the command line's default
  is one worker per usable core): the rows are cut into chunks of whole ``chunk_size`` steps,
  each chunk is a task (``rbjax.studies.chunks.evaluate_chunk``, a picklable call) of
  :func:`rbjax.studies.executors.run_tasks` — a local pool of worker processes with one JAX
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

(or ``run_sweep(config, scheduler=cluster.scheduler_address)``); the workers must be able to
import rbjax, in the same version. Without a scheduler, a plain job array runs one part each
(:func:`run_part`, ``rbjax sweep cfg.toml --shard I/P``: rows cut deterministically, each part
written with the digest of the design) and :func:`merge_parts` (``--merge``) joins them,
refusing a missing, repeated or foreign part, and analyses the whole.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tomllib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..solve.batch import (  # noqa: F401  (re-exported: the sweep's public names)
    BALL_PARAMETERS,
    SCALAR_OUTPUTS,
    assemble,
    canonical_name,
    evaluate,
    lfe_output_names,
    nominal_parameters,
    parameter_names,
    sharded_map,
)
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.model import Solver
from ..terms.serialize import to_json
from . import sensitivity as sens
from .chunks import evaluate_rows, row_count, task_evaluator, unflatten
from .executors import Parallel

SWEEP_KINDS = (*sens.METHODS, "conformance")
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
#: The marker of a part file (``run_part``), and its format's version.
PART_FORMAT = "rbjax-sweep-part/1"


def load_config(path) -> dict:
    """Read a sweep configuration (TOML) into a dict; ``ValueError`` if unreadable."""
    try:
        with open(path, "rb") as fh:
            config = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as err:
        raise ValueError(f"config={str(path)!r}: cannot read TOML ({err})") from err
    return config


def _base(config: dict):
    from ..terms.serialize import model_from_dict

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


def _study(config: dict, *, evaluator: Callable | None, progress: bool, devices):
    """Check ``config`` and run its study, the design's rows evaluated by ``evaluator``."""
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
        solver=solver,
        seed=int(config.get("seed", 0)),
        chunk_size=None if config.get("chunk_size") is None else int(config["chunk_size"]),
        devices=devices,
        progress=progress,
        evaluator=evaluator,
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
    valid = (size, *sens.method_options(kind))
    unknown = set(options) - set(valid)
    if unknown:
        raise ValueError(f"[{kind}] has unknown keys {sorted(unknown)}; valid: {', '.join(valid)}")
    n = options.pop(size, DEFAULT_SIZES[kind])
    return sens.global_sensitivity(
        ranges, n, method=kind, outputs=tuple(outputs), **options, **common
    )


def run_sweep(
    config: dict,
    *,
    progress: bool = False,
    devices=None,
    workers: int | None = 1,
    scheduler: str | None = None,
    executor=None,
):
    """Run a sweep configuration (see the module docstring); returns the study's result object.

    ``kind = "sobol"`` → ``rbjax.studies.sensitivity.SobolResult``, ``"morris"`` →
    ``MorrisResult``, ``"fast"`` → ``FastResult``, ``"pawn"`` → ``PawnResult``, ``"dgsm"`` →
    ``DGSMResult``, ``"conformance"`` → ``ConformanceProbability``. Each has ``.to_dict()`` (the
    JSON summary) and ``.samples`` (the inputs and outputs of every evaluation).

    Args:
        config: the configuration (``load_config``).
        progress: progress bars on stderr.
        devices: the JAX devices of the in-process evaluation (default: all of them).
        workers: ``1`` (the default here: a library call starts no processes, and the
            in-process evaluation already spreads over this process's devices): every row in
            this process, exactly as ``rbjax.solve.batch.evaluate``; ``N > 1``: chunks on a
            pool of N local worker processes (at most the usable cores), one JAX CPU device
            each; ``None``: one worker per usable core (the command line's default). A count
            below 1 is a ``ValueError``.
        scheduler: the address of a Dask scheduler (``"tcp://host:8786"``, e.g. a
            dask-jobqueue cluster's ``scheduler_address``: module docstring): the chunks run
            on its workers. A scheduler that does not answer within
            ``rbjax.studies.executors.CONNECT_TIMEOUT_S`` is a ``ValueError``.
        executor: a ``concurrent.futures.Executor`` of the caller's for the chunks (not
            closed here).

    Raises:
        rbjax.studies.executors.TaskError: a chunk failed (the message names its rows and
            their first values), or its local worker died more often than allowed.
    """
    parallel = Parallel(workers=workers, scheduler=scheduler, executor=executor)
    evaluator = None if parallel.in_process else task_evaluator(parallel, progress)
    return _study(config, evaluator=evaluator, progress=progress, devices=devices)


# ----------------------------------------------------------------------------------------------
# Parts of a design, for job arrays without a scheduler: run_part, merge_parts.


@dataclasses.dataclass(frozen=True)
class _Call:
    """One evaluation a study makes: its rows, values or gradients, and ``evaluate``'s
    keyword arguments."""

    samples: dict
    gradients: bool
    settings: dict


class _Planned(Exception):
    """The planning evaluator's signal: the study's last evaluation is known."""


class _NaNs(Mapping):
    """NaN outputs of a planned evaluation that the study reads before its next one."""

    def __init__(self, n: int):
        self.n = n

    def __getitem__(self, key):
        return np.full(self.n, np.nan)

    def __iter__(self):
        return iter(())

    def __len__(self):
        return 0


def design_plan(config: dict) -> list[_Call]:
    """The evaluations of ``config``'s study, in order, without running them: its design's
    rows (one evaluation; DGSM two: the finite-difference design, then the gradients at its
    base points). The same configuration gives the same plan on every machine (the seed
    fixes the design)."""
    calls: list[_Call] = []

    def plan(samples, gradients, **settings):
        rows = {k: np.asarray(v, dtype=np.float64).reshape(-1).copy() for k, v in samples.items()}
        calls.append(_Call(rows, bool(gradients), settings))
        if config.get("kind") == "dgsm" and not gradients:
            return _NaNs(row_count(rows))
        raise _Planned

    try:
        _study(config, evaluator=plan, progress=False, devices=None)
    except _Planned:
        pass
    return calls


def design_digest(config: dict, plan: list[_Call] | None = None) -> str:
    """SHA-256 of the configuration and of its design's rows (``design_plan``): parts with the
    same digest belong to the same sweep."""
    plan = design_plan(config) if plan is None else plan
    digest = hashlib.sha256(json.dumps(config, sort_keys=True, default=str).encode())
    for call in plan:
        head = [call.gradients, row_count(call.samples), list(call.samples)]
        digest.update(json.dumps(head).encode())
        for v in call.samples.values():
            digest.update(np.ascontiguousarray(v, dtype=np.float64).tobytes())
    return digest.hexdigest()


def part_rows(n: int, part: int, parts: int) -> tuple[int, int]:
    """Rows [a, b) of part ``part`` (1 … ``parts``) of ``n`` rows: consecutive, sizes within
    one of each other."""
    return n * (part - 1) // parts, n * part // parts


def parse_part(text: str) -> tuple[int, int]:
    """``"I/P"`` → (I, P), part I of P (1 ≤ I ≤ P); else a ``ValueError`` naming it."""
    try:
        part, parts = (int(x) for x in str(text).split("/"))
    except ValueError:
        part = parts = 0
    if not 1 <= part <= parts:
        raise ValueError(
            f"--shard {text!r} is not a part: expected I/P with 1 ≤ I ≤ P (part I of P), "
            "e.g. 1/4 … 4/4"
        )
    return part, parts


def _check_part(part, parts) -> tuple[int, int]:
    ok = all(isinstance(x, int) and not isinstance(x, bool) for x in (part, parts))
    if not (ok and 1 <= part <= parts):
        raise ValueError(f"part={part!r} of parts={parts!r}: expected integers 1 ≤ part ≤ parts")
    return part, parts


def run_part(
    config: dict,
    part: int,
    parts: int,
    path,
    *,
    progress: bool = False,
    devices=None,
    workers: int | None = 1,
    scheduler: str | None = None,
    executor=None,
) -> Path:
    """Evaluate part ``part`` of ``parts`` of ``config``'s design and write it to ``path``.

    The rows of each evaluation (``design_plan``) are cut into ``parts`` consecutive slices
    (``part_rows``); this runs slice ``part`` where ``workers``/``scheduler``/``executor``
    say (as :func:`run_sweep`), with the whole design's L_FE window (with L_FE outputs, the
    contact times of every row are computed first: ~1 % of the work on the fast paths, but
    every part repeats it). ``path`` (NumPy ``.npz``, written whole or not at all) holds the
    outputs, the rows and the design's digest (``design_digest``), for :func:`merge_parts`.
    Returns ``path``.
    """
    part, parts = _check_part(part, parts)
    parallel = Parallel(workers=workers, scheduler=scheduler, executor=executor)
    plan = design_plan(config)
    arrays: dict[str, Any] = {}  # key "<evaluation>/<output>" → the part's rows
    calls = []
    for k, call in enumerate(plan):
        n = row_count(call.samples)
        a, b = part_rows(n, part, parts)
        calls.append({"rows": [a, b], "n": n, "gradients": call.gradients})
        if b > a:
            settings = call.settings | {"devices": devices, "progress": progress}
            label = f"part {part}/{parts}" + (" gradients" if call.gradients else "")
            flat = evaluate_rows(
                parallel,
                call.samples,
                call.gradients,
                settings,
                (a, b),
                progress=progress,
                label=label,
            )
            arrays.update({f"{k}/{name}": v for name, v in flat.items()})
    from .. import __version__

    meta = {
        "format": PART_FORMAT,
        "digest": design_digest(config, plan),
        "part": part,
        "parts": parts,
        "kind": config.get("kind"),
        "rbjax": __version__,
        "calls": calls,
    }
    path = Path(path)
    partial = path.with_name(f".{path.name}.{os.getpid()}.partial")
    try:
        with open(partial, "wb") as fh:
            np.savez_compressed(fh, meta=np.array(json.dumps(meta)), **arrays)
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)
    return path


def _read_part(path: Path) -> tuple[dict, dict]:
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {k: data[k] for k in data.files if k != "meta"}
        if meta.get("format") != PART_FORMAT:
            raise ValueError(f"format {meta.get('format')!r}, expected {PART_FORMAT!r}")
    except Exception as err:  # noqa: BLE001  (any unreadable file: one named error)
        raise ValueError(
            f"{str(path)!r} is not a part of an rbjax sweep ({type(err).__name__}: {err})"
        ) from None
    return meta, arrays


def merge_parts(config: dict, paths: Sequence, *, progress: bool = False):
    """Join the parts of ``config``'s design written by :func:`run_part` and analyse them: the
    same result object as :func:`run_sweep`, equal to a single run's.

    Every part 1 … P must be given once, all with this configuration's design digest; a
    missing, repeated or foreign part (another configuration, seed, size or split) is a
    ``ValueError`` naming it, and nothing is analysed.
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ValueError("merge: no part files given")
    plan = design_plan(config)
    digest = design_digest(config, plan)
    found: dict[int, tuple[Path, dict, dict]] = {}
    first: tuple[Path, int] | None = None
    for path in paths:
        meta, arrays = _read_part(path)
        if meta["digest"] != digest:
            raise ValueError(
                f"{str(path)!r} is a part of another sweep: its design digest "
                f"{meta['digest'][:12]}… differs from this configuration's {digest[:12]}… (the "
                "configuration, seed and sizes must be those the parts were run with)"
            )
        part, parts = int(meta["part"]), int(meta["parts"])
        if first is None:
            first = (path, parts)
        elif parts != first[1]:
            raise ValueError(
                f"{str(path)!r} is part {part} of {parts}, but {str(first[0])!r} is a part of "
                f"{first[1]}: the parts of one split must be merged together"
            )
        if part in found:
            raise ValueError(
                f"part {part}/{parts} is given twice: {str(found[part][0])!r} and {str(path)!r}"
            )
        found[part] = (path, meta, arrays)
    assert first is not None
    parts = first[1]
    missing = [i for i in range(1, parts + 1) if i not in found]
    if missing:
        raise ValueError(
            f"parts {', '.join(f'{i}/{parts}' for i in missing)} are missing (given: "
            f"{', '.join(str(p) for p in paths)}): a merged result needs every part"
        )
    outputs = []
    for k, call in enumerate(plan):
        n = row_count(call.samples)
        pieces = []
        for i in range(1, parts + 1):
            path, meta, arrays = found[i]
            a, b = part_rows(n, i, parts)
            if meta["calls"][k]["rows"] != [a, b]:
                raise ValueError(f"{str(path)!r}: rows {meta['calls'][k]['rows']}, not {[a, b]}")
            if b > a:
                prefix = f"{k}/"
                pieces.append(
                    {x[len(prefix) :]: v for x, v in arrays.items() if x.startswith(prefix)}
                )
        flat = {x: np.concatenate([p[x] for p in pieces]) for x in pieces[0]}
        if any(len(v) != n for v in flat.values()):
            raise ValueError(f"merge: the parts hold {len(flat)} outputs of the wrong length")
        outputs.append(flat)
    served: list[int] = []

    def replay(samples, gradients, **settings):
        k = len(served)
        call = plan[k] if k < len(plan) else None
        same = (
            call is not None
            and bool(gradients) == call.gradients
            and list(samples) == list(call.samples)
            and all(np.array_equal(np.reshape(samples[x], -1), call.samples[x]) for x in samples)
        )
        if not same:
            raise RuntimeError("merge: the study asked for rows outside its planned design")
        served.append(k)
        return unflatten(outputs[k], bool(gradients))

    return _study(config, evaluator=replay, progress=progress, devices=None)


def write_outputs(result, path, config: dict | None = None) -> list[Path]:
    """Write a study's summary as JSON to ``path`` and its samples as ``.npz`` beside it.

    The summary is ``result.to_dict()``, with the ``config`` that produced it when given.

    JSON (the summary: indices, probabilities, confidence intervals) is plain text that any
    language reads; NumPy ``.npz`` keeps the N × (inputs + outputs) samples compact, in float64,
    with their names (``np.load``). Returns the paths written.
    """
    path = Path(path)
    summary = result.to_dict() if config is None else {"config": config, **result.to_dict()}
    path.write_text(to_json(summary) + "\n")
    samples = path.with_suffix(".samples.npz")
    np.savez_compressed(samples, **result.samples)
    return [path, samples]

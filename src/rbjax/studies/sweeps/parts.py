"""Parts of a sweep's design, for job arrays without a scheduler: :func:`run_part` evaluates
one of P consecutive slices of every evaluation's rows and writes it with the design's digest;
:func:`merge_parts` joins all P parts and replays them through the study (its analysis as a
single run would do it).

The design is read by running the study with a planning evaluator (:func:`design_plan`), so
the parts follow whatever evaluations a method makes (Sobol's matrices, DGSM's gradients).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ... import __version__
from ...solve.parallel import Parallel, cut_rows
from ..parallel.rows import evaluate_rows, row_count, unflatten
from .sweep import run_study, sweep_parallel

#: The marker of a part file (``run_part``), and its format's version.
PART_FORMAT = "rbjax-sweep-part/1"


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
        run_study(config, parallel=plan, progress=False)
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
    one of each other (:func:`rbjax.solve.parallel.cut_rows`)."""
    return cut_rows(0, n, parts=parts)[part - 1]


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
    parallel: Parallel | None = None,
) -> Path:
    """Evaluate part ``part`` of ``parts`` of ``config``'s design and write it to ``path``.

    The rows of each evaluation (``design_plan``) are cut into ``parts`` consecutive slices
    (``part_rows``); this runs slice ``part`` where ``parallel`` says (as in
    :func:`~rbjax.studies.sweeps.sweep.run_sweep`), with the whole design's L_FE window (with
    L_FE outputs, the contact times of every row are computed first: ~1 % of the work on the
    fast paths, but every part repeats it).

    Args:
        config: the sweep configuration (:func:`~rbjax.studies.sweeps.sweep.load_config`).
        part: which part, 1 … ``parts``.
        parts: how many parts the design is cut into.
        path: the file to write (NumPy ``.npz``, written whole or not at all): the part's
            outputs, its rows and the design's digest (``design_digest``), for
            :func:`merge_parts`.
        progress: progress bars on stderr.
        parallel: an ``rbjax.Parallel``, as in :func:`~rbjax.studies.sweeps.sweep.run_sweep`
            (default ``Parallel(workers=1)``).

    Returns:
        ``path``, as a :class:`~pathlib.Path`.

    Raises:
        ValueError: ``part``/``parts`` not integers with 1 ≤ part ≤ parts, a bad
            configuration, or ``parallel`` as in :func:`~rbjax.studies.sweeps.sweep.run_sweep`.
        rbjax.studies.parallel.executors.TaskError: a chunk failed, or its local worker died more
            often than allowed.
    """
    part, parts = _check_part(part, parts)
    parallel = sweep_parallel(config, parallel)
    plan = design_plan(config)
    arrays: dict[str, Any] = {}  # key "<evaluation>/<output>" → the part's rows
    calls = []
    for k, call in enumerate(plan):
        n = row_count(call.samples)
        a, b = part_rows(n, part, parts)
        calls.append({"rows": [a, b], "n": n, "gradients": call.gradients})
        if b > a:
            spec = call.settings["evaluation"].replace(progress=progress)
            settings = {**call.settings, "evaluation": spec}
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

    Args:
        config: the sweep configuration the parts were run with.
        paths: the part files (:func:`run_part`), in any order.
        progress: progress bars on stderr.

    Returns:
        The study's result, as :func:`~rbjax.studies.sweeps.sweep.run_sweep` returns it.

    Raises:
        ValueError: no paths; a file that is not a sweep part; a part of another design or
            of another split; a part given twice or missing; a part whose rows or outputs do
            not match the design (or another part's); an evaluation of the design with 0
            rows (its parts hold no outputs); a bad configuration.
        RuntimeError: the study asks for rows outside its planned design.
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
        if n == 0:  # run_part evaluates nothing for it: no part holds its outputs' names
            raise ValueError(
                f"merge: call {k} of this configuration's design has 0 rows: the parts "
                "hold no outputs for it, and a study cannot be analysed without its rows"
            )
        pieces: list[tuple[Path, dict]] = []
        for i in range(1, parts + 1):
            path, meta, arrays = found[i]
            a, b = part_rows(n, i, parts)
            if meta["calls"][k]["rows"] != [a, b]:
                raise ValueError(f"{str(path)!r}: rows {meta['calls'][k]['rows']}, not {[a, b]}")
            if b > a:
                prefix = f"{k}/"
                piece = {x[len(prefix) :]: v for x, v in arrays.items() if x.startswith(prefix)}
                if pieces and set(piece) != set(pieces[0][1]):
                    raise ValueError(
                        f"{str(path)!r}: call {k}'s outputs {sorted(piece)} differ from "
                        f"those of {str(pieces[0][0])!r} ({sorted(pieces[0][1])})"
                    )
                pieces.append((path, piece))
        flat = {x: np.concatenate([p[x] for _, p in pieces]) for x in pieces[0][1]}
        wrong = {x: len(v) for x, v in flat.items() if len(v) != n}
        if wrong:
            raise ValueError(f"merge: call {k}'s parts hold {wrong} rows, not {n}")
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

    return run_study(config, parallel=replay, progress=progress)

"""Where a sweep's impacts run: ``rbjax sweep src/rbjax/examples/sweeps/sobol.toml`` (131 072
impacts with L_FE, SALib's analysis) in a fresh process, cold (an empty compilation cache,
``RBJAX_CACHE_DIR``) and warm (the same cache again), with ``--workers 1`` (every impact in the
command's process, sharded over one JAX CPU device per core) and ``--workers 2`` (chunks on two
worker processes of one device each, sharing the cache).

Wall time, CPU time (the command and its worker processes), and the command's own figure for the
study (after its imports). The runs' indices are compared with the first run's (they must agree
to rounding). ``--quick``: the same study with N = 256 base points (2048 impacts), cold only.

Prints a table, writes ``results/sweep_parallel.json`` (``sweep_parallel_quick.json``).
"""

from __future__ import annotations

import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from _common import REPO, finish_machine_info, machine_info, table, write_json

SOBOL_TOML = REPO / "src" / "rbjax" / "examples" / "sweeps" / "sobol.toml"
WORKERS = (1, 2)
#: Environment variables of the caller (e.g. a test session's) that would change the runs.
CLEARED = ("JAX_COMPILATION_CACHE_DIR", "JAX_DISABLE_MOST_OPTIMIZATIONS", "XLA_FLAGS")


def _sweep(config: Path, workers: int, cache: Path) -> dict:
    """``rbjax sweep CONFIG --workers N --json`` in a fresh process: wall and CPU seconds."""
    env = {k: v for k, v in os.environ.items() if k not in CLEARED}
    env["RBJAX_CACHE_DIR"] = str(cache)
    env["PYTHONPATH"] = str(REPO / "src") + os.pathsep + env.get("PYTHONPATH", "")
    command = [sys.executable, "-m", "rbjax.cli", "sweep", str(config), "--no-progress"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()[0]
    start = time.perf_counter()
    proc = subprocess.run(
        [*command, "--json", "--workers", str(workers)], env=env, capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode:
        raise RuntimeError(proc.stderr[-3000:])
    study = re.search(r"impact evaluations in ([\d.]+) s", proc.stderr)
    return {
        "workers": workers,
        "wall_s": wall,
        "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
        "study_s": float(study.group(1)) if study else None,
        "loadavg_before": load,
        "loadavg_after": os.getloadavg()[0],
        "summary": json.loads(proc.stdout),
    }


def _largest_difference(a: dict, b: dict) -> float:
    """Largest relative difference of the first- and total-order indices of two summaries."""
    worst = 0.0
    for o, entry in a["outputs"].items():
        for field in ("first_order", "total_order"):
            for p, x in entry[field].items():
                y = b["outputs"][o][field][p]
                if x is not None and y is not None:
                    worst = max(worst, abs(x - y) / max(abs(x), 1e-300))
    return worst


def main(quick: bool = False) -> None:
    info = machine_info()
    t0 = time.perf_counter()
    config = tomllib.loads(SOBOL_TOML.read_text())
    with tempfile.TemporaryDirectory(prefix="rbjax-sweep-parallel-") as tmp:
        path = SOBOL_TOML
        if quick:
            path = Path(tmp) / "sobol-quick.toml"
            path.write_text(SOBOL_TOML.read_text().replace("n_base = 16384", "n_base = 256"))
            config["sobol"]["n_base"] = 256
        runs = []
        # interleaved: a change of load hits both counts; quick: cold only
        for state in ("cold",) if quick else ("cold", "warm"):
            for workers in WORKERS:
                cache = Path(tmp) / f"cache-{workers}"  # cold: made by this run; warm: reused
                run = _sweep(path, workers, cache)
                run["state"] = state
                runs.append(run)
                print(
                    f"{state} --workers {workers}: {run['wall_s']:.1f} s wall, "
                    f"{run['cpu_s']:.1f} s CPU (load {run['loadavg_before']:.1f})",
                    flush=True,
                )
    reference = runs[0]["summary"]
    for run in runs:
        run["largest_index_difference"] = _largest_difference(reference, run["summary"])
        run["n_evaluations"] = run["summary"]["n_evaluations"]
    rows = [
        [
            r["state"],
            r["workers"],
            f"{r['wall_s']:.1f}",
            f"{r['cpu_s']:.1f}",
            f"{r['study_s']:.1f}" if r["study_s"] is not None else "—",
            f"{r['loadavg_before']:.1f} → {r['loadavg_after']:.1f}",
            f"{r['largest_index_difference']:.1e}",
        ]
        for r in runs
    ]
    print(
        table(
            [
                "cache",
                "--workers",
                "wall (s)",
                "CPU (s)",
                "study after imports (s)",
                "load average",
                "indices vs first run (rel.)",
            ],
            rows,
        )
    )
    for run in runs:
        run.pop("summary")
    path = write_json(
        "sweep_parallel" + ("_quick" if quick else ""),
        {
            "machine": finish_machine_info(info),
            "config": str(SOBOL_TOML.relative_to(REPO)),
            "n_base": config["sobol"]["n_base"],
            "runs": runs,
            "wall_s": time.perf_counter() - t0,
        },
    )
    print(f"wrote {path}")

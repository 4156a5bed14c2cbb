"""The model selection in worker processes: wall time of the command line by worker count,
cold and warm, and the agreement of the results.

Measures, on the bundled recordings, in subprocesses sharing one fresh ``RBJAX_CACHE_DIR``:

* ``rbjax fit DIR`` (no ``--model``: the full default selection, every usable core) cold (the
  empty cache: every program traced and compiled) and warm (the same command again);
* ``rbjax select DIR --workers 1`` and ``--workers N`` for N = 2 … the usable cores, warm; the
  held-out errors and the fits' residuals of every worker count are compared with
  ``--workers 1`` (relative difference; the bar is 1e-12, the design aims at 0) and the
  recommendation must be the same.

Prints a table and writes ``results/selection_workers.json``. ``--quick``: one candidate
(hunt-crossley with the momentum blocked force) instead of all, the first run cold.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

from rbjax.data import examples_dir

from _common import RESULTS_DIR, finish_machine_info, machine_info, usable_cores

QUICK = ["--candidates", "hunt-crossley", "--blocked-force", "momentum"]


def timed(argv, cache_dir) -> tuple[float, dict]:
    env = dict(os.environ, RBJAX_CACHE_DIR=str(cache_dir))
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "rbjax.cli", *argv], env=env, capture_output=True, text=True
    )
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"rbjax {' '.join(argv)} failed:\n{proc.stderr[-3000:]}")
    return elapsed, json.loads(proc.stdout)


def figures(out: dict) -> dict:
    """label → [held-out error of each fold …, residual rms] of a selection's JSON."""
    sel = out["selection"]
    return {
        f"{c['model_name']}/{c['blocked_force']}": [
            *(f["history_error_pct"] for f in c["folds"]),
            c["residual_rms_N"],
        ]
        for c in sel["candidates"]
    }


def largest_relative_difference(a: dict, b: dict) -> float:
    assert a.keys() == b.keys()
    worst = 0.0
    for k in a:
        for x, y in zip(a[k], b[k], strict=True):
            worst = max(worst, abs(x - y) / max(abs(x), 1e-300))
    return worst


def main(quick: bool = False) -> None:
    data = str(examples_dir())
    extra = QUICK if quick else []
    info = machine_info()
    cores = usable_cores()
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        fit_argv = ["fit", data, "--json", "--quiet"]
        if not quick:
            cold, _ = timed(fit_argv, cache)
            warm, out = timed(fit_argv, cache)
            rows.append(
                {
                    "command": "rbjax fit DIR (full selection, default workers)",
                    "workers": cores,
                    "cold_s": cold,
                    "warm_s": warm,
                    "recommended": out["selection"]["recommended"],
                }
            )
            print(f"rbjax fit DIR: cold {cold:.1f} s, warm {warm:.1f} s", flush=True)
        reference = None
        for workers in range(1, cores + 1):
            argv = ["select", data, *extra, "--json", "--quiet", "--workers", str(workers)]
            warm, out = timed(argv, cache)
            if reference is None:
                reference = out
            diff = largest_relative_difference(figures(reference), figures(out))
            same = out["selection"]["recommended"] == reference["selection"]["recommended"]
            rows.append(
                {
                    "command": "rbjax select DIR" + (" (1 candidate)" if quick else ""),
                    "workers": workers,
                    "warm_s": warm,
                    "largest_relative_difference": diff,
                    "same_recommendation": same,
                    "recommended": out["selection"]["recommended"],
                }
            )
            print(
                f"rbjax select --workers {workers}: warm {warm:.1f} s, largest relative "
                f"difference to --workers 1: {diff:.1e}, same recommendation: {same}",
                flush=True,
            )
    one = next(r for r in rows if r["workers"] == 1 and "select" in r["command"])
    for r in rows:
        if "select" in r["command"]:
            r["ratio_to_one_worker"] = r["warm_s"] / one["warm_s"]
    print()
    print("| command | workers | cold (s) | warm (s) | × --workers 1 | max rel. diff |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        cold = f"{r['cold_s']:.1f}" if "cold_s" in r else "—"
        ratio = f"{r['ratio_to_one_worker']:.2f}" if r.get("ratio_to_one_worker") else "—"
        diff = (
            f"{r['largest_relative_difference']:.1e}" if "largest_relative_difference" in r else "—"
        )
        print(
            f"| {r['command']} | {r['workers']} | {cold} | {r['warm_s']:.1f} | {ratio} | {diff} |"
        )
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    path = RESULTS_DIR / ("selection_workers" + ("_quick" if quick else "") + ".json")
    path.write_text(
        json.dumps({"machine": finish_machine_info(info), "quick": quick, "rows": rows}, indent=2)
    )
    print(f"wrote {path}")

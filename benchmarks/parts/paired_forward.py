"""The forward path paired against an older revision: the same timing, alternately in fresh
processes for the baseline and for this working tree, so that the load of a shared machine falls
on both (issue 42, item 5: the damped path had lost a fifth of its speed since ``fc0325d``).

    .venv/bin/python benchmarks/forward.py --only paired_forward       # against fc0325d
    .venv/bin/python benchmarks/parts/paired_forward.py --against REV [--pairs N] [--quick]

The baseline is checked out with ``git worktree add`` into a temporary folder (removed after)
and imported from there with ``PYTHONPATH``, with this environment's dependencies; each process
checks that ``rbjax`` came from where it should. One process times, after a first (compiling)
call, ``rbjax.simulate(heights, JIS_RUBBER_BALL, Model(damping=Zener(0.3, 2e-3)))`` on 10 000
heights 0.1-1.6 m (the phase-angle path; the elastic ``Model()``, the quadrature, beside it),
best of 3, the outputs blocked on, and prints impacts/s; the pairs run baseline, working tree,
baseline, working tree, ... and the table gives each side's median over the pairs, their ratio
(working tree / baseline; ≥ 1.0 is the bar for the damped path) and the load average. The scipy
loop of ``forward_speed`` (``_common.scipy_impact_lean``, one Python call per elastic impact)
is timed in this process after the pairs: the damped path's speed-up over it (bar ≥ 1000×).

Any revision whose ``rbjax`` has ``Model``, ``Zener`` and ``simulate(height, ball, model)`` can
be the baseline (``fc0325d`` on: the solve layer before the device chunks). ``--quick``: 1000
heights, the damped model only, one pair, best of 1 (a smoke run; no figure checked).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

if __name__ == "__main__":  # run as a script: _common is one folder up
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from _common import REPO, finish_machine_info, machine_info, scipy_impact_lean, table, write_json

#: The revision the damped path is paired against by default (issue 42, item 5).
BASELINE = "fc0325d"
MODELS = ("zener", "elastic")

#: The timing each process runs: argv = heights, repeats, models (comma-separated).
CHILD = r"""
import json, os, sys, time
import numpy as np
import jax
import rbjax

n, repeats, models = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3].split(",")
heights = np.linspace(0.1, 1.6, n)
ball = rbjax.JIS_RUBBER_BALL
out = {"rbjax": rbjax.__file__, "load_start": os.getloadavg()[0]}
for name in models:
    model = rbjax.Model(damping=rbjax.Zener(0.3, 2e-3)) if name == "zener" else rbjax.Model()

    def call():
        res = rbjax.simulate(heights, ball, model)
        jax.block_until_ready((res.contact_time_s, res.peak_force_N, res.restitution))
        return res

    t0 = time.perf_counter()
    res = call()
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - t0)
    path = getattr(res, "path", getattr(res, "method", "?"))
    out[name] = {"per_s": n / best, "best_s": best, "first_s": first, "path": str(path)}
out["load_end"] = os.getloadavg()[0]
print(json.dumps(out))
"""


def _git(*args: str) -> str:
    proc = subprocess.run(["git", "-C", str(REPO), *args], capture_output=True, text=True)
    if proc.returncode:
        raise RuntimeError(f"git {' '.join(args)}: {proc.stderr.strip()}")
    return proc.stdout.strip()


def _time_one(src: Path, n: int, repeats: int, models: tuple[str, ...]) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(n), str(repeats), ",".join(models)],
        env=env,
        capture_output=True,
        text=True,
        cwd=tempfile.gettempdir(),  # not the repository: its src/ must come from PYTHONPATH
    )
    if proc.returncode:
        raise RuntimeError(f"timing under {src} failed:\n{proc.stderr[-3000:]}")
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    if not Path(out["rbjax"]).resolve().is_relative_to(src.resolve()):
        raise RuntimeError(f"rbjax came from {out['rbjax']}, not from {src}")
    return out


def scipy_per_impact(n: int) -> float:
    """Seconds per impact of the scipy loop (as ``forward_speed`` times it)."""
    from rbjax import JIS_RUBBER_BALL

    scipy_impact_lean(1.0, JIS_RUBBER_BALL)
    t0 = time.perf_counter()
    for k in range(n):
        scipy_impact_lean(0.1 + 1.5 * k / max(n - 1, 1), JIS_RUBBER_BALL)
    return (time.perf_counter() - t0) / n


def paired(against: str, n: int, pairs: int, repeats: int, models: tuple[str, ...]) -> dict:
    """Baseline and working tree timed alternately, ``pairs`` times each."""
    sha = _git("rev-parse", "--short", f"{against}^{{commit}}")
    runs: dict[str, list[dict]] = {"baseline": [], "working tree": []}
    with tempfile.TemporaryDirectory(prefix="rbjax-paired-") as tmp:
        tree = Path(tmp) / f"rbjax-{sha}"
        _git("worktree", "add", "--detach", str(tree), sha)
        try:
            sources = {"baseline": tree / "src", "working tree": REPO / "src"}
            for k in range(pairs):
                for side, src in sources.items():
                    out = _time_one(src, n, repeats, models)
                    runs[side].append(out)
                    figures = ", ".join(f"{m} {out[m]['per_s'] / 1e3:,.1f} k/s" for m in models)
                    print(f"pair {k + 1}/{pairs} {side} ({src}): {figures}", flush=True)
        finally:
            _git("worktree", "remove", "--force", str(tree))
    return {"against": against, "sha": sha, "runs": runs}


def main(
    quick: bool = False, against: str = BASELINE, pairs: int | None = None, n: int | None = None
) -> dict:
    info = machine_info()
    n = n or (1000 if quick else 10_000)
    pairs = pairs or (1 if quick else 3)
    repeats = 1 if quick else 3
    models = MODELS[:1] if quick else MODELS
    data = paired(against, n, pairs, repeats, models)
    scipy_s = scipy_per_impact(20 if quick else 100)
    rows, summary = [], {}
    for m in models:
        base = statistics.median(r[m]["per_s"] for r in data["runs"]["baseline"])
        new = statistics.median(r[m]["per_s"] for r in data["runs"]["working tree"])
        loads = [r["load_start"] for side in data["runs"].values() for r in side]
        path = data["runs"]["working tree"][0][m]["path"]
        summary[m] = {
            "baseline_per_s": base,
            "working_tree_per_s": new,
            "ratio": new / base,
            "speedup_vs_scipy": new * scipy_s,
            "path": path,
        }
        rows.append(
            [
                f"{m} ({path})",
                f"{base:,.0f}",
                f"{new:,.0f}",
                f"{new / base:.3f}",
                f"{new * scipy_s:,.0f}×",
                f"{min(loads):.1f}-{max(loads):.1f}",
            ]
        )
    print(
        f"\n{n} heights, best of {repeats}, median of {pairs} pair(s); baseline {data['sha']}"
        f" ({against}); scipy loop {1 / scipy_s:,.0f} impacts/s"
    )
    print(
        table(
            [
                "model (path)",
                f"{data['sha']} impacts/s",
                "working tree impacts/s",
                "ratio",
                "vs scipy loop",
                "load (1 min)",
            ],
            rows,
        )
    )
    result = {
        "machine": finish_machine_info(info),
        "heights": n,
        "pairs": pairs,
        "repeats": repeats,
        "scipy_per_impact_s": scipy_s,
        "summary": summary,
        **data,
    }
    print(f"wrote {write_json('paired_forward' + ('_quick' if quick else ''), result)}")
    return result


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--against", default=BASELINE, help=f"git revision (default {BASELINE})")
    p.add_argument("--pairs", type=int, help="baseline/working-tree pairs (default 3; quick 1)")
    p.add_argument("--heights", type=int, help="heights per call (default 10 000; quick 1000)")
    p.add_argument("--quick", action="store_true", help="a smoke run (seconds)")
    a = p.parse_args()
    main(a.quick, a.against, a.pairs, a.heights)

"""Sensitivity studies on SALib (issue 23): the bundled Sobol study's time, its agreement with the
hand-written estimators it replaced, convergence of the total-index intervals (pseudo-random
against Sobol'-sequence designs), and DGSM from exact gradients against SALib's finite
differences.

Parts (all by default; ``--part NAME`` repeats to pick):

* ``timing``: ``rbjax sweep src/rbjax/examples/sweeps/sobol.toml`` in a fresh process (cold:
  imports, compilation, 131 072 impacts with L_FE, SALib's analysis), wall and CPU time; the
  split between evaluation and SALib analysis in a second, in-process run; the indices against
  ``results/sobol_study_before.json`` (the old code's run: pseudo-random design, 100 000
  impacts): does each old total index lie within the new interval, and do the intervals overlap.
* ``convergence``: width of the total-index 95 % intervals against the number of evaluations,
  for contact time, peak force and L_FE 63 and 500 Hz, for the Sobol'-sequence design (SALib,
  scrambled) and the same scheme on pseudo-random points. The width is 2 · 1.96 · the standard
  deviation of S_Ti over R independent replicates (other scrambles / seeds), averaged over the
  parameters: the error a study actually has. (SALib's bootstrap width is recorded beside it:
  the bootstrap treats the points as independent and does not see the Sobol' sequence's gain.)
  A power law w = a n^b is fitted per design (its slope b printed: −1/2 is the Monte Carlo
  rate). The factor is how many more pseudo-random evaluations reach the width of the Sobol'
  design: (w_random / w_sobol)² at each size, the pseudo-random width falling as n^(−1/2) (the
  central limit theorem; the fitted slope checks it).
* ``dgsm``: ν_i = E[(∂f/∂x_i)²] and the total-index bound from ``jax.jacfwd`` at N base points
  against SALib's one-sided differences on the same design (N (d + 1) impacts), warm wall
  times of each; the bound against the total indices of the ``timing`` run.
* ``million`` (only when asked): a 2^17 × 8 = 1 048 576-impact Sobol study with L_FE in one
  command (``rbjax sweep``), wall time.

Prints tables, writes ``results/sensitivity_study.json`` and
``results/sensitivity_convergence.png``.
"""

from __future__ import annotations

import copy
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from _common import (
    REPO,
    RESULTS_DIR,
    finish_machine_info,
    machine_info,
    read_json,
    table,
    write_json,
)

# isort: split
import rbjax
from rbjax import plot as _plot  # noqa: F401  (a headless backend before pyplot)
from rbjax.studies.sensitivity import global_sensitivity

SOBOL_TOML = REPO / "src" / "rbjax" / "examples" / "sweeps" / "sobol.toml"
#: the old code's run (hand-written estimators), committed; read when RESULTS_DIR has none
BEFORE = REPO / "benchmarks" / "results" / "sobol_study_before.json"
CONFIG = tomllib.loads(SOBOL_TOML.read_text())
RANGES = CONFIG["ranges"]
CONVERGENCE_OUTPUTS = ("contact_time_s", "peak_force_N", "lfe_63_dB", "lfe_500_dB")
Z95 = 1.959963984540054


def _cli_sweep(config_path, out_path) -> dict:
    """``rbjax sweep`` in a fresh process: wall and CPU seconds."""
    env = dict(
        os.environ, PYTHONPATH=str(REPO / "src") + os.pathsep + os.environ.get("PYTHONPATH", "")
    )
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "rbjax.cli",
            "sweep",
            str(config_path),
            "--no-progress",
            "--out",
            str(out_path),
        ],
        env=env,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode:
        raise RuntimeError(proc.stderr[-2000:])
    return {
        "wall_s": wall,
        "cpu_user_s": after.ru_utime - before.ru_utime,
        "cpu_sys_s": after.ru_stime - before.ru_stime,
        "loadavg_after": list(os.getloadavg()),
    }


def _split_run(config: dict) -> dict:
    """The study ``config`` in this process: time in SALib's analysis and in the rest."""
    from SALib.analyze import sobol as salib_sobol

    from rbjax.studies import run_sweep

    original, spent = salib_sobol.analyze, [0.0]

    def timed(*args, **kw):
        start = time.perf_counter()
        try:
            return original(*args, **kw)
        finally:
            spent[0] += time.perf_counter() - start

    salib_sobol.analyze = timed
    try:
        start = time.perf_counter()
        run_sweep(copy.deepcopy(config))
        total = time.perf_counter() - start
    finally:
        salib_sobol.analyze = original
    return {"study_s": total, "salib_analysis_s": spent[0], "evaluation_s": total - spent[0]}


def _agreement(new: dict, old: dict) -> tuple[list, dict]:
    rows, worst = [], {"old_in_new_interval": 0, "intervals_overlap": 0, "pairs": 0}
    for o, entry in new["outputs"].items():
        for p in new["parameters"]:
            t_new, (lo, hi) = entry["total_order"][p], entry["total_order_ci"][p]
            t_old, (olo, ohi) = (
                old["outputs"][o]["total_order"][p],
                old["outputs"][o]["total_order_ci"][p],
            )
            inside, overlap = lo <= t_old <= hi, lo <= ohi and olo <= hi
            worst["pairs"] += 1
            worst["old_in_new_interval"] += inside
            worst["intervals_overlap"] += overlap
            if p in ("wall_m", "youngs_Pa", "mass_kg"):
                rows.append(
                    [
                        o,
                        p,
                        f"{t_old:.4f} [{olo:.4f}, {ohi:.4f}]",
                        f"{t_new:.4f} [{lo:.4f}, {hi:.4f}]",
                        "yes" if inside else "no",
                        "yes" if overlap else "no",
                    ]
                )
    return rows, worst


def part_timing(out: dict, quick: bool = False) -> None:
    """The bundled study cold from the command line and in this process (``quick``: with
    N = 256 base points instead of 16 384), its indices against the old estimators'."""
    config = copy.deepcopy(CONFIG)
    with tempfile.TemporaryDirectory() as tmp:
        path = SOBOL_TOML
        if quick:
            config["sobol"]["n_base"] = 256
            path = Path(tmp) / "sobol-quick.toml"
            path.write_text(SOBOL_TOML.read_text().replace("n_base = 16384", "n_base = 256"))
        cold = _cli_sweep(path, f"{tmp}/sobol.json")
        summary = json.loads(open(f"{tmp}/sobol.json").read())
    split = _split_run(config)
    old = read_json("sobol_study_before") or json.loads(BEFORE.read_text())
    rows, counts = _agreement(summary, old)
    out["timing"] = {
        "cold_cli": cold,
        "in_process": split,
        "n_evaluations": summary["n_evaluations"],
        "agreement_with_before": counts,
        "before_note": old.get("note"),
    }
    out["sobol_summary"] = summary
    print(
        table(
            ["", "wall (s)", "CPU user + sys (s)", "evaluation (s)", "SALib analysis (s)"],
            [
                [
                    "cold `rbjax sweep sobol.toml`",
                    f"{cold['wall_s']:.1f}",
                    f"{cold['cpu_user_s'] + cold['cpu_sys_s']:.1f}",
                    "",
                    "",
                ],
                [
                    "in process (after imports)",
                    f"{split['study_s']:.1f}",
                    "",
                    f"{split['evaluation_s']:.1f}",
                    f"{split['salib_analysis_s']:.1f}",
                ],
            ],
        )
    )
    print(
        table(
            [
                "output",
                "parameter",
                "S_T before (pseudo-random, 100 000)",
                "S_T now (Sobol', 131 072)",
                "before inside now's interval",
                "intervals overlap",
            ],
            rows,
        )
    )
    print(f"all pairs: {counts}")


def _fit(ns, widths) -> tuple[float, float]:
    """log w = log a + b log n (least squares)."""
    b, log_a = np.polyfit(np.log(ns), np.log(widths), 1)
    return float(math.exp(log_a)), float(b)


def part_convergence(out: dict, quick: bool) -> None:
    ns = [2**k for k in (range(5, 7) if quick else range(6, 12))]
    replicates = 2 if quick else 8
    res: dict = {
        "n_base": ns,
        "replicates": replicates,
        "outputs": list(CONVERGENCE_OUTPUTS),
        "designs": {},
    }
    for design in ("sobol", "random"):
        entry: dict = {
            "n_evaluations": [n * (len(RANGES) + 2) for n in ns],
            "width": {o: [] for o in CONVERGENCE_OUTPUTS},
            "bootstrap_width": {o: [] for o in CONVERGENCE_OUTPUTS},
            "mean_total_order": {o: [] for o in CONVERGENCE_OUTPUTS},
        }
        for n in ns:
            start = time.perf_counter()
            studies = [
                global_sensitivity(
                    RANGES,
                    n,
                    outputs=CONVERGENCE_OUTPUTS,
                    design=design,
                    second_order=False,
                    seed=rep,
                    n_bootstrap=100,
                    parallel=rbjax.Parallel(chunk_size=1024),
                )
                for rep in range(replicates)
            ]
            for o in CONVERGENCE_OUTPUTS:
                totals = np.array([s.total_order[o] for s in studies])  # (R, d)
                entry["width"][o].append(float(np.mean(2 * Z95 * totals.std(axis=0, ddof=1))))
                entry["bootstrap_width"][o].append(
                    float(np.mean([np.mean(np.diff(s.total_order_ci[o], axis=1)) for s in studies]))
                )
                entry["mean_total_order"][o].append(totals.mean(axis=0).tolist())
            print(
                f"{design} N={n}: {replicates} × {n * (len(RANGES) + 2)} impacts in "
                f"{time.perf_counter() - start:.1f} s",
                flush=True,
            )
        res["designs"][design] = entry
    out["convergence"] = res
    _summarize_convergence(res)
    _plot_convergence(
        res, RESULTS_DIR / ("sensitivity_convergence" + ("_quick" if quick else "") + ".png")
    )


def _summarize_convergence(res: dict) -> None:
    """Fitted slopes, and per size the factor (w_random / w_sobol)²: how many more pseudo-random
    evaluations reach the Sobol' design's width (the pseudo-random width falling as n^(−1/2))."""
    rows = []
    res["factor"] = {}
    evals = np.array(res["designs"]["sobol"]["n_evaluations"], dtype=float)
    for o in res["outputs"]:
        (_, b_s), (_, b_r) = (
            _fit(evals, res["designs"][d]["width"][o]) for d in ("sobol", "random")
        )
        factors = (
            np.array(res["designs"]["random"]["width"][o])
            / np.array(res["designs"]["sobol"]["width"][o])
        ) ** 2
        res["factor"][o] = {
            "slope_sobol": b_s,
            "slope_random": b_r,
            "by_size": factors.tolist(),
            "smallest": float(factors.min()),
            "factor": float(factors[-1]),
        }
        rows.append([o, f"{b_r:.2f}", f"{b_s:.2f}", *(f"{f:,.0f}×" for f in factors)])
    headers = ["output", "slope, pseudo-random", "slope, Sobol'", *(f"{n:,.0f}" for n in evals)]
    print(
        "pseudo-random evaluations needed per Sobol' evaluation for the same S_T interval width, "
        "by evaluations:"
    )
    print(table(headers, rows))


def _plot_convergence(res: dict, path) -> None:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        1,
        len(res["outputs"]),
        figsize=(3.3 * len(res["outputs"]) + 0.5, 3.4),
        layout="constrained",
        sharey=False,
    )
    for ax, o in zip(axes, res["outputs"]):
        for design, style in (("random", "o-"), ("sobol", "s-")):
            entry = res["designs"][design]
            ax.loglog(
                entry["n_evaluations"], entry["width"][o], style, label=f"{design}: replicates"
            )
            ax.loglog(
                entry["n_evaluations"],
                entry["bootstrap_width"][o],
                style[0] + ":",
                alpha=0.5,
                label=f"{design}: SALib bootstrap",
            )
        f = res["factor"][o]
        ax.set_title(
            f"{o}: Sobol' needs {f['smallest']:.0f}–{max(f['by_size']):,.0f}× fewer", fontsize=9
        )
        ax.set_xlabel("evaluations")
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("S_T 95 % interval width")
    axes[0].legend(fontsize=7)
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def part_dgsm(out: dict, quick: bool) -> None:
    n = 16 if quick else 512
    outputs = ("contact_time_s", "peak_force_N", "restitution", "lfe")
    global_sensitivity(RANGES, n, analysis="dgsm", outputs=outputs)  # compile
    res = global_sensitivity(RANGES, n, analysis="dgsm", outputs=outputs)
    d = len(RANGES)
    per_fd, per_exact = res.seconds_fd / n, res.seconds_exact / n
    entry: dict = {
        "n_base": n,
        "delta": res.delta,
        "seconds_fd": res.seconds_fd,
        "seconds_exact": res.seconds_exact,
        "per_base_point_fd_s": per_fd,
        "per_base_point_exact_s": per_exact,
        "cost_ratio_fd_over_exact": per_fd / per_exact,
        "outputs": {},
    }
    totals = (out.get("sobol_summary") or {}).get("outputs", {})
    rows, bound_rows = [], []
    for o in res.outputs:
        nu, (lo, hi), fd = res.nu[o], res.nu_ci[o].T, res.nu_fd[o]
        within = bool(np.all((lo <= fd) & (fd <= hi)))
        rel = float(np.max(np.abs(fd / nu - 1)))
        e = {
            "nu": nu.tolist(),
            "nu_ci": res.nu_ci[o].tolist(),
            "nu_fd": fd.tolist(),
            "total_bound": res.total_bound[o].tolist(),
            "fd_within_sampling_error": within,
            "max_rel_difference": rel,
        }
        if o in totals:
            st = np.array([totals[o]["total_order"][p] for p in res.parameters])
            e["total_order_sobol"] = st.tolist()
            e["bound_over_total"] = (res.total_bound[o] / st).tolist()
            bound_rows.append([o] + [f"{r:.2f}" for r in res.total_bound[o] / st])
        entry["outputs"][o] = e
        rows.append([o, "yes" if within else "no", f"{rel:.1e}"])
    out["dgsm"] = entry
    print(
        f"DGSM, N = {n}: exact {res.seconds_exact:.2f} s ({per_exact * 1e3:.2f} ms per base "
        f"point), SALib finite differences {res.seconds_fd:.2f} s ({d + 1} impacts per base "
        f"point, {per_fd * 1e3:.2f} ms): finite differences cost {per_fd / per_exact:.2f}× the "
        "exact gradient"
    )
    print(
        table(
            [
                "output",
                "finite-difference ν within the exact ν's 95 % sampling interval",
                "max |ν_fd/ν − 1|",
            ],
            rows,
        )
    )
    if bound_rows:
        print(
            "bound ν_i (b−a)²/(π² V) over the Sobol S_Ti (12/π² = 1.22 for a response linear in "
            "x_i):"
        )
        print(table(["output", *res.parameters], bound_rows))


def part_million(out: dict) -> None:
    config = copy.deepcopy(CONFIG)
    config["sobol"]["n_base"] = 2**17
    with tempfile.TemporaryDirectory() as tmp:
        path = f"{tmp}/million.toml"
        with open(path, "w") as fh:
            fh.write(_toml(config))
        run = _cli_sweep(path, f"{tmp}/million.json")
        n = json.loads(open(f"{tmp}/million.json").read())["n_evaluations"]
    out["million"] = {"n_evaluations": n, **run}
    print(
        f"{n:,} impacts with L_FE in one command: {run['wall_s']:.0f} s wall, "
        f"{run['cpu_user_s'] + run['cpu_sys_s']:.0f} s CPU"
    )


def _toml(config: dict) -> str:
    """A flat TOML writer for the sweep config (tables of scalars and lists)."""

    def value(v):
        return json.dumps(v) if not isinstance(v, bool) else str(v).lower()

    lines = [f"{k} = {value(v)}" for k, v in config.items() if not isinstance(v, dict)]
    for k, v in config.items():
        if isinstance(v, dict):
            lines += [f"[{k}]"] + [f"{kk} = {value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def main(quick: bool = False, parts: tuple[str, ...] = ("timing", "convergence", "dgsm")) -> None:
    """``parts``: any of timing, convergence, dgsm and million (the last only when asked)."""
    info = machine_info()
    name = "sensitivity_study" + ("_quick" if quick else "")
    out = read_json(name) or {}
    if "timing" in parts:
        part_timing(out, quick)
    if "convergence" in parts:
        part_convergence(out, quick)
    if "dgsm" in parts:
        part_dgsm(out, quick)
    if "million" in parts:
        part_million(out)
    out.setdefault("machine", {})
    for part in parts:
        out["machine"][part] = finish_machine_info(dict(info))
    print(f"wrote {write_json(name, out)}")

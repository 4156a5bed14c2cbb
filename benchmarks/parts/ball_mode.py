"""The ball mode (``+ball-mode``) on the bundled emulated recordings: held-out accuracy against
the issue's bars, the first-maximum peak against the history's maximum, the cost per impact,
and ``rbjax select`` with the ball-mode candidates (cold and warm).

1. Fit to 0.1, 0.4, 1.0, 1.6 m and predict 0.2 and 0.8 m (the held-out split of
   docs/guides/fitting.md), for the best models without the mode (hunt-crossley/momentum,
   zener/momentum) and with it; the ball-mode fits start from several mode frequencies
   (``BALL_MODE_FREQUENCY_STARTS_Hz``), every start is reported and the lowest cost is kept. One
   superset structure (all terms), one compiled program.
2. For the fitted ball-mode model: ``peak_force_N`` (the floor force at the first maximum of
   compression) against the maximum of a 200 kHz history, at every height.
3. Forward cost per impact: ``rbjax.simulate`` of 1000 heights on the ODE path, with and
   without the mode (fitted values), warm median.
4. ``rbjax select --candidates hunt-crossley,zener,hunt-crossley+ball-mode,zener+ball-mode
   --blocked-force momentum`` in subprocesses, cold (empty cache) and warm.

Prints tables and writes ``results/ball_mode.json``. ``--quick``: hunt-crossley+ball-mode alone,
one start, the peak at two heights, the cost at 100 impacts, no select.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import rbjax
from rbjax.data import examples_dir
from rbjax.fit import FitOptions, fit, prepare_data
from rbjax.spectrum import OCTAVE_BANDS

from _common import (
    finish_machine_info,
    held_out_rows,
    machine_info,
    shared_structure,
    time_call,
    write_json,
)

FIT_HEIGHTS = (0.1, 0.4, 1.0, 1.6)
MODELS = ("hunt-crossley", "zener", "hunt-crossley+ball-mode", "zener+ball-mode")
QUICK_MODELS = ("hunt-crossley+ball-mode",)
BALL_MODE_FREQUENCY_STARTS_Hz = (300.0, 600.0, 1200.0)
BARS = {
    "history_error_pct": 1.5,
    "contact_time_pct": 1.0,
    "peak_force_pct": 1.5,
    "lfe_low_dB": 0.5,
    "lfe_high_dB": 1.5,
}
SELECT_CANDIDATES = "hunt-crossley,zener,hunt-crossley+ball-mode,zener+ball-mode"


def bars_met(row) -> dict:
    lfe = np.abs(np.asarray(row.lfe_octave_dB))
    return {
        "history": row.history_error_pct <= BARS["history_error_pct"],
        "contact_time": abs(row.contact_time_pct) <= BARS["contact_time_pct"],
        "peak_force": abs(row.peak_force_pct) <= BARS["peak_force_pct"],
        "lfe_31.5-250": bool(np.all(lfe[:4] <= BARS["lfe_low_dB"])),
        "lfe_500-1000": bool(np.all(lfe[4:] <= BARS["lfe_high_dB"])),
    }


def held_out(data, superset, quick: bool):
    out, fits = {}, {}
    for name in QUICK_MODELS if quick else MODELS:
        starts = [None]
        if name.endswith("+ball-mode"):
            starts = [
                {"mode_frequency_Hz": f}
                for f in (
                    BALL_MODE_FREQUENCY_STARTS_Hz[1:2] if quick else BALL_MODE_FREQUENCY_STARTS_Hz
                )
            ]
        tried = []
        for start in starts:
            t0 = time.perf_counter()
            res = fit(
                data,
                name,
                blocked_force="momentum",
                options=FitOptions(fit_heights=FIT_HEIGHTS, structure=superset),
                start=start,
                progress=False,
            )
            elapsed = time.perf_counter() - t0
            cost = float(np.sum(((res.predicted_N - res.measured_N)[res.in_fit]) ** 2))
            tried.append((cost, res, start, elapsed))
            print(
                f"fit {name}/momentum start {start}: rms {res.residual_rms_N:.2f} N, "
                f"{res.message}, {elapsed:.0f} s",
                flush=True,
            )
        cost, res, start, elapsed = min(tried, key=lambda x: x[0])
        rest = [h for h in data.heights_m if not np.any(np.isclose(FIT_HEIGHTS, h))]
        rows = held_out_rows(res, rest)
        fits[name] = res
        out[name] = {
            "start": start,
            "starts": [
                {
                    "start": s,
                    "residual_rms_N": r.residual_rms_N,
                    "converged": r.converged,
                    "iterations": r.iterations,
                    "time_s": t,
                    "parameters": {k: v.value for k, v in r.parameters.items()},
                }
                for _, r, s, t in tried
            ],
            "residual_rms_N": res.residual_rms_N,
            "converged": res.converged,
            "parameters": {k: v.value for k, v in res.parameters.items()},
            "held_out": [vars(r) | {"bars_met": bars_met(r)} for r in rows],
        }
    return out, fits


def peak_check(result, quick: bool = False) -> list[dict]:
    rows = []
    times = np.arange(0.0, 0.05, 5e-6)
    for h in (0.1, 1.6) if quick else (0.1, 0.2, 0.4, 0.8, 1.0, 1.6):
        res = rbjax.simulate(
            h,
            result.ball,
            damping=result.model.damping,
            blocked_force="momentum",
            ball_mode=result.model.ball_mode,
            path="ode",
        )
        traj = rbjax.trajectory(h, times, result.ball, result.model)
        fmax = float(np.max(np.asarray(traj.force_N)))
        rows.append(
            {
                "height_m": h,
                "peak_force_N": float(res.peak_force_N),
                "history_max_N": fmax,
                "difference_pct": 100.0 * (float(res.peak_force_N) / fmax - 1.0),
                "peak_time_s": float(res.peak_time_s),
            }
        )
    return rows


def cost_per_impact(fits, quick: bool = False) -> dict:
    heights = np.linspace(0.05, 2.0, 100 if quick else 1000)
    out = {}
    for name in ("hunt-crossley", "hunt-crossley+ball-mode"):
        if name not in fits:  # quick: the ball-mode model alone
            continue
        r = fits[name]
        fn = lambda r=r: (  # noqa: E731
            rbjax.simulate(
                heights,
                r.ball,
                damping=r.model.damping,
                blocked_force="momentum",
                ball_mode=r.model.ball_mode,
                path="ode",
            ).contact_time_s
        )
        t = time_call(fn, min_repeats=3)
        steps = rbjax.simulate(
            heights,
            r.ball,
            damping=r.model.damping,
            blocked_force="momentum",
            ball_mode=r.model.ball_mode,
            path="ode",
        ).num_steps
        out[name] = {
            "batch": heights.size,
            "median_s": t["median_s"],
            "per_impact_us": 1e6 * t["median_s"] / heights.size,
            "compile_s": t["compile_s"],
            "mean_steps": float(np.mean(np.asarray(steps))),
        }
    return out


def select_times(data_dir: str) -> dict:
    argv = [
        sys.executable,
        "-m",
        "rbjax.cli",
        "select",
        data_dir,
        "--candidates",
        SELECT_CANDIDATES,
        "--blocked-force",
        "momentum",
        "--json",
        "--quiet",
    ]
    out: dict = {"argv": argv[3:]}
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, RBJAX_CACHE_DIR=cache)
        for label in ("cold", "warm"):
            t0 = time.perf_counter()
            proc = subprocess.run(argv, env=env, capture_output=True, text=True)
            out[f"{label}_s"] = time.perf_counter() - t0
            out[f"{label}_exit"] = proc.returncode
            if proc.returncode == 0:
                sel = json.loads(proc.stdout)["selection"]
                out["recommended"] = sel["recommended"]
                out["within_noise"] = sel["within_noise"]
                out["candidates"] = [
                    {
                        k: c[k]
                        for k in (
                            "model_name",
                            "blocked_force",
                            "n_physical",
                            "converged",
                            "residual_rms_N",
                            "cv_history_error_pct",
                            "cv_history_error_se_pct",
                            "cv_mean_abs_contact_time_pct",
                            "cv_mean_abs_peak_force_pct",
                            "cv_mean_abs_lfe_octave_dB",
                        )
                    }
                    for c in sel["candidates"]
                ]
            else:
                out[f"{label}_stderr"] = proc.stderr[-2000:]
            print(f"select {label}: {out[f'{label}_s']:.0f} s (exit {proc.returncode})", flush=True)
    return out


def main(quick: bool = False) -> None:
    info = machine_info()
    data = prepare_data(str(examples_dir()))
    superset = shared_structure(QUICK_MODELS if quick else MODELS)
    ho, fits = held_out(data, superset, quick)
    print(
        "\n| model | h (m) | history err (%) | Δt_c (%) | Δpeak (%) | "
        + " | ".join(f"ΔL {b}" for b in OCTAVE_BANDS)
        + " (dB) |"
    )
    print("|---|---|---|---|---|" + "---|" * len(OCTAVE_BANDS))
    for name, rec in ho.items():
        for r in rec["held_out"]:
            print(
                f"| {name}/momentum | {r['height_m']:.1f} | {r['history_error_pct']:.2f} | "
                f"{r['contact_time_pct']:+.2f} | {r['peak_force_pct']:+.2f} | "
                + " | ".join(f"{x:+.2f}" for x in r["lfe_octave_dB"])
                + " |"
            )
    for name, rec in ho.items():
        print(name, {k: round(v, 6) for k, v in rec["parameters"].items()})
    peaks = peak_check(fits["hunt-crossley+ball-mode"], quick)
    for p in peaks:
        print(
            f"peak check h={p['height_m']:.1f}: peak_force_N {p['peak_force_N']:.1f} N, history "
            f"max {p['history_max_N']:.1f} N ({p['difference_pct']:+.3f} %)"
        )
    cost = cost_per_impact(fits, quick)
    for name, c in cost.items():
        print(
            f"cost {name}: {c['per_impact_us']:.0f} µs/impact (batch {c['batch']}, median "
            f"{c['median_s']:.2f} s, {c['mean_steps']:.0f} steps)"
        )
    out = {
        "machine": None,
        "fit_heights_m": FIT_HEIGHTS,
        "bars": BARS,
        "held_out": ho,
        "peak_check": peaks,
        "cost_per_impact": cost,
    }
    if not quick:
        out["select"] = select_times(str(examples_dir()))
    out["machine"] = finish_machine_info(info)
    print(f"wrote {write_json('ball_mode_quick' if quick else 'ball_mode', out)}")

"""Wall time of `rbjax fit` on the bundled recordings, cold (empty compilation cache) and warm,
beside what a scipy user would write (``scipy_fit.py``), and the cost of one LM evaluation.

Runs the command line in subprocesses with ``RBJAX_CACHE_DIR`` pointing at a fresh folder, so
the first run compiles and the second reads JAX's persistent compilation cache; prints a
table and writes ``results/fit_time.json`` (with the full selection's table, printed as
Markdown for docs/guides/fitting.md). Settings: ``--model hunt-crossley+ball-mode --blocked-force
momentum``, ``--model kelvin-voigt --blocked-force momentum`` and the full selection (no
``--model``). Then, in this process: the scipy fits of the same two models (time, cost ½Σr²
of the scipy residuals, rms) and rbjax's optimum's cost under the same residuals; the time of
one LM evaluation (residuals and Jacobian of all records) against the forward histories of
the same records. ``--quick``: the kelvin-voigt fit alone (cold, warm, scipy's) and one LM
evaluation of hunt-crossley: no ball mode (its scipy fit takes minutes), no full selection.
Cold and warm runs are separate processes; the first reads nothing from any cache.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rbjax.data import examples_dir

from _common import RESULTS_DIR, finish_machine_info, machine_info

HERE = Path(__file__).parent


def timed(argv, cache_dir) -> tuple[float, int, dict]:
    env = dict(os.environ, RBJAX_CACHE_DIR=str(cache_dir))
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "rbjax.cli", *argv], env=env, capture_output=True, text=True
    )
    elapsed = time.perf_counter() - t0
    try:
        out = json.loads(proc.stdout)
    except json.JSONDecodeError:
        out = {"stderr_tail": proc.stderr[-2000:]}
    return elapsed, proc.returncode, out


def _selection_summary(out: dict) -> dict:
    sel = out.get("selection")
    if not sel:
        return {}
    keys = (
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
    return {
        "recommended": sel["recommended"],
        "candidates": [{k: c[k] for k in keys} for c in sel["candidates"]],
    }


def selection_markdown(sel: dict) -> str:
    """The selection table of docs/guides/fitting.md from ``rbjax fit --json``'s ``selection``."""
    bands = "31.5 | 63 | 125 | 250 | 500 | 1000 Hz (dB)"
    lines = [
        "| model | blocked force | fitted params | history rms (N) | held-out history err (%) | "
        f"\\|Δt_c\\| (%) | \\|Δpeak\\| (%) | \\|ΔL\\| {bands} |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    rec = (sel["recommended"]["model_name"], sel["recommended"]["blocked_force"])
    for c in sel["candidates"]:
        bold = (c["model_name"], c["blocked_force"]) == rec
        name = (
            [f"**{c['model_name']}**", f"**{c['blocked_force']}**"]
            if bold
            else [c["model_name"], c["blocked_force"]]
        )
        err = f"{c['cv_history_error_pct']:.2f} ± {c['cv_history_error_se_pct']:.2f}"
        lines.append(
            "| "
            + " | ".join(
                [
                    *name,
                    str(c["n_physical"]),
                    f"{c['residual_rms_N']:.1f}",
                    f"**{err}**" if bold else err,
                    f"{c['cv_mean_abs_contact_time_pct']:.2f}",
                    f"{c['cv_mean_abs_peak_force_pct']:.2f}",
                    *(f"{x:.2f}" for x in c["cv_mean_abs_lfe_octave_dB"]),
                ]
            )
            + " |"
        )
    base = sel["baseline_paper_unfitted"]
    mean = lambda key: sum(abs(r[key]) for r in base) / len(base)  # noqa: E731
    lfe = [
        sum(abs(r["lfe_octave_dB"][i]) for r in base) / len(base)
        for i in range(len(base[0]["lfe_octave_dB"]))
    ]
    lines.append(
        "| "
        + " | ".join(
            [
                "paper, unfitted",
                "paper",
                "0",
                "—",
                f"{mean('history_error_pct'):.2f}",
                f"{mean('contact_time_pct'):.2f}",
                f"{mean('peak_force_pct'):.2f}",
                *(f"{x:.2f}" for x in lfe),
            ]
        )
        + " |"
    )
    return "\n".join(lines)


def lm_evaluation_ratio(model: str) -> dict:
    """Median time of one evaluation of the fit's program (residuals and the Jacobian of all
    records, the optimiser stopped after it) against the forward histories of the same records
    on the same path (``record_forces`` alone, jitted)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from rbjax import JIS_RUBBER_BALL
    from rbjax.fit import model_from_name, prepare_data
    from rbjax.fit.problem import Problem, fit_solver
    from rbjax.fit.record_forces import record_forces

    from _common import time_call

    data = prepare_data(examples_dir())
    m = model_from_name(model, blocked_force="momentum", values={"alpha_s_per_m": 0.05})
    problem = Problem(
        data, JIS_RUBBER_BALL, m, fit_solver(None), height_error=False, decimate=1, scale="noise"
    )
    lay = problem.layout
    theta = lay.theta(JIS_RUBBER_BALL, m, data.onset_s)
    free = np.zeros(len(lay.names), bool)
    weights = problem.weights(np.ones(data.n_records, bool))
    constants = lay.constant_values(JIS_RUBBER_BALL, m)
    evaluation = time_call(lambda: problem.run(theta, free, weights, constants)["r"])
    s = problem.structure
    forward = jax.jit(
        lambda th: record_forces(
            s, th, jnp.asarray(constants), jnp.asarray(problem.arrays["heights"])
        )
    )
    histories = time_call(lambda: forward(jnp.asarray(theta)))
    return {
        "model": model,
        "records": int(data.n_records),
        "samples": int(data.n_samples),
        "columns": len(lay.names),
        "evaluation_ms": 1e3 * evaluation["median_s"],
        "forward_ms": 1e3 * histories["median_s"],
        "ratio": evaluation["median_s"] / histories["median_s"],
    }


def scipy_anchor(model: str, rbjax_out: dict) -> dict:
    """The scipy user's fit of ``model`` (momentum) and rbjax's optimum under its residuals."""
    from parts.scipy_fit import MODELS, cost_at, fit
    from rbjax.fit import prepare_data

    data = prepare_data(examples_dir())
    ref = fit(model, data)
    names = MODELS[model][0]
    params = {n: rbjax_out["parameters"][n]["value"] for n in names}
    rbjax_cost = cost_at(ref.pop("residuals"), names, params, rbjax_out["onset_shift_s"])
    return {**ref, "rbjax_cost_under_scipy_residuals": rbjax_cost, "rbjax_parameters": params}


def main(quick: bool = False) -> None:
    data = str(examples_dir())
    settings = {
        "hunt-crossley+ball-mode/momentum": [
            "fit",
            data,
            "--model",
            "hunt-crossley+ball-mode",
            "--blocked-force",
            "momentum",
            "--json",
            "--quiet",
        ],
        "kelvin-voigt/momentum": [
            "fit",
            data,
            "--model",
            "kelvin-voigt",
            "--blocked-force",
            "momentum",
            "--json",
            "--quiet",
        ],
    }
    if quick:
        del settings["hunt-crossley+ball-mode/momentum"]
    else:
        settings["full selection"] = ["fit", data, "--json", "--quiet"]
    info = machine_info()
    rows = []
    outs = {}
    for label, argv in settings.items():
        with tempfile.TemporaryDirectory() as cache:
            cold, rc1, out = timed(argv, cache)
            warm, rc2, _ = timed(argv, cache)
        outs[label] = out
        rows.append(
            {
                "setting": label,
                "cold_s": cold,
                "warm_s": warm,
                "exit_codes": [rc1, rc2],
                "selection": _selection_summary(out),
                "recommended": (out.get("model_name"), out.get("blocked_force")),
                "residual_rms_N": out.get("residual_rms_N"),
                "message": out.get("message"),
                "selection_table": selection_markdown(out["selection"])
                if out.get("selection")
                else None,
            }
        )
        print(
            f"{label:34s} cold {cold:7.1f} s   warm {warm:7.1f} s   exit {rc1}/{rc2}   rms "
            f"{out.get('residual_rms_N')}",
            flush=True,
        )
    anchors = []
    for model in ("kelvin-voigt",) if quick else ("kelvin-voigt", "hunt-crossley+ball-mode"):
        a = scipy_anchor(model, outs[f"{model}/momentum"])
        warm = next(r["warm_s"] for r in rows if r["setting"] == f"{model}/momentum")
        a["rbjax_warm_s"] = warm
        a["speedup_warm"] = a["time_s"] / warm
        anchors.append(a)
        print(
            f"scipy {model:26s} {a['time_s']:7.1f} s ({a['evaluations']} evaluations + FD "
            f"Jacobians), cost {a['cost']:.6g}, rms {a['rms_N']:.2f} N; rbjax's optimum under the "
            f"same residuals: cost {a['rbjax_cost_under_scipy_residuals']:.6g}; rbjax warm "
            f"{warm:.1f} s: {a['speedup_warm']:.1f}×",
            flush=True,
        )
    models = ("hunt-crossley",) if quick else ("hunt-crossley", "hunt-crossley+ball-mode")
    ratios = [lm_evaluation_ratio(m) for m in models]
    for r in ratios:
        print(
            f"one LM evaluation, {r['model']}: {r['evaluation_ms']:.1f} ms vs forward histories "
            f"{r['forward_ms']:.1f} ms: {r['ratio']:.2f}×",
            flush=True,
        )
    for row in rows:
        if row["selection_table"]:
            print(row["selection_table"])
    out = {
        "machine": finish_machine_info(info),
        "rows": rows,
        "scipy_anchor": anchors,
        "lm_evaluation": ratios,
    }
    name = "fit_time_quick.json" if quick else "fit_time.json"
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    (RESULTS_DIR / name).write_text(json.dumps(out, indent=2))

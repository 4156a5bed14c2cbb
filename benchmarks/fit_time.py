"""Wall time of `rbjax fit` on the bundled recordings, cold (empty compilation cache) and warm.

Runs the command line in subprocesses with ``RBJAX_CACHE_DIR`` pointing at a fresh folder, so
the first run compiles and the second reads JAX's persistent compilation cache; prints a
table and writes ``results/fit_time.json`` (with the full selection's table, printed as
Markdown for the README). Settings: the full selection (no ``--model``) and
``--model zener --blocked-force momentum``. Pass ``--quick`` for the single-model rows only.
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

from _common import finish_machine_info, machine_info

HERE = Path(__file__).parent


def timed(argv, cache_dir) -> tuple[float, int, dict]:
    env = dict(os.environ, RBJAX_CACHE_DIR=str(cache_dir))
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "rbjax.cli", *argv], env=env, capture_output=True, text=True)
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
    keys = ("model_name", "blocked_force", "n_physical", "converged", "residual_rms_N", "cv_history_error_pct", "cv_history_error_se_pct",
            "cv_mean_abs_contact_time_pct", "cv_mean_abs_peak_force_pct", "cv_mean_abs_lfe_octave_dB")
    return {"recommended": sel["recommended"], "candidates": [{k: c[k] for k in keys} for c in sel["candidates"]]}


def selection_markdown(sel: dict) -> str:
    """The README's selection table from ``rbjax fit --json``'s ``selection``."""
    bands = "31.5 | 63 | 125 | 250 | 500 | 1000 Hz (dB)"
    lines = [
        f"| model | blocked force | fitted params | history rms (N) | held-out history err (%) | \\|Δt_c\\| (%) | \\|Δpeak\\| (%) | \\|ΔL\\| {bands} |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    rec = (sel["recommended"]["model_name"], sel["recommended"]["blocked_force"])
    for c in sel["candidates"]:
        bold = (c["model_name"], c["blocked_force"]) == rec
        name = [f"**{c['model_name']}**", f"**{c['blocked_force']}**"] if bold else [c["model_name"], c["blocked_force"]]
        err = f"{c['cv_history_error_pct']:.2f} ± {c['cv_history_error_se_pct']:.2f}"
        lines.append("| " + " | ".join([*name, str(c["n_physical"]), f"{c['residual_rms_N']:.1f}", f"**{err}**" if bold else err,
                                          f"{c['cv_mean_abs_contact_time_pct']:.2f}", f"{c['cv_mean_abs_peak_force_pct']:.2f}",
                                          *(f"{x:.2f}" for x in c["cv_mean_abs_lfe_octave_dB"])]) + " |")
    base = sel["baseline_paper_unfitted"]
    mean = lambda key: sum(abs(r[key]) for r in base) / len(base)  # noqa: E731
    lfe = [sum(abs(r["lfe_octave_dB"][i]) for r in base) / len(base) for i in range(len(base[0]["lfe_octave_dB"]))]
    lines.append("| " + " | ".join(["paper, unfitted", "paper", "0", "—", f"{mean('history_error_pct'):.2f}", f"{mean('contact_time_pct'):.2f}",
                                      f"{mean('peak_force_pct'):.2f}", *(f"{x:.2f}" for x in lfe)]) + " |")
    return "\n".join(lines)


def main() -> None:
    quick = "--quick" in sys.argv
    data = str(examples_dir())
    settings = {"zener/momentum": ["fit", data, "--model", "zener", "--blocked-force", "momentum", "--json", "--quiet"]}
    if not quick:
        settings["full selection"] = ["fit", data, "--json", "--quiet"]
    info = machine_info()
    rows = []
    for label, argv in settings.items():
        with tempfile.TemporaryDirectory() as cache:
            cold, rc1, out = timed(argv, cache)
            warm, rc2, _ = timed(argv, cache)
        rows.append({"setting": label, "cold_s": cold, "warm_s": warm, "exit_codes": [rc1, rc2], "selection": _selection_summary(out),
                     "selection_table": selection_markdown(out["selection"]) if out.get("selection") else None})
        print(f"{label:18s} cold {cold:7.1f} s   warm {warm:7.1f} s   exit {rc1}/{rc2}", flush=True)
    for row in rows:
        if row["selection_table"]:
            print(row["selection_table"])
    out = {"machine": finish_machine_info(info), "rows": rows}
    name = "fit_time_quick.json" if quick else "fit_time.json"
    (HERE / "results" / name).write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

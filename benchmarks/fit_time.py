"""Wall time of `rbjax fit` on the bundled recordings, cold (empty compilation cache) and warm.

Runs the command line in subprocesses with ``RBJAX_CACHE_DIR`` pointing at a fresh folder, so
the first run compiles and the second reads JAX's persistent compilation cache; prints a
table and writes ``results/fit_time.json``. Settings: the full selection (no ``--model``) and
``--model zener --blocked-force momentum``. Pass ``--quick`` for the single-model rows only.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rbjax.data import examples_dir

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


def main() -> None:
    quick = "--quick" in sys.argv
    data = str(examples_dir())
    settings = {"zener/momentum": ["fit", data, "--model", "zener", "--blocked-force", "momentum", "--json", "--quiet"]}
    if not quick:
        settings["full selection"] = ["fit", data, "--json", "--quiet"]
    rows = []
    for label, argv in settings.items():
        with tempfile.TemporaryDirectory() as cache:
            cold, rc1, out = timed(argv, cache)
            warm, rc2, _ = timed(argv, cache)
        rows.append({"setting": label, "cold_s": cold, "warm_s": warm, "exit_codes": [rc1, rc2], "selection": _selection_summary(out)})
        print(f"{label:18s} cold {cold:7.1f} s   warm {warm:7.1f} s   exit {rc1}/{rc2}", flush=True)
    out = {"machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores", "rows": rows}
    name = "fit_time_quick.json" if quick else "fit_time.json"
    (HERE / "results" / name).write_text(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

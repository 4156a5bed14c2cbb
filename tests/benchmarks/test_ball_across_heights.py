"""benchmarks/ball_across_heights.py (issue 43, the mechanism study) stays runnable: it answers
``--help`` in the normal suite, and ``pytest -m bench_quick tests/benchmarks`` runs its
``--quick`` mode end to end (three candidates at two heights; under a minute on a quiet 2-core
machine, most of it compiling the composite's ODE and history). No figure is checked here: the
figures the docs quote are "measured by benchmarks/ball_across_heights.py"."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "ball_across_heights.py"


def test_ball_across_heights_is_a_script():
    out = subprocess.run([sys.executable, str(SCRIPT), "--help"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "--quick" in out.stdout


@pytest.mark.bench_quick
def test_ball_across_heights_runs_quick(tmp_path):
    env = dict(os.environ, RBJAX_BENCH_RESULTS=str(tmp_path), RBJAX_CACHE_DIR="")
    env["JAX_DISABLE_MOST_OPTIMIZATIONS"] = "1"  # a smoke run: no figure is checked
    out = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick"], env=env, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-3000:]
    record = json.loads((tmp_path / "ball_across_heights_quick.json").read_text())
    assert set(record["candidates"]) == {"paper", "momentum", "composite (rbjax)"}
    assert (tmp_path / "ball_across_heights_quick.png").exists()

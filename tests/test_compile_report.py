"""``pytest --compile-report=PATH`` (the root conftest.py): where each test's time went, its wall
time and JAX's tracing, lowering and XLA compile seconds, as JSON (one file per xdist worker);
run here in a subprocess on tests/test_xla_level.py, whose first test compiles one program (no
persistent compilation cache there, so that it compiles whatever ran before); with the programs
each test traced and compiled."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LEVEL_TESTS = "tests/test_xla_level.py"


def test_the_report_holds_each_tests_wall_time_and_its_compile_seconds(tmp_path):
    report = tmp_path / "report" / "times.json"
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", LEVEL_TESTS, "-q", "-n", "0", "-p", "no:cacheprovider"]
        + [f"--compile-report={report}"],
        cwd=ROOT,
        env={k: v for k, v in os.environ.items() if k != "PYTEST_XDIST_WORKER"}
        | {"JAX_COMPILATION_CACHE_DIR": ""},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    seconds = json.loads(report.read_text())
    ids = [
        f"{LEVEL_TESTS}::{name}"
        for name in (
            "test_an_unmarked_test_compiles_at_the_default_level",
            "test_the_next_test_is_back_at_the_default_level",
        )
    ]
    assert set(ids) <= set(seconds)
    assert all(row["wall"] > 0.0 for row in seconds.values())
    first = seconds[ids[0]]  # jit(x + 1) traced, lowered and compiled in that test
    for event in (
        "jaxpr_trace_duration",
        "jaxpr_to_mlir_module_duration",
        "backend_compile_duration",
    ):
        assert first[f"/jax/core/compile/{event}"] > 0.0
    assert "/jax/core/compile/backend_compile_duration" not in seconds[ids[1]]  # compiles nothing
    # the program itself, in order: traced, its arguments' shapes, compiled by XLA
    assert [row[:2] for row in first["programs"]] == [
        ["trace", "<lambda>"],
        [
            "args",
            "jit(<lambda>) with global shapes and types (ShapedArray(float64[], weak_type=True),)",
        ],
        ["xla", "jit(<lambda>)"],
    ]
    assert all(s > 0.0 for kind, _, s in first["programs"] if kind != "args")
    assert seconds[ids[1]]["programs"] == []

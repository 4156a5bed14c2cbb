"""The benchmark suites stay runnable (issue 44): every section imports, every suite lists its
sections, the benchmarks import only public names (but the listed ones still pending), and one
cheap section runs end to end through its suite with ``--quick``.

The full ``--quick`` run of every suite takes minutes (accuracy alone ~9 min on the 2-core box):
``pytest -m bench_quick tests/benchmarks`` runs it; the normal suite runs the cheap checks below.
"""

import ast
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
BENCH = REPO / "benchmarks"
SUITES = ("forward", "fitting", "accuracy", "parallel")

# benchmarks/… that still import a name outside the public surface: the measurement needs an
# internal the public API does not expose (issue 44 item 4, left for the lead). Only shrinks.
PENDING = {
    "parts/ball_mode_growth.py": {"rbjax.studies.growth"},
    "parts/design_check.py": {"rbjax.studies.design"},
    "parts/fit_time.py": {"rbjax.fit.layout", "rbjax.fit.problem", "rbjax.fit.record_forces"},
    "parts/history_speed.py": {"rbjax.solve.sampled"},
    "parts/selection_lanes.py": {"rbjax.fit.lanes", "rbjax.fit.problem", "rbjax.fit.program"},
    "parts/summary_fit.py": {"rbjax.fit.summary", "rbjax.fit.summary_table"},
}


def _env(tmp_path):
    env = dict(os.environ, RBJAX_BENCH_RESULTS=str(tmp_path), RBJAX_CACHE_DIR="")
    env["JAX_DISABLE_MOST_OPTIMIZATIONS"] = "1"  # a smoke run: no figure is checked
    return env


def _non_public(module: str, names: list[str]) -> list[str]:
    if module.split(".")[0] != "rbjax":
        return []
    mod = importlib.import_module(module)
    if module != "rbjax" and Path(mod.__file__).name != "__init__.py":
        return [module]
    public = set(getattr(mod, "__all__", ()))
    bad = []
    for name in names:
        sub = getattr(mod, name, None)
        is_package = getattr(sub, "__file__", "").endswith("__init__.py")
        if name not in public and not is_package:
            bad.append(f"{module}.{name}")
    return bad


def test_benchmarks_import_only_public_names():
    found = {}
    for path in sorted(BENCH.rglob("*.py")):
        rel = path.relative_to(BENCH).as_posix()
        for node in ast.walk(ast.parse(path.read_text())):
            bad = []
            if isinstance(node, ast.ImportFrom) and node.module:
                bad = _non_public(node.module, [a.name for a in node.names])
            elif isinstance(node, ast.Import):
                bad = [m for a in node.names for m in _non_public(a.name, [])]
            if bad:
                found.setdefault(rel, set()).update(bad)
    for rel, names in found.items():
        pending = PENDING.get(rel, set())
        assert names <= pending, f"benchmarks/{rel} imports non-public {sorted(names - pending)}"


def test_every_section_imports_and_every_suite_lists(tmp_path):
    code = (
        f"import sys; sys.path[:0] = [{str(BENCH)!r}]; import importlib\n"
        f"for suite in {SUITES!r}:\n"
        "    m = importlib.import_module(suite)\n"
        "    for s in m.SECTIONS:\n"
        "        if not s.isolated:\n"
        "            importlib.import_module('parts.' + s.name)\n"
        "        print(suite, s.name)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=_env(tmp_path), capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-3000:]
    listed = {line.split()[1] for line in out.stdout.splitlines()}
    modules = {p.stem for p in (BENCH / "parts").glob("*.py")} - {"__init__", "scipy_fit"}
    assert listed == modules, "every part is a section of a suite"
    readme = (BENCH / "README.md").read_text()
    for name in [*SUITES, *listed, "device_check"]:
        assert name in readme, f"{name} is not in benchmarks/README.md"


def test_a_suite_runs_quick(tmp_path):
    cmd = [sys.executable, str(BENCH / "forward.py"), "--quick", "--only", "pulse_spectrum"]
    out = subprocess.run(cmd, env=_env(tmp_path), capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-3000:]
    record = json.loads((tmp_path / "forward_quick.json").read_text())
    assert [s["outcome"] for s in record["sections"]] == ["ok"]
    assert (tmp_path / "pulse_spectrum.json").exists() or any(tmp_path.glob("pulse_spectrum*"))


@pytest.mark.bench_quick
@pytest.mark.parametrize("suite", SUITES)
def test_every_suite_runs_quick(suite, tmp_path):
    out = subprocess.run(
        [sys.executable, str(BENCH / f"{suite}.py"), "--quick"],
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        cwd=REPO,
    )
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]


def test_device_check_is_a_script():
    out = subprocess.run(
        [sys.executable, str(BENCH / "device_check.py"), "--help"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-2000:]

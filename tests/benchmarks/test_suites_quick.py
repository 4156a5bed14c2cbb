"""The benchmark suites stay runnable (issue 44): every section imports, every suite lists its
sections, the benchmarks import only public names (but the listed ones, which need an internal),
and each suite runs its cheapest section end to end with ``--quick``.

The full ``--quick`` run of every suite takes minutes on the 2-core box (benchmarks/README.md has
the times): ``pytest -m bench_quick tests/benchmarks`` runs it; the normal suite runs the cheap
checks below.
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
#: each suite's cheapest section with ``--quick`` (seconds; benchmarks/README.md)
CHEAPEST = {
    "forward": "pulse_spectrum",
    "fitting": "summary_fit",
    "accuracy": "opt_levels",
    "parallel": "multicore",
}

# benchmarks/… that import a name outside the public surface (a package's ``__all__``), each
# because the measurement needs what no public name exposes. Only shrinks.
PENDING = {
    # one LM evaluation of the fit's compiled program against the forward histories alone: the
    # program (Problem, fit_solver) and the sampled forward (record_forces) are the fit's insides
    "parts/fit_time.py": {"rbjax.fit.problem", "rbjax.fit.record_forces"},
    # counts every call of the fit program through the batched-fit executor's run hook: the
    # count is the measurement (BatchedFitExecutor, run_lanes, STEPS_PER_ROUND are the fit's
    # insides)
    "parts/selection_lanes.py": {"rbjax.fit.batching", "rbjax.fit.problem", "rbjax.fit.program"},
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
    for rel, names in PENDING.items():
        assert found.get(rel, set()) == names, (
            f"benchmarks/{rel}: shrink PENDING to {found.get(rel)}"
        )


def test_every_section_imports_and_every_suite_lists(tmp_path):
    # the isolated sections (XLA flags set at import) last: their flags then change nothing here
    code = (
        f"import sys; sys.path[:0] = [{str(BENCH)!r}]; import importlib\n"
        f"suites = [importlib.import_module(s) for s in {SUITES!r}]\n"
        "sections = [(m.__name__, s) for m in suites for s in m.SECTIONS]\n"
        "for suite, s in sorted(sections, key=lambda x: x[1].isolated):\n"
        "    importlib.import_module('parts.' + s.name)\n"
        "    print(suite, s.name)\n"
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
    for suite in SUITES:
        shown = subprocess.run(
            [sys.executable, str(BENCH / f"{suite}.py"), "--list"], capture_output=True, text=True
        )
        assert shown.returncode == 0, shown.stderr[-2000:]
        names = {line.split()[0] for line in shown.stdout.splitlines() if line.strip()}
        assert names <= modules and CHEAPEST[suite] in names, shown.stdout


def _run_quick(suite: str, tmp_path, *only: str) -> subprocess.CompletedProcess:
    args = [a for name in only for a in ("--only", name)]
    return subprocess.run(
        [sys.executable, str(BENCH / f"{suite}.py"), "--quick", *args],
        env=_env(tmp_path),
        capture_output=True,
        text=True,
        cwd=REPO,
    )


@pytest.mark.parametrize("suite", SUITES)
def test_each_suite_runs_its_cheapest_section_quick(suite, tmp_path):
    out = _run_quick(suite, tmp_path, CHEAPEST[suite])
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-3000:]
    record = json.loads((tmp_path / f"{suite}_quick.json").read_text())
    assert [(s["section"], s["outcome"]) for s in record["sections"]] == [(CHEAPEST[suite], "ok")]
    assert (tmp_path / f"{CHEAPEST[suite]}_quick.json").exists(), sorted(tmp_path.iterdir())


@pytest.mark.bench_quick
@pytest.mark.parametrize("suite", SUITES)
def test_every_suite_runs_quick(suite, tmp_path):
    out = _run_quick(suite, tmp_path)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]


def test_device_check_is_a_script():
    out = subprocess.run(
        [sys.executable, str(BENCH / "device_check.py"), "--help"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-2000:]

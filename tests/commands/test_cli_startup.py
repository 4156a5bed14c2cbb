"""An instant command line: ``rbjax --help``, ``rbjax COMMAND --help`` and ``rbjax --version``
answer without importing JAX, NumPy, SciPy or Matplotlib, and ``import rbjax`` (even with
every layer) pulls no SciPy submodule nor Matplotlib (the figures measured:
benchmarks/RESULTS.md, "Start-up time").
Each check runs in a fresh interpreter: in this one the library is loaded already."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import textwrap

from rbjax.cli import build_parser, command_modules
from rbjax.commands.simulate import FLOOR_PRESET_NAMES
from rbjax.terms.floors.presets import FLOOR_PRESETS
from rbjax.terms.model import BLOCKED_FORCE_OPTIONS, GAS_OPTIONS

HEAVY = ("jax", "jaxlib", "numpy", "scipy", "matplotlib", "diffrax", "equinox")


def run_python(code: str) -> dict:
    proc = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_help_and_version_import_no_library():
    out = run_python(
        f"""
        import contextlib, io, json, sys
        from rbjax.cli import build_parser, command_modules, main

        codes = {{}}
        for argv in (["--help"], ["--version"], *([c, "--help"] for c in command_modules())):
            with contextlib.redirect_stdout(io.StringIO()) as text:
                codes[" ".join(argv)] = (main(argv), len(text.getvalue()))
        heavy = sorted(m for m in sys.modules if m.split(".")[0] in {HEAVY!r})
        print(json.dumps({{"codes": codes, "heavy": heavy}}))
        """
    )
    assert out["heavy"] == []
    assert len(out["codes"]) == len(command_modules()) + 2 >= 10
    # every one answers (a usage text, or "rbjax 0.2.0")
    assert all(code == 0 and size > 10 for code, size in out["codes"].values()), out["codes"]


def test_the_help_names_the_floor_presets():
    # written out in the command so that --help imports no library
    assert FLOOR_PRESET_NAMES == FLOOR_PRESETS


def test_the_gas_and_blocked_force_choices_are_the_library_s():
    # written out in the commands for the same reason: one definition (rbjax.terms.model) all
    # the same; `rbjax select` adds "both"
    subcommands = next(
        a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)
    )
    seen = {"gas": 0, "blocked_force": 0}
    for name, parser in subcommands.choices.items():
        for action in parser._actions:
            if action.dest == "gas" and action.choices is not None:
                assert tuple(action.choices) == GAS_OPTIONS, name
                seen["gas"] += 1
            if action.dest == "blocked_force" and action.choices is not None:
                extra = ("both",) if name == "select" else ()
                assert tuple(action.choices) == BLOCKED_FORCE_OPTIONS + extra, name
                seen["blocked_force"] += 1
    assert seen["gas"] >= 4 and seen["blocked_force"] >= 4


def test_import_rbjax_pulls_no_scipy_submodule_nor_matplotlib():
    out = run_python(
        """
        import json, sys
        import rbjax
        bare = sorted(m for m in sys.modules if m.split(".")[0] in ("jax", "scipy"))
        import jax
        import rbjax.data, rbjax.fit, rbjax.report, rbjax.room, rbjax.solve, rbjax.studies
        rbjax.simulate
        heavy = sorted(m for m in sys.modules if m.split(".")[0] in ("scipy", "matplotlib"))
        scipy_parts = sorted({m.split(".")[1] for m in heavy if m.count(".") and m[:6] == "scipy."})
        print(json.dumps({"bare": bare, "x64": bool(jax.config.jax_enable_x64),
                          "matplotlib": [m for m in heavy if m.startswith("matplotlib")],
                          "scipy": scipy_parts}))
        """
    )
    assert out["bare"] == []  # import rbjax alone: the names load on first use
    assert out["x64"]  # float64 on, though JAX was imported after rbjax
    assert out["matplotlib"] == []
    # at most SciPy's own internals (JAX's dependencies may import some); no SciPy module the
    # library uses where it is needed (signal, stats, optimize, fft, io, linalg)
    assert not set(out["scipy"]) & {"signal", "stats", "optimize", "fft", "io", "linalg"}


def test_the_lazy_names_are_the_typed_names_and_all():
    """``rbjax/__init__.py`` lists each public name three times (for type checkers under
    ``TYPE_CHECKING``, for ``__getattr__`` in ``_WHERE``, and ``__all__``): they agree, and
    each loads from the module it names."""
    import ast

    import rbjax

    tree = ast.parse(open(rbjax.__file__).read())
    typed = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for imp in node.body:
                assert isinstance(imp, ast.ImportFrom)
                typed |= {a.name: imp.module for a in imp.names}
    assert typed == rbjax._MODULE_OF
    assert set(rbjax.__all__) == set(typed)
    for name, module in typed.items():
        assert getattr(rbjax, name) is getattr(__import__(f"rbjax.{module}", fromlist=[name]), name)

"""No module imports another module's ``_private`` name (docs/architecture.md): a helper that two
modules share has a public name in the module where it belongs. Read from the source text like
``tests/test_layout.py`` (every ``import`` statement, lazy and ``TYPE_CHECKING`` ones included).

A package's own ``__init__`` re-exporting a private name counts as well. Dunder names
(``__version__``) are not private, and a package-private *module* (``rbjax._x64``,
``rbjax.studies.sensitivity._common``) may be imported by the modules of its package: the rule
is about the names defined inside another module.
"""

from __future__ import annotations

import ast

from test_layout import MODULES, rbjax_from_imports


def is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_imports(name: str, source: str) -> list[str]:
    """``"module: target.name"`` for each private name of another rbjax module imported in
    ``source`` (the text of module ``name``)."""
    return [
        f"{name}: {target}.{alias}"
        for target, alias in rbjax_from_imports(name, source)
        if is_private(alias) and f"{target}.{alias}" not in MODULES
    ]


def test_the_check_finds_a_private_import():
    source = (
        "from .ode import _phases, solve_phases\n"
        "from .. import _x64, __version__\n"
        "def f():\n"
        "    from rbjax.solve.simulate import _simulate\n"
    )
    assert private_imports("rbjax.solve.energy", source) == [
        "rbjax.solve.energy: rbjax.solve.ode._phases",
        "rbjax.solve.energy: rbjax.solve.simulate._simulate",
    ]
    # a package's facade re-exporting a private name of its own module counts too
    assert private_imports("rbjax.solve", "from .ode import _final\n") == [
        "rbjax.solve: rbjax.solve.ode._final"
    ]


def test_no_module_imports_another_modules_private_name():
    found = [
        hit for name, path in MODULES.items() for hit in private_imports(name, path.read_text())
    ]
    assert found == []


#: An import inside a function says why beside it (on its line or in the comment lines just
#: above its block of imports): ``lazy: <what it costs at import>`` or ``cycle``. The command
#: line's modules import the library inside their ``run`` by design (an instant ``--help``).
REASON = ("lazy", "cycle")


def unexplained_imports(source: str) -> list[int]:
    """Lines of the imports inside functions of ``source`` with no reason written beside them."""
    lines = source.splitlines()
    tree = ast.parse(source)
    out = []
    for fn in ast.walk(tree):
        if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        for node in ast.walk(fn):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            above, i = [lines[node.lineno - 1]], node.lineno - 2
            while i >= 0 and lines[i].strip().startswith(("#", "import ", "from ")):
                above.append(lines[i])
                i -= 1
            if not any(word in line for line in above for word in REASON):
                out.append(node.lineno)
    return sorted(set(out))


def test_the_check_finds_an_unexplained_import():
    source = (
        "def f():\n"
        "    # lazy: SciPy's signal costs 1 s at import\n"
        "    import scipy.signal\n"
        "    from scipy.stats import norm\n"
        "\n"
        "    import numpy as np\n"
    )
    assert unexplained_imports(source) == [6]


def test_imports_inside_functions_say_why():
    found = {
        name: lines
        for name, path in MODULES.items()
        if not name.startswith(("rbjax.commands", "rbjax.cli"))
        and (lines := unexplained_imports(path.read_text()))
    }
    assert found == {}

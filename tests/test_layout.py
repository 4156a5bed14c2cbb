"""The package's layout (docs/architecture.md): one package per layer, imports pointing down, no
import cycle anywhere in src/, nothing below the command line importing ``rbjax.commands``,
small modules. Read from the source text (every ``import`` statement, lazy and
``TYPE_CHECKING`` ones included), so it holds however the modules are loaded."""

from __future__ import annotations

import ast
from pathlib import Path

import rbjax

SRC = Path(rbjax.__file__).parent

#: Layers from the bottom up (docs/architecture.md): a module may import its own layer and the
#: layers below it, never one above.
LAYERS = ("terms", "spectrum", "solve", "room", "data", "fit", "studies", "report", "commands")
#: Top-level helpers beside the packages, and the layers they may import.
HELPERS = {
    "_x64": (),
    "_validate": (),
    "_progress": (),
    "_exit": (),
    "text": (),
    "plot": ("spectrum",),
}
#: A module holds one idea: at most this many statements (``ast.stmt`` nodes, nested ones
#: included). Statements, not lines, so that the formatter's wrapping never forces a split;
#: 300 is what the largest modules held under the former 500-line cap.
MAX_STATEMENTS = 300


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in SRC.rglob("*.py")}


def rbjax_from_imports(name: str, source: str):
    """(module, imported name) of every ``from … import`` of an rbjax module in ``source`` (the
    text of module ``name``), relative imports resolved."""
    is_package = name in MODULES and MODULES[name].name == "__init__.py"
    package = name if is_package else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = package.split(".")
            base = base[: len(base) - (node.level - 1)]
            target = ".".join(base + ([node.module] if node.module else []))
        else:
            target = node.module or ""
        if target.split(".")[0] == "rbjax":
            yield from ((target, alias.name) for alias in node.names)


def imports_of(name: str) -> set[str]:
    """The rbjax modules ``name`` imports (``from pkg import mod`` counts as ``pkg.mod``)."""
    source = MODULES[name].read_text()
    out = {
        a.name
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.Import)
        for a in node.names
        if a.name.split(".")[0] == "rbjax"
    }
    for target, alias in rbjax_from_imports(name, source):
        full = f"{target}.{alias}"
        out.add(full if full in MODULES else target)
    return out - {name}


GRAPH = {name: imports_of(name) for name in MODULES}


def layer_of(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_every_import_resolves_to_a_module():
    # the graph below is only as good as its edges: each one names a module of the package
    assert all(target in MODULES for targets in GRAPH.values() for target in targets)
    assert len(GRAPH) > 40 and sum(map(len, GRAPH.values())) > 150


def _cycles(graph):
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_cycle():
    # Package facades (``__init__``) only re-export: they are left out, as Python imports them
    # before their modules (the modules themselves never import their own facade).
    graph = {
        v: {w for w in ws if not MODULES[w].name == "__init__.py" or w == "rbjax.data"}
        for v, ws in GRAPH.items()
        if MODULES[v].name != "__init__.py"
    }
    graph = {v: ws & set(graph) for v, ws in graph.items()}
    assert _cycles(graph) == []


def test_imports_point_down_the_layers():
    upward = []
    for name, targets in GRAPH.items():
        if name == "rbjax" or name == "rbjax.cli":
            continue
        mine = layer_of(name)
        for target in targets:
            theirs = layer_of(target)
            if theirs in HELPERS or theirs == "" or theirs == mine:
                continue
            if mine in HELPERS:
                ok = theirs in HELPERS[mine]
            else:
                ok = theirs in LAYERS and LAYERS.index(theirs) < LAYERS.index(mine)
            if not ok:
                upward.append(f"{name} -> {target}")
    assert upward == []


def test_library_never_imports_the_commands():
    offenders = [
        n
        for n, ts in GRAPH.items()
        if layer_of(n) not in ("commands", "cli") and any(layer_of(t) == "commands" for t in ts)
    ]
    assert offenders == []


def test_top_level_holds_packages_and_a_few_helpers():
    files = sorted(p.stem for p in SRC.glob("*.py"))
    packages = sorted(p.name for p in SRC.iterdir() if (p / "__init__.py").exists())
    # every layer is a package; a helper is one module, or a package once it outgrows one (plot/)
    assert set(LAYERS) <= set(packages)
    assert sorted(files + packages) == sorted(["__init__", "cli", *HELPERS, *LAYERS])


def statements(path: Path) -> int:
    return sum(isinstance(node, ast.stmt) for node in ast.walk(ast.parse(path.read_text())))


def test_statement_count_counts_nested_statements():
    assert (
        sum(isinstance(n, ast.stmt) for n in ast.walk(ast.parse("if a:\n    b = 1\n    c()\n")))
        == 3
    )


def test_no_module_over_the_statement_cap():
    big = {n: statements(p) for n, p in MODULES.items()}
    assert {n: k for n, k in big.items() if k > MAX_STATEMENTS} == {}

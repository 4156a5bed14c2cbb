"""Every figure a page states is registered: ``docs/claims.toml`` lists each number with a unit
(dB, %, ms, s, N, ×, impacts/s) that ``README.md``, the pages of ``docs/`` and the notebooks'
markdown cells state, with what holds it:

- ``test = "tests/path.py::test_name"`` and ``tolerance``: a test asserts the figure, at that
  tolerance (or ``"notebooks/NAME.ipynb"``: an ``assert`` in a code cell that names the figure's
  number, which the suite executes);
- ``measured = "<a heading of benchmarks/RESULTS.md>"`` and ``date``: a dated benchmark
  measurement (speed lives in ``benchmarks/``, not in timed tests);
- ``source = "..."``: not rbjax's result but a cited one (a standard's table, the paper's
  stated measurement);
- ``input = "..."``: a setting or a definition the page states (a drop height, a tolerance a
  bar is set to), not a result;
- ``unheld = "..."``: a result nothing holds yet, said so; ``test_no_figure_is_unheld`` fails
  on any (issue 45 held the last of them).

An entry is keyed by its page and its figure as written (spaces normalised; ``figures`` lists
several of one page held the same way); where one figure
stands on a page for different things, ``quote`` (a piece of the figure's line) tells the
entries apart. The first test fails on a figure with no entry, the second on an entry whose test
does not exist, whose measurement names no dated section, or whose figure is no longer on its
page. Pure text: nothing of rbjax is imported.
"""

from __future__ import annotations

import ast
import functools
import json
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REGISTRY = ROOT / "docs" / "claims.toml"
RESULTS = ROOT / "benchmarks" / "RESULTS.md"

#: Fenced blocks of these languages are code or command lines, not statements of results; a
#: block without a language (or ``text``) is printed output and is read.
CODE_LANGUAGES = {"bash", "sh", "shell", "console", "python", "py", "toml", "json", "yaml"}

_SPACE = "[ \u00a0\u2009\u202f]"
_NUMBER = r"[+−-]?\d+(?:[\u00a0\u2009\u202f ,]\d{3})*(?:\.\d+)?(?:e[+−-]?\d+)?"
_JOIN = r"\s*(?:–|—|-|±|/|to)\s*"
_UNIT = r"(?:impacts/s|dB|ms|%|(?<=\d)×|×(?!\s?[\d(])|x(?=\W|$)|s|N(?!\s?s/m)|/s)"
#: A number (or a range, ± or /-list of numbers) with a unit, or a factor written ×1.44.
FIGURE = re.compile(
    rf"(?<![\w.]){_NUMBER}(?:{_JOIN}{_NUMBER})*{_SPACE}?{_UNIT}(?![\w/^·])"
    rf"|(?<![\w.])×\d+(?:\.\d+)?(?![\w.])"
)


@dataclass(frozen=True)
class Figure:
    page: str
    figure: str  # as written, spaces normalised
    line: str  # the line it stands on (for the quote and the message)
    lineno: int


def normalise(text: str) -> str:
    return re.sub(r"[ \u00a0\u2009\u202f]+", " ", text).strip()


def _strip_code(text: str) -> str:
    """The text with fenced code blocks of code languages blanked (line numbers kept)."""
    out, fence, skip = [], None, False
    for line in text.split("\n"):
        m = re.match(r"^\s*(```+|~~~+)\s*([\w+-]*)", line)
        if fence is None and m:
            fence, skip = m.group(1), m.group(2).lower() in CODE_LANGUAGES
            out.append("")
            continue
        if fence is not None and line.strip().startswith(fence):
            fence = None
            out.append("")
            continue
        out.append("" if fence is not None and skip else line)
    return "\n".join(out)


@functools.cache
def page_texts() -> dict[str, str]:
    """README.md, every docs/**/*.md and the markdown cells of notebooks/*.ipynb."""
    pages = {"README.md": (ROOT / "README.md").read_text(encoding="utf-8")}
    for path in sorted((ROOT / "docs").rglob("*.md")):
        pages[path.relative_to(ROOT).as_posix()] = path.read_text(encoding="utf-8")
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        markdown = ["".join(c["source"]) for c in cells if c["cell_type"] == "markdown"]
        pages[path.relative_to(ROOT).as_posix()] = "\n\n".join(markdown)
    return pages


def figures(page: str, text: str) -> list[Figure]:
    found = []
    for lineno, line in enumerate(_strip_code(text).split("\n"), 1):
        for m in FIGURE.finditer(line):
            found.append(Figure(page, normalise(m.group(0)), line, lineno))
    return found


@functools.cache
def all_figures() -> list[Figure]:
    return [f for page, text in page_texts().items() for f in figures(page, text)]


def registry() -> list[dict]:
    """The entries, one per figure (an entry may list several ``figures`` of one page held the
    same way: it stands for one entry each)."""
    entries = []
    for e in tomllib.loads(REGISTRY.read_text(encoding="utf-8"))["claim"]:
        listed = e.get("figures", [])
        if "figure" in e:
            listed = [e["figure"], *listed]
        rest = {k: v for k, v in e.items() if k not in ("figure", "figures")}
        entries += [{**rest, "figure": f} for f in listed] or [rest]
    return entries


def entry_for(figure: Figure, entries: list[dict]) -> dict | None:
    """The entry of a figure: one with its quote in the figure's line first, else one without."""
    same = [e for e in entries if e["page"] == figure.page and e["figure"] == figure.figure]
    quoted = [e for e in same if "quote" in e and e["quote"] in normalise(figure.line)]
    if quoted:
        return quoted[0]
    unquoted = [e for e in same if "quote" not in e]
    return unquoted[0] if unquoted else None


def test_the_scanner_reads_figures_as_written():
    text = (
        "within 4.9–11.2 dB, 1.03 ± 0.16 %, −1.8 %, +1.9 %, 3 000× faster (×1.44), 1\u202f000 N,\n"
        "20.43 ms, 2 s; 1,791,123/s and 2.2e5 impacts/s; not 1.6 m, 3 starts, 40 N·s/m.\n"
        "```bash\nrbjax simulate --max 5 s\n```\n```\nprinted 7.5 dB\n```\n"
    )
    assert [f.figure for f in figures("p.md", text)] == [
        "4.9–11.2 dB",
        "1.03 ± 0.16 %",
        "−1.8 %",
        "+1.9 %",
        "3 000×",
        "×1.44",
        "1 000 N",
        "20.43 ms",
        "2 s",
        "1,791,123/s",
        "2.2e5 impacts/s",
        "7.5 dB",
    ]


def test_every_figure_on_the_pages_has_an_entry():
    entries = registry()
    missing = [f for f in all_figures() if entry_for(f, entries) is None]
    assert not missing, f"{len(missing)} figures with no entry in docs/claims.toml:\n" + "\n".join(
        f"  {f.page}:{f.lineno}: {f.figure!r} in {normalise(f.line)[:120]!r}" for f in missing
    )


def _notebook_asserts(ref: str, figure: str) -> bool:
    """A notebook's code cell that asserts (the suite executes the notebooks) and names the
    figure's first number."""
    file = ROOT / ref
    if not file.is_file():
        return False
    number = re.search(r"\d+(?:\.\d+)?", figure.replace(" ", ""))
    cells = json.loads(file.read_text(encoding="utf-8"))["cells"]
    code = ["".join(c["source"]) for c in cells if c["cell_type"] == "code"]
    return number is not None and any("assert" in c and number.group(0) in c for c in code)


@functools.cache
def _parsed(file: Path) -> ast.Module:
    return ast.parse(file.read_text(encoding="utf-8"))


def _test_exists(ref: str, figure: str) -> bool:
    if ref.endswith(".ipynb"):
        return _notebook_asserts(ref, figure)
    path, _, name = ref.partition("::")
    file = ROOT / path
    if not file.is_file() or not name:
        return False
    names = name.split("[")[0].split("::")  # Class::test, test[param-id]
    tree = _parsed(file)
    scope: list[ast.stmt] = tree.body
    for part in names:
        found = [
            n
            for n in scope
            if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)
            and n.name == part
        ]
        if not found:
            return False
        scope = found[0].body
    return True


def _results_sections() -> dict[str, str]:
    """Each heading of benchmarks/RESULTS.md (without the #s) and its section's text."""
    sections: dict[str, str] = {}
    heading = None
    for line in RESULTS.read_text(encoding="utf-8").split("\n"):
        m = re.match(r"^(#+)\s+(.*)$", line)
        if m:
            heading = m.group(2).strip()
            sections[heading] = line + "\n"
        elif heading is not None:
            sections[heading] += line + "\n"
    return sections


def test_every_entry_is_held_by_a_test_a_dated_measurement_or_a_source():
    entries = registry()
    sections = _results_sections()
    on_pages = {(f.page, f.figure) for f in all_figures()}
    texts = page_texts()
    problems = []
    for e in entries:
        where = f"{e.get('page')} {e.get('figure')!r}"
        kinds = [k for k in ("test", "measured", "source", "input", "unheld") if k in e]
        if len(kinds) != 1:
            problems.append(
                f"{where}: needs exactly one of test/measured/source/input/unheld: {kinds}"
            )
            continue
        if e["page"] not in texts:
            problems.append(f"{where}: no such page")
        elif (e["page"], e["figure"]) not in on_pages:
            problems.append(f"{where}: the page no longer states this figure (stale entry)")
        elif "quote" in e and e["quote"] not in normalise(texts[e["page"]]):
            problems.append(f"{where}: quote {e['quote']!r} no longer on the page")
        if "test" in e:
            refs = e["test"] if isinstance(e["test"], list) else [e["test"]]
            problems += [f"{where}: no test {r}" for r in refs if not _test_exists(r, e["figure"])]
            if not str(e.get("tolerance", "")).strip():
                problems.append(f"{where}: a test entry states the tolerance it is held to")
        elif "measured" in e:
            date = str(e.get("date", ""))
            heads = [h for h in sections if h.startswith(e["measured"])]
            if not re.fullmatch(r"\d{4}-\d{2}-\d{2}", date):
                problems.append(f"{where}: a measured entry has a date (YYYY-MM-DD)")
            elif not heads:
                problems.append(f"{where}: no heading {e['measured']!r} in benchmarks/RESULTS.md")
            elif date not in sections[heads[0]]:
                problems.append(f"{where}: section {heads[0]!r} does not state {date}")
        elif not str(e[kinds[0]]).strip():
            problems.append(f"{where}: {kinds[0]} says what it is")
    assert not problems, "\n".join(problems)


def test_no_figure_is_unheld():
    unheld = [f"{e['page']} {e['figure']!r}: {e['unheld']}" for e in registry() if "unheld" in e]
    assert not unheld, f"{len(unheld)} figures held by nothing:\n" + "\n".join(unheld)

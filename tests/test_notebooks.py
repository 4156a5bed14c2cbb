"""The notebooks are stored with their outputs (CONTRIBUTING.md, "The documentation site").

A reader on the code host or on the documentation site (mkdocs-jupyter renders them as stored,
without executing them) sees what is stored: a notebook stored without outputs shows no figure.
The test command executes them without writing to them (nbmake; ``pytest notebooks --overwrite``
refreshes the stored outputs, CONTRIBUTING.md) and then builds the site. Here the stored files
are read: every code cell has been run, in order, no cell stores an error, and every notebook
stores its figures (each of them draws).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).resolve().parents[1] / "notebooks").glob("*.ipynb"))


def _read(path: Path) -> dict:
    # in the test command nbmake may be writing this notebook back at the same moment
    for _ in range(20):
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except json.JSONDecodeError:
            time.sleep(0.5)
    return json.loads(path.read_text(encoding="utf-8"))


def test_the_notebooks_are_found():
    assert len(NOTEBOOKS) >= 6


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[path.name for path in NOTEBOOKS])
def test_the_notebook_is_stored_with_its_outputs(path):
    cells = [cell for cell in _read(path)["cells"] if cell["cell_type"] == "code"]
    assert cells
    counts = [cell.get("execution_count") for cell in cells]
    assert None not in counts, f"{path.name}: code cells stored without being run"
    assert counts == sorted(counts), f"{path.name}: cells run out of order: {counts}"
    for cell in cells:
        source = "".join(cell["source"])
        errors = [out for out in cell["outputs"] if out["output_type"] == "error"]
        assert not errors, f"{path.name}: a stored error in\n{source[:200]}"
    figures = sum(
        1
        for cell in cells
        for out in cell["outputs"]
        if any(kind.startswith("image/") for kind in out.get("data", {}))
    )
    assert figures > 0, f"{path.name}: no figure stored (every notebook here draws)"

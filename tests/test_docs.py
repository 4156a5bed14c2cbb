"""The documentation site's API reference lists every public name (docs/api/*.md).

Each page documents one package: its docstring, then every name of its ``__all__`` as a
mkdocstrings directive (``::: rbjax.fit.fit``). The docs build (``mkdocs build --strict`` in the
README's test command) fails on a directive whose object does not exist, and this test on a
public name the page leaves out, so the reference and ``__all__`` cannot drift apart. Nothing is
built here: the pages are read as text.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

API = Path(__file__).resolve().parents[1] / "docs" / "api"

PAGES = {
    "rbjax": "rbjax.md",
    "rbjax.fit": "fit.md",
    "rbjax.data": "data.md",
    "rbjax.room": "room.md",
    "rbjax.studies": "studies.md",
}


@pytest.mark.parametrize("module", sorted(PAGES))
def test_the_api_page_lists_every_public_name(module):
    text = (API / PAGES[module]).read_text(encoding="utf-8")
    listed = re.findall(rf"^::: {re.escape(module)}\.(\w+)$", text, flags=re.MULTILINE)
    public = importlib.import_module(module).__all__
    assert [name for name in public if name not in listed] == []  # missing from the page
    assert [name for name in listed if name not in public] == []  # not public (any more)
    assert len(listed) == len(set(listed))
    assert re.search(rf"^::: {re.escape(module)}$", text, flags=re.MULTILINE)  # the docstring

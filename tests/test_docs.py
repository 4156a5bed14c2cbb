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


def test_sphinx_roles_become_optional_autorefs():
    """docs/_hooks/sphinx_roles.py: a role becomes a link that may stay unresolved without a
    warning (``optional``), showing the name as written, or its last part after ``~``."""
    import importlib.util

    import griffe

    path = API.parent / "_hooks" / "sphinx_roles.py"
    spec = importlib.util.spec_from_file_location("sphinx_roles", path)
    assert spec is not None and spec.loader is not None
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    scope = griffe.Module("scope")
    text = "see :func:`rbjax.simulate` and :class:`~rbjax.terms.ball.Ball`, not ``code``"
    assert hook.convert(scope, text) == (
        'see <autoref identifier="rbjax.simulate" optional><code>rbjax.simulate</code></autoref>'
        ' and <autoref identifier="rbjax.terms.ball.Ball" optional><code>Ball</code></autoref>,'
        " not ``code``"
    )


def test_every_returns_section_renders_as_one_unnamed_item():
    """mkdocs.yml parses a ``Returns:`` section as one item (``returns_multiple_items: false``),
    after the hook has turned the roles into links: a first line such as ``The :class:`X`: ...``
    read before that would make "The" the name of the returned value."""
    import importlib.util

    import griffe

    path = API.parent / "_hooks" / "sphinx_roles.py"
    spec = importlib.util.spec_from_file_location("sphinx_roles", path)
    assert spec is not None and spec.loader is not None
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    src = API.parents[1] / "src"
    extensions = griffe.load_extensions(hook.SphinxRoles)
    package = griffe.load("rbjax", search_paths=[str(src)], extensions=extensions)

    def walk(obj):
        for member in obj.members.values():
            if not member.is_alias:
                yield member
                if member.is_module or member.is_class:
                    yield from walk(member)

    sections = [
        (obj.path, section)
        for obj in walk(package)
        if obj.docstring is not None
        for section in obj.docstring.parse("google", returns_multiple_items=False)
        if section.kind.value == "returns"
    ]
    assert len(sections) > 50
    named = [(name, section.value[0].name) for name, section in sections if section.value[0].name]
    assert named == []

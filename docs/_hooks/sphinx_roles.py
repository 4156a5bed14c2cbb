"""A griffe extension for the API pages: Sphinx cross-reference roles become autorefs.

rbjax's docstrings are Google style (``Args:``, ``Returns:``, ``Raises:``) and name other
objects with Sphinx roles (:func:`rbjax.simulate`, :mod:`rbjax.solve.ode`, :class:`~x.Y`).
mkdocstrings renders Markdown, where a role would show as raw text. When griffe has loaded the
package, this rewrites each role into an *optional* autorefs link
(``<autoref identifier="rbjax.simulate" optional><code>rbjax.simulate</code></autoref>``):
a name that the site documents becomes a link, any other (a private helper, a name of JAX or
SciPy) stays inline code, and neither warns under ``mkdocs build --strict``. A name written
relative to its module (:func:`simulate` inside ``rbjax.solve.simulate``) is resolved in the
scope of the object whose docstring names it. ``~`` shows the last component only, as Sphinx
does. The docstrings in the source are left as they are.
"""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|meth|class|mod|data|attr|exc|obj|const):`(~?)([^`<>]+?)`")


def _identifier(obj: griffe.Object, name: str) -> str:
    name = name.rstrip("()")
    if name.startswith("rbjax"):
        return name
    scope: griffe.Object | None = obj
    while scope is not None:
        try:
            return scope.resolve(name)
        except Exception:  # noqa: BLE001 - griffe raises several kinds for an unknown name
            scope = scope.parent
    return name


def convert(obj: griffe.Object, text: str) -> str:
    """``text`` with each Sphinx role written as an optional autorefs link."""

    def replace(match: re.Match[str]) -> str:
        tilde, name = match.groups()
        shown = name.split(".")[-1] if tilde else name
        target = _identifier(obj, name)
        return (
            f'<autoref identifier="{html.escape(target)}" optional>'
            f"<code>{html.escape(shown)}</code></autoref>"
        )

    return ROLE.sub(replace, text)


class SphinxRoles(griffe.Extension):
    """Rewrites the roles of every docstring of a loaded package (see the module docstring)."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        seen: set[int] = set()
        stack: list[griffe.Object] = [pkg]
        while stack:
            obj = stack.pop()
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            if obj.docstring is not None and ":" in obj.docstring.value:
                obj.docstring.value = convert(obj, obj.docstring.value)
            for member in obj.members.values():
                if not member.is_alias:
                    stack.append(member)  # type: ignore[arg-type]

"""Every public function and class documents its arguments, its result and its errors.

The API reference (docs/api/*.md, rendered by mkdocstrings from Google-style docstrings) shows
the sections it finds: a public name without them renders as a paragraph of prose with no list
of what to pass or what comes back. For every function and class in the ``__all__`` of the
packages the reference covers:

- a function or class that takes arguments has ``Args:`` (a class whose constructor arguments
  are its fields may name them under ``Attributes:`` instead);
- a function has ``Returns:`` (or ``Yields:``);
- a function whose own body raises, or a class whose constructor or ``__check_init__`` raises,
  has ``Raises:``.

The docstrings are read, nothing is built; the sections' contents are the authors' to write.
"""

from __future__ import annotations

import importlib
import inspect
import re

import pytest

PACKAGES = ("rbjax", "rbjax.fit", "rbjax.data", "rbjax.room", "rbjax.studies")
RAISE = re.compile(r"^\s*raise\b", flags=re.MULTILINE)
VALIDATORS = ("__init__", "__check_init__", "__post_init__")


def _public_objects():
    seen: dict[tuple[str, str], tuple[str, object]] = {}
    for package in PACKAGES:
        module = importlib.import_module(package)
        for name in module.__all__:
            obj = getattr(module, name)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            key = (obj.__module__, obj.__qualname__)
            seen.setdefault(key, (f"{package}.{name}", obj))
    return sorted(seen.values(), key=lambda item: item[0])


def _parameters(obj) -> list[str]:
    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    return [name for name in signature.parameters if name not in ("self", "cls")]


def _own_source(obj) -> str:
    """The source whose ``raise`` statements are this object's: a function's body, or a class's
    constructor and checks defined in the class itself (not inherited)."""
    if inspect.isfunction(obj):
        return inspect.getsource(inspect.unwrap(obj))
    parts = []
    for name in VALIDATORS:
        member = obj.__dict__.get(name)
        if inspect.isfunction(member):
            try:
                parts.append(inspect.getsource(member))
            except OSError:  # generated (a dataclass's or an equinox Module's __init__)
                pass
    return "\n".join(parts)


def missing_sections(obj) -> list[str]:
    doc = inspect.getdoc(obj) or ""
    sections = set(re.findall(r"^(\w+):\s*$", doc, flags=re.MULTILINE))
    missing = []
    if _parameters(obj) and not sections & {"Args", "Attributes"}:
        missing.append("Args")
    if inspect.isfunction(obj) and not sections & {"Returns", "Yields"}:
        missing.append("Returns")
    if RAISE.search(_own_source(obj)) and "Raises" not in sections:
        missing.append("Raises")
    return missing


PUBLIC = _public_objects()


def test_the_public_objects_are_found():
    # the five packages export well over a hundred functions and classes; an empty list
    # would make the test below pass vacuously
    assert len(PUBLIC) > 100


@pytest.mark.parametrize("name,obj", PUBLIC, ids=[name for name, _ in PUBLIC])
def test_public_docstring_has_its_sections(name, obj):
    assert missing_sections(obj) == [], f"{name}: add {missing_sections(obj)}"


def test_the_check_sees_a_missing_section():
    def documented(height_m):
        """Drop from a height.

        Args:
            height_m: the height.

        Returns:
            Nothing useful.

        Raises:
            ValueError: a negative height.
        """
        if height_m < 0:
            raise ValueError(height_m)

    def undocumented(height_m):
        """Drop from a height."""
        if height_m < 0:
            raise ValueError(height_m)

    assert missing_sections(documented) == []
    assert missing_sections(undocumented) == ["Args", "Returns", "Raises"]

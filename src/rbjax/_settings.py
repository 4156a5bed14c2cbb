"""Settings objects built from the keywords of a previous release (deprecated, one release)."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any, TypeVar

T = TypeVar("T")


def from_old_keywords(
    function: str, argument: str, cls: type[T], given: T | None, keywords: Mapping[str, Any], fields
) -> T:
    """``given`` (default ``cls()``), or a ``cls`` built from ``keywords``, the keywords of the
    previous signature of ``function`` that are now fields of ``cls`` (``fields``: keyword →
    field), with a ``DeprecationWarning``. ``given`` and such keywords together are a
    ``ValueError`` naming them (neither is dropped); an unknown keyword a ``TypeError``."""
    unknown = sorted(set(keywords) - set(fields))
    if unknown:
        raise TypeError(f"{function}() got unexpected keyword arguments {unknown}")
    if given is not None and not isinstance(given, cls):
        raise ValueError(f"{argument}={given!r} must be an rbjax {cls.__name__}")
    if not keywords:
        return cls() if given is None else given
    names = sorted(keywords)
    if given is not None:
        raise ValueError(
            f"{function} got {argument}= and the keywords {names}: give them in the "
            f"{cls.__name__} ({cls.__name__}(..., {', '.join(names)}=...))"
        )
    renamed = "".join(f" ({k}= is its {v}=)" for k, v in fields.items() if k != v and k in names)
    warnings.warn(
        f"{function}({', '.join(f'{k}=' for k in names)}...) is deprecated: pass "
        f"{argument}={cls.__name__}(...){renamed}",
        DeprecationWarning,
        stacklevel=4,
    )
    return cls(**{fields[k]: v for k, v in keywords.items()})

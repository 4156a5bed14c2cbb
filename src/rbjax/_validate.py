"""Validation at the API edge: clear messages naming the parameter, its value and the range."""

from __future__ import annotations

import math
from typing import TypeVar

import jax
import numpy as np
from jaxtyping import ArrayLike


def is_traced(x) -> bool:
    """True for values that are abstract under jit/grad/vmap (they cannot be checked here)."""
    return any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(x))


def as_float(x: ArrayLike) -> float:
    """``float(x)`` of a concrete scalar: a Python number or a 0-d numpy or JAX array."""
    return float(np.asarray(x).item())


def check_choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ValueError(
            f"{name}={value!r} is not a known option; valid: {', '.join(repr(c) for c in choices)}"
        )


def check_range(
    name: str,
    value,
    *,
    lower: float = -math.inf,
    upper: float = math.inf,
    lower_open: bool = True,
    upper_open: bool = True,
) -> None:
    """Check every element of ``value`` is finite and inside the interval; skip tracers."""
    if is_traced(value):
        return
    arr = np.asarray(value, dtype=float)
    lo = "(" if lower_open else "["
    hi = ")" if upper_open else "]"
    valid = f"{lo}{lower:g}, {upper:g}{hi}"
    bad = ~np.isfinite(arr)
    if lower_open:
        bad |= arr <= lower
    else:
        bad |= arr < lower
    if upper_open:
        bad |= arr >= upper
    else:
        bad |= arr > upper
    if np.any(bad):
        first = arr.reshape(-1)[np.argmax(bad.reshape(-1))]
        where = "" if arr.ndim == 0 else f" (element {int(np.argmax(bad.reshape(-1)))})"
        raise ValueError(
            f"{name}={float(first)!r}{where} is outside the valid range {valid} and finite"
        )


T = TypeVar("T")


def settings_or_default(argument: str, cls: type[T], given: T | None) -> T:
    """``given``, or ``cls()`` when it is ``None``; anything but a ``cls`` is a ``ValueError``
    naming ``argument``."""
    if given is None:
        return cls()
    if not isinstance(given, cls):
        raise ValueError(f"{argument}={given!r} must be an rbjax {cls.__name__}")
    return given

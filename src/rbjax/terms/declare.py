"""Parameter declarations: what a term says of each of its fields (unit, bounds, fitting
transform), and the check that a term declares every continuous field.

Terms import this module; the walker over a whole impact (:mod:`rbjax.terms.parameters`)
imports the terms, so declarations point one way and no term needs the model to exist."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .._validate import check_range

TRANSFORMS = ("log", "interval", "identity")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """Declaration of one continuous parameter.

    Attributes:
        unit: SI unit (``"1"`` for dimensionless).
        lower, upper: physical bounds; ``lower_open``/``upper_open`` say whether the bound
            itself is excluded.
        transform: the map from an unconstrained φ used by the optimiser to the parameter:
            ``log`` (θ = exp φ, for θ > 0), ``interval`` (θ = lower + (upper − lower)·sigmoid φ,
            for a bounded θ) or ``identity``.
        description: what the parameter is, with the equation it enters.

    Raises:
        ValueError: a ``transform`` other than ``log``, ``interval`` or ``identity``.
    """

    unit: str
    lower: float = -math.inf
    upper: float = math.inf
    lower_open: bool = True
    upper_open: bool = True
    transform: str = "identity"
    description: str = ""

    def __post_init__(self):
        if self.transform not in TRANSFORMS:
            raise ValueError(
                f"transform={self.transform!r} is not known; valid: {', '.join(TRANSFORMS)}"
            )

    def check(self, name: str, value) -> None:
        """Raise ``ValueError`` naming the parameter if a concrete value is outside its bounds."""
        check_range(
            name,
            value,
            lower=self.lower,
            upper=self.upper,
            lower_open=self.lower_open,
            upper_open=self.upper_open,
        )

    def to_unconstrained(self, value):
        """φ with ``from_unconstrained(φ) = value`` (values on a closed bound are moved inside by
        1e-12)."""
        xp = _namespace(value)
        value = xp.asarray(value, dtype=xp.float64)
        if self.transform == "log":
            return xp.log(xp.maximum(value, 1e-300))
        if self.transform == "interval":
            s = xp.clip((value - self.lower) / (self.upper - self.lower), 1e-12, 1.0 - 1e-12)
            return xp.log(s) - xp.log1p(-s)
        return value

    def from_unconstrained(self, phi):
        xp = _namespace(phi)
        phi = xp.asarray(phi, dtype=xp.float64)
        if self.transform == "log":
            return xp.exp(phi)
        if self.transform == "interval":
            return self.lower + (self.upper - self.lower) * _sigmoid(xp, phi)
        return phi

    def slope(self, phi):
        """dθ/dφ of :meth:`from_unconstrained` at φ."""
        xp = _namespace(phi)
        phi = xp.asarray(phi, dtype=xp.float64)
        if self.transform == "log":
            return xp.exp(phi)
        if self.transform == "interval":
            s = _sigmoid(xp, phi)
            return (self.upper - self.lower) * s * (1.0 - s)
        return xp.ones_like(phi)


def _namespace(x):
    """jax.numpy for JAX arrays and tracers (jit, grad), NumPy for host values (the fit's driver
    converts θ ↔ φ on the host every round: NumPy there, not one dispatched JAX op per entry)."""
    return jnp if isinstance(x, (jax.Array, jax.core.Tracer)) else np


def _sigmoid(xp, x):
    return jax.nn.sigmoid(x) if xp is jnp else 0.5 * (1.0 + np.tanh(0.5 * x))


POSITIVE: dict[str, Any] = dict(lower=0.0, transform="log")


NON_NEGATIVE: dict[str, Any] = dict(lower=0.0, lower_open=False, transform="log")


#: The drop height h_D (Eq. 10).
HEIGHT = Parameter("m", **POSITIVE, description="drop height h_D; impact speed √(2 g h_D) (Eq. 10)")


#: Per-record nuisances of a fit: the record's contact start on its time axis, and an error of
#: its nominal drop height (bounded by ±1 cm).
ONSET_SHIFT = Parameter("s", description="contact start of a record on its time axis")


HEIGHT_ERROR_BOUND_M = 0.01


HEIGHT_ERROR = Parameter(
    "m",
    lower=-HEIGHT_ERROR_BOUND_M,
    upper=HEIGHT_ERROR_BOUND_M,
    transform="interval",
    description="error of a record's nominal drop height",
)


def declarations(module) -> dict[str, Parameter]:
    """The ``PARAMETERS`` a term declares (empty for a module without any)."""
    return dict(getattr(type(module), "PARAMETERS", {}))


def check_declared(module) -> None:
    """Check every declared field of a term against its bounds (concrete values only)."""
    for name, spec in declarations(module).items():
        spec.check(name, getattr(module, name))

"""Ball parameters: a frozen, typed pytree with units in the names, and the JIS preset."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .._validate import is_traced
from .declare import POSITIVE, Parameter, check_declared
from .forces import reissner_stiffness_N_per_m


class Ball(eqx.Module):
    """A hollow elastic sphere (paper §2.1, Fig. 2).

    Fields are floats or JAX arrays (a batch of balls is a Ball of arrays), so a Ball goes
    through ``jax.grad``, ``jax.jacfwd`` and ``jax.vmap`` like any pytree.

    Attributes:
        radius_m: outer radius R of the shell.
        wall_m: wall thickness h, 0 < h < R.
        mass_kg: total mass M.
        youngs_Pa: Young's modulus E of the rubber.
        poisson: Poisson's ratio ν, −1 < ν ≤ 0.5.

    Raises:
        ValueError: a field outside its valid range or not finite, or ``wall_m`` ≥ ``radius_m``,
            named in the message (concrete values only).
    """

    radius_m: ArrayLike
    wall_m: ArrayLike
    mass_kg: ArrayLike
    youngs_Pa: ArrayLike
    poisson: ArrayLike
    PARAMETERS: ClassVar = {
        "radius_m": Parameter("m", **POSITIVE, description="outer radius R of the shell"),
        "wall_m": Parameter("m", **POSITIVE, description="wall thickness h (0 < h < R)"),
        "mass_kg": Parameter("kg", **POSITIVE, description="total mass M"),
        "youngs_Pa": Parameter("Pa", **POSITIVE, description="Young's modulus E (Eqs. 1–3)"),
        "poisson": Parameter(
            "1",
            lower=-1.0,
            upper=0.5,
            upper_open=False,
            transform="interval",
            description="Poisson's ratio ν (Eqs. 1–3)",
        ),
    }

    def __check_init__(self):
        validate_ball(self)

    def replace(self, **changes) -> Ball:
        """A copy with some fields changed, e.g. ``ball.replace(youngs_Pa=2e6)``."""
        names = {f.name for f in dataclasses.fields(self)}
        unknown = set(changes) - names
        if unknown:
            raise ValueError(
                f"unknown Ball field(s) {sorted(unknown)}; valid fields: {sorted(names)}"
            )
        return dataclasses.replace(self, **changes)

    def as_arrays(self) -> Ball:
        """The same ball with every field a float64 JAX array (what the jitted core takes)."""
        return Ball(
            *(
                jnp.asarray(getattr(self, f.name), dtype=jnp.float64)
                for f in dataclasses.fields(self)
            )
        )

    @property
    def stiffness_N_per_m(self):
        """Reissner's point-load stiffness of the shell, 4Eh²/(R√(3(1−ν²))) (corrected Eqs. 1–3)."""

        return reissner_stiffness_N_per_m(self)


def validate_ball(ball: Ball) -> None:
    """Raise ``ValueError`` naming the field if a concrete ball parameter is invalid."""
    check_declared(ball)
    if not (is_traced(ball.wall_m) or is_traced(ball.radius_m)):
        h = np.asarray(ball.wall_m, dtype=float)
        r = np.asarray(ball.radius_m, dtype=float)
        if np.any(h >= r):
            raise ValueError(
                f"wall_m={float(np.max(h))!r} must be smaller than radius_m={float(np.min(r))!r} "
                "(valid range: 0 < wall_m < radius_m)"
            )


#: The standard heavy impact ball with the paper's values (§4: R = 89 mm, h = 32 mm,
#: M = 2.5 kg from JIS A 1418-2; E = 1.6 MPa and ν = 0.5 from the literature [17]).
JIS_RUBBER_BALL = Ball(radius_m=0.089, wall_m=0.032, mass_kg=2.5, youngs_Pa=1.6e6, poisson=0.5)

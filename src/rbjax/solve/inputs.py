"""The API edge of the forward model: input checks and the broadcast of (height, ball, model)
to one batch axis, shared by every solve path (``simulate``, ``sampled_history``, fits)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._validate import check_range
from .._x64 import require_x64
from ..terms.ball import Ball
from ..terms.model import Model

#: The paper's output grid (§2.4): 44.1 kHz over 1 s.
PAPER_RATE_Hz = 44_100.0
PAPER_DURATION_S = 1.0


def broadcast_inputs(height_m, ball: Ball, model: Model):
    """Flatten height, ball and model parameters to one batch axis (shape kept for outputs)."""
    height = jnp.asarray(height_m, dtype=jnp.float64)
    ball = ball.as_arrays()
    arrays, static = eqx.partition(model, eqx.is_array_like)
    arrays = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype=jnp.float64), arrays)
    leaves = [height, *jax.tree_util.tree_leaves(ball), *jax.tree_util.tree_leaves(arrays)]
    shape = jnp.broadcast_shapes(*(x.shape for x in leaves))
    flat = lambda x: jnp.broadcast_to(x, shape).reshape(-1)  # noqa: E731
    height = flat(height)
    ball = jax.tree_util.tree_map(flat, ball)
    model = eqx.combine(jax.tree_util.tree_map(flat, arrays), static)
    return shape, height, ball, model


def _check_record(rate_Hz, duration_s) -> None:
    check_range("rate_Hz", rate_Hz, lower=0.0)
    check_range("duration_s", duration_s, lower=0.0)
    if int(round(rate_Hz * duration_s)) < 1:
        raise ValueError(
            f"duration_s={duration_s!r} at rate_Hz={rate_Hz!r} gives no sample; need "
            "rate_Hz·duration_s ≥ 1"
        )


def check_inputs(height_m, ball, rate_Hz=None, duration_s=None) -> None:
    """The checks at the API edge shared by simulate, trajectory and sensitivities."""
    require_x64()
    check_range("height_m", height_m, lower=0.0)
    if not isinstance(ball, Ball):
        raise ValueError(f"ball={ball!r} must be an rbjax.Ball")
    if rate_Hz is not None:
        _check_record(rate_Hz, duration_s)


def _as_float64(x):
    if isinstance(x, (jax.Array, jax.core.Tracer)):
        return x if x.dtype == jnp.float64 else jnp.asarray(x, dtype=jnp.float64)
    return np.asarray(x, dtype=np.float64)


def as_arrays(tree):
    """Every array-like leaf of ``tree`` as a float64 array (NumPy where concrete: an eager
    ``jnp.asarray`` per leaf costs more than the whole solve of a small batch), the rest kept,
    so that new values reuse a compiled program instead of retracing it (shared by the fast
    paths)."""
    arrays, static = eqx.partition(tree, eqx.is_array_like)
    return eqx.combine(jax.tree_util.tree_map(_as_float64, arrays), static)


#: The smallest batch the ODE fallback of the fast paths runs (padded): a handful of flagged
#: impacts costs ~10 s of compile per new shape and microseconds per extra impact, so batches of
#: 1–64 flagged impacts share one compiled program.
FALLBACK_MIN_BATCH = 64


def padded_rows(rows: np.ndarray, size: int | None = None) -> np.ndarray:
    """``rows`` padded with its first entry to ``size`` rows (default: a power of two, at least
    ``FALLBACK_MIN_BATCH``, so that the batches solved again by the ODE come in few shapes)."""
    if size is None:
        size = max(FALLBACK_MIN_BATCH, 1 << int(rows.size - 1).bit_length())
    return np.concatenate([rows, np.full(size - rows.size, rows[0])])

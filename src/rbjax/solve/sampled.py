"""Force histories of the rigid-floor models sampled inside the solve (fixed steps, no events).

A history is wanted at the samples t_k = k/rate of a record. ``rbjax.trajectory`` solves the
ODE adaptively to the located end of contact and evaluates its dense interpolant there; this
module instead steps Eq. 7 from sample to sample with a fixed step and records the state and
the floor force at every sample inside the loop:

* the classic fourth-order Runge–Kutta method, ``substeps`` steps of 1/(rate·substeps) per
  sample (default one step per sample: ~1e-10 of the peak force against the scipy reference
  at 44.1 kHz for the JIS ball, benchmarks/RESULTS.md "Histories sampled inside the solve");
* the vector field is ode.py's restitution field, valid in both phases: its momentum-flux
  thrust (M/2R)δ̇² acts only while δ̇ < 0, so no phase switch is needed; it is continuous
  with its first derivative at δ̇ = 0 (the thrust is quadratic in δ̇);
* contact starts at t = 0 with δ = 0, δ̇ = √(2 g h) and ends at the first time δ returns to 0
  or (damped models) the contact force returns to 0. Sample t_k (k ≥ 1) is in contact iff the
  end has not occurred in (0, t_k], decided by the signs of δ and of the contact force at the
  sample itself (an excursion that ends and comes back between two samples is not seen). Once
  a lane has ended it is frozen: force 0, ``in_contact`` False, the state no longer advanced.

Status per impact, with the codes of outcome.py: ``mass_singularity`` (δ ≥ 0.999·2R),
``deflection_limit`` (δ_max > ``max_deflection_ratio``·h; δ_max from the cubic Hermite
interpolant of the two samples around maximum compression), ``solver_failed`` (a non-finite
state or force), and ``step_limit`` when the contact is still going after the last computed
sample, at t_n (more samples are needed; a contact that ends between t_(n−1) and t_n is
complete). A failed impact gives NaN samples, never plausible numbers.

The trip count (the number of samples) is static: one compiled program per batch size, number
of samples, substeps and model structure; it works under ``jax.jit``, ``jax.vmap`` and
``jax.jacfwd``. Coupled models (a ball mode, a moving floor) are not handled here.
"""

from __future__ import annotations

import math
import operator

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .._validate import check_range
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.forces import singular_deflection_m
from ..terms.model import Model
from .inputs import PAPER_RATE_Hz, as_arrays, broadcast_inputs, check_inputs
from .outcome import (
    SINGULAR_FRACTION,
    STATUS_CODES,
    Trajectory,
    impact_velocity_m_per_s,
    nan_where,
)
from .vector_field import RESTITUTION_FIELD, contact_force, floor_force_N, initial_state

#: Fourth-order Runge–Kutta steps per sample unless the caller asks for more.
DEFAULT_SUBSTEPS = 1
#: Fewest Runge–Kutta steps over the shortest contact of a batch that ``force_history`` lets
#: through (it adds sub-steps below): ~5e-10 of the peak force or better, as the ODE path.
MIN_STEPS_PER_CONTACT = 400
#: Newton steps for the maximum of the cubic Hermite interpolant around maximum compression.
HERMITE_NEWTON_STEPS = 4


def _sample(y, ball, model):
    """(dy/dt, floor force, the contact not yet over) at state y. The three share the contact
    force, which XLA computes once (see ``sampled_impact``)."""
    inside = y[0] > 0.0
    if model.velocity_dependent:
        inside = inside & (contact_force(y, ball, model) > 0.0)
    return RESTITUTION_FIELD(0.0, y, (ball, model)), floor_force_N(y, ball, model), inside


def _rk4(y, k1, h, ball, model):
    """One classic Runge–Kutta step of length h from y, with k1 = dy/dt at y given."""

    def f(yy):
        return RESTITUTION_FIELD(0.0, yy, (ball, model))

    k2 = f(y + 0.5 * h * k1)
    k3 = f(y + 0.5 * h * k2)
    k4 = f(y + h * k3)
    return y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def _hermite_max(d0, v0, d1, v1, dt):
    """Maximum over the interval of the cubic Hermite interpolant of δ through (δ0, δ̇0) and
    (δ1, δ̇1) a time dt apart, for δ̇0 > 0 ≥ δ̇1 (Newton on p'(s) = 0 from the linear root of δ̇)."""
    a, b = d0 - d1, dt

    def slope(s):
        return (
            (6.0 * s * s - 6.0 * s) * a
            + (3.0 * s * s - 4.0 * s + 1.0) * b * v0
            + (3.0 * s * s - 2.0 * s) * b * v1
        )

    def curvature(s):
        return (12.0 * s - 6.0) * a + (6.0 * s - 4.0) * b * v0 + (6.0 * s - 2.0) * b * v1

    s = jnp.clip(v0 / jnp.where(v0 - v1 > 0.0, v0 - v1, 1.0), 0.0, 1.0)
    for _ in range(HERMITE_NEWTON_STEPS):
        c = curvature(s)
        s = jnp.clip(s - slope(s) / jnp.where(c < 0.0, c, -1.0), 0.0, 1.0)
    s2, s3 = s * s, s * s * s
    value = (
        (2.0 * s3 - 3.0 * s2 + 1.0) * d0
        + (s3 - 2.0 * s2 + s) * b * v0
        + (-2.0 * s3 + 3.0 * s2) * d1
        + (s3 - s2) * b * v1
    )
    return jnp.maximum(value, jnp.maximum(d0, d1))


def _max_deflection(d, v, inside, dt):
    """δ_max of one impact from its in-contact samples: the largest sample, or the Hermite
    maximum over the interval where δ̇ first changes sign, whichever is larger."""
    d_in = jnp.where(inside, d, 0.0)
    crossing = inside[1:] & (v[:-1] > 0.0) & (v[1:] <= 0.0)
    k = jnp.argmax(crossing)
    refined = _hermite_max(d[k], v[k], d[k + 1], v[k + 1], dt)
    return jnp.maximum(jnp.max(d_in), jnp.where(jnp.any(crossing), refined, 0.0))


def sampled_impact(height_m, ball, model: Model, rate_Hz, num_samples: int, substeps: int):
    """One impact: (δ, δ̇, floor force) at the ``num_samples`` samples k/rate_Hz from first
    contact, each (num_samples,), 0 out of contact, NaN if failed, and the status."""
    v0 = impact_velocity_m_per_s(height_m)
    y0 = initial_state(v0, ball, model)
    h = 1.0 / (rate_Hz * substeps)
    singular = SINGULAR_FRACTION * singular_deflection_m(ball, model)
    arrays, static = eqx.partition((ball, model), eqx.is_array)

    def step(carry, _):
        y, k1, force, going, ended, bad, singular_hit, i = carry
        # the sample at y (the incoming state): recorded, then the step to the next sample
        record = jnp.where(going, jnp.stack([y[0], y[1], force]), 0.0)
        # The parameters pass an optimization barrier keyed on the step counter: XLA would
        # otherwise hoist each loop-invariant subexpression (2R, k, ...) out of the loop once per
        # use, and the copies would keep it from merging the contact force shared by dy/dt, the
        # floor force and the end test (one gas-force power instead of two per sample).
        params, i = jax.lax.optimization_barrier((arrays, i))
        b, m = eqx.combine(params, static)
        yn, kn = y, k1
        for j in range(substeps):
            yn = _rk4(yn, kn, h, b, m)
            if j < substeps - 1:
                kn = RESTITUTION_FIELD(0.0, yn, (b, m))
        kn, fn, inside = _sample(yn, b, m)
        too_close = yn[0] >= singular
        broken = ~(jnp.all(jnp.isfinite(yn)) & jnp.isfinite(fn)) | too_close
        singular_hit = singular_hit | (going & too_close)
        bad = bad | (going & broken)
        ended = ended | (going & ~broken & ~inside)
        going = ~(ended | bad)
        carry = (
            jnp.where(going, yn, y),
            jnp.where(going, kn, k1),
            jnp.where(going, fn, force),
            going,
            ended,
            bad,
            singular_hit,
            i + 1,
        )
        return carry, record

    k0, f0, _ = _sample(y0, ball, model)
    false = jnp.asarray(False)
    start = (y0, k0, f0, jnp.asarray(True), false, false, false, jnp.asarray(0))
    # the step after the last sample records nothing; it tells whether the contact outlasts them
    (_, _, _, _, ended, bad, singular_hit, _), records = jax.lax.scan(
        step, start, None, length=num_samples
    )
    d, v, f = records[:, 0], records[:, 1], records[:, 2]
    inside = (jnp.arange(num_samples) == 0) | (d > 0.0)

    d_max = _max_deflection(d, v, inside, 1.0 / rate_Hz)
    still_going = ~(ended | bad)
    singular_hit = singular_hit | (d_max >= singular * (1.0 - 1e-9))
    status = jnp.select(
        [
            still_going,
            singular_hit,
            bad | ~jnp.isfinite(d_max),
            d_max > model.max_deflection_ratio * ball.wall_m,
        ],
        [
            STATUS_CODES["step_limit"],
            STATUS_CODES["mass_singularity"],
            STATUS_CODES["solver_failed"],
            STATUS_CODES["deflection_limit"],
        ],
        STATUS_CODES["ok"],
    ).astype(jnp.int32)
    failed = status != 0
    return (
        nan_where(failed, d),
        nan_where(failed, v),
        nan_where(failed, f),
        inside & ~failed,
        status,
    )


def _count(name: str, value) -> int:
    try:
        n = operator.index(value)
    except TypeError:
        raise ValueError(f"{name}={value!r} must be an integer ≥ 1") from None
    if n < 1:
        raise ValueError(f"{name}={n!r} is outside the valid range [1, inf)")
    return n


def sampled_history_unsupported(model: Model) -> str | None:
    """Why ``sampled_history`` cannot solve ``model``; None if it can (rigid floor, no ball
    mode)."""
    return model.coupling


def substeps_for_contact(contact_time_s, rate_Hz: float) -> int:
    """Sub-steps per sample that give the shortest finite contact of ``contact_time_s`` at least
    ``MIN_STEPS_PER_CONTACT`` steps (1 where none is finite)."""
    tc = np.asarray(contact_time_s, dtype=float)
    finite = tc[np.isfinite(tc) & (tc > 0.0)]
    if finite.size == 0:
        return DEFAULT_SUBSTEPS
    return max(
        DEFAULT_SUBSTEPS, math.ceil(MIN_STEPS_PER_CONTACT / (float(np.min(finite)) * rate_Hz))
    )


@eqx.filter_jit
def _sampled_program(height_m, ball, model, rate_Hz, num_samples: int, substeps: int):
    """Broadcast, the solve vmapped over the batch and the reshape as ONE compiled program (one
    dispatch): one per batch shape, ``num_samples``, ``substeps`` and model structure."""
    shape, height, ball, model = broadcast_inputs(height_m, ball, model)
    solve = jax.vmap(lambda h, b, m: sampled_impact(h, b, m, rate_Hz, num_samples, substeps))
    out = jax.tree_util.tree_map(
        lambda x: x.reshape(shape + x.shape[1:]), solve(height, ball, model)
    )
    return jnp.arange(num_samples) / rate_Hz, out


def sampled_solve(
    height_m, ball: Ball, model: Model, rate_Hz, num_samples: int, substeps: int
) -> Trajectory:
    """``sampled_history`` after its checks, with ``time_s`` the 1-D sample grid (not repeated
    per impact)."""
    height, ball, model, rate = as_arrays((height_m, ball, model, rate_Hz))
    times, (d, v, f, inside, status) = _sampled_program(
        height, ball, model, rate, num_samples, substeps
    )
    return Trajectory(
        time_s=times,
        deflection_m=d,
        velocity_m_per_s=v,
        force_N=f,
        in_contact=inside,
        status=status,
    )


@eqx.filter_jit
def pad_record(traj: Trajectory, num_samples: int, rate_Hz: float) -> Trajectory:
    """The record of ``num_samples`` samples at ``rate_Hz``: the history's samples, then zeros
    (``in_contact`` False); a failed impact stays NaN over the whole record, padding included.
    One compiled program, so that each padded field is written once (the records are large:
    44 100 samples a second)."""
    pad = num_samples - traj.force_N.shape[-1]
    failed = (traj.status != 0)[..., None]

    def padded(x):
        return nan_where(failed, jnp.pad(x, [(0, 0)] * (x.ndim - 1) + [(0, pad)]))

    return Trajectory(
        time_s=jnp.arange(num_samples) / rate_Hz,
        deflection_m=padded(traj.deflection_m),
        velocity_m_per_s=padded(traj.velocity_m_per_s),
        force_N=padded(traj.force_N),
        in_contact=jnp.pad(traj.in_contact, [(0, 0)] * (traj.in_contact.ndim - 1) + [(0, pad)]),
        status=traj.status,
    )


def sampled_history(
    height_m: ArrayLike,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    *,
    num_samples: int,
    rate_Hz: ArrayLike = PAPER_RATE_Hz,
    substeps: int = DEFAULT_SUBSTEPS,
) -> Trajectory:
    """State and floor force at the samples k/``rate_Hz``, k = 0 … ``num_samples`` − 1, from
    first contact, integrated by fixed fourth-order Runge–Kutta steps (``substeps`` per sample)
    and recorded inside the loop (see the module docstring). Rigid-floor models only.

    ``height_m`` and the ball's and model's fields broadcast to one batch (the outputs have its
    shape plus the sample axis, ``time_s`` included). Samples after the end of contact are 0; an
    impact whose contact goes on after the last sample has status ``step_limit`` (ask for more
    samples). Works under ``jax.jit``, ``jax.vmap`` and ``jax.jacfwd`` (``num_samples`` and
    ``substeps`` static). One step per sample is ~1e-10 of the peak force for contacts of ~900
    samples (the JIS ball at 44.1 kHz); the error grows as (samples per contact)⁻⁴, so give
    ``substeps`` for contacts of a few hundred samples or less (``substeps_for_contact``).
    """
    model = Model() if model is None else model
    if not isinstance(model, Model):
        raise ValueError(f"model={model!r} must be an rbjax.Model")
    reason = sampled_history_unsupported(model)
    if reason is not None:
        raise ValueError(
            f"sampled_history cannot solve this model: {reason}; use rbjax.trajectory (the ODE)"
        )
    check_inputs(height_m, ball)
    num_samples = _count("num_samples", num_samples)
    substeps = _count("substeps", substeps)
    check_range("rate_Hz", rate_Hz, lower=0.0)
    traj = sampled_solve(height_m, ball, model, rate_Hz, num_samples, substeps)
    return eqx.tree_at(lambda t: t.time_s, traj, jnp.broadcast_to(traj.time_s, traj.force_N.shape))

"""Force histories of the elastic model by quadrature: t(δ) inverted on nested Gauss rules.

The scalar outputs (contact time, peak force, restitution) come from :mod:`rbjax.solve.quadrature`;
this module samples the history at given times from the same integrals in δ (see that
module's docstring for the derivation), with its own nested Gauss–Legendre rules.

A reference implementation, kept for the tests (``tests/solve/test_quadrature.py``: the
histories against the ODE's) and the accuracy benchmark
(``benchmarks/accuracy.py --only work_precision``: the reference history): no path of
:func:`rbjax.simulate` or the fit calls it. It stays public as
``rbjax.solve.force_history_quadrature``.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp

from ..terms.ball import Ball
from ..terms.forces import reissner_stiffness_N_per_m
from ..terms.model import Model
from .outcome import SINGULAR_FRACTION, STATUS_CODES, Trajectory, impact_velocity_m_per_s
from .quadrature import RESIDUAL_TOLERANCE, check_quadrature, undamped_force
from .quadrature_rules import bernstein_decay, gauss_legendre_01

# --- force histories (force_history_quadrature) -------------------------------------------------
#: Gauss–Legendre points of the nested rules of the history path.
HISTORY_NODES = 32
#: Newton steps for δ_max in the history path. The start lies right of the root and u_c is
#: concave and decreasing there (F > 0 increasing), so the iterates fall monotonically.
NEWTON_STEPS = 12
#: Newton steps on σ when inverting t(δ) for the force history (from a linear-oscillator guess).
HISTORY_NEWTON_STEPS = 4
#: Largest accepted ``rule_error_estimate`` of the history path's nested rule.
HISTORY_RULE_TOLERANCE = 1e-9


def _compression_residual(d, v0, ball, model, x, w):
    """u_c(δ) = v0² − (4R/M) ∫₀^δ F(s)/(2R − s) ds on an n-point rule."""
    two_r = 2.0 * ball.radius_m
    s = d * x
    integral = d * jnp.sum(w * undamped_force(s, ball, model) / (two_r - s))
    return v0**2 - 4.0 * ball.radius_m / ball.mass_kg * integral


def _compression_slope(d, ball, model):
    """du_c/dδ = −(4R/M) F(δ)/(2R − δ)."""
    return (
        -4.0
        * ball.radius_m
        / ball.mass_kg
        * undamped_force(d, ball, model)
        / (2.0 * ball.radius_m - d)
    )


def _max_deflection(v0, ball, model, x, w, d_limit):
    """δ_max, the root of u_c, by NEWTON_STEPS Newton steps and one differentiable step.

    The start min(v0√(M/k), d_limit) lies right of the root: F(s)/(2R − s) ≥ ks/2R gives
    u_c(v0√(M/k)) ≤ 0, and the caller flags roots beyond d_limit. The iterations run on
    stop-gradient copies; the last step, at the converged root, carries the derivatives
    dδ_max/dθ = −(∂u_c/∂θ)/(∂u_c/∂δ) (implicit-function theorem).
    """
    v0_c, ball_c, model_c = jax.lax.stop_gradient((v0, ball, model))
    k = reissner_stiffness_N_per_m(ball_c)
    start = jnp.minimum(v0_c * jnp.sqrt(ball_c.mass_kg / k), jax.lax.stop_gradient(d_limit))

    def step(_, d):
        return d - _compression_residual(d, v0_c, ball_c, model_c, x, w) / _compression_slope(
            d, ball_c, model_c
        )

    d = jax.lax.stop_gradient(jax.lax.fori_loop(0, NEWTON_STEPS, step, start))
    slope = jax.lax.stop_gradient(_compression_slope(d, ball_c, model_c))
    return d - _compression_residual(d, v0, ball, model, x, w) / slope


def _phase_weights(sigma, d_max, ball, model, x, w):
    """W_c(σ) and W_r(σ) (see the module docstring) at the points ``sigma`` (inner n-point rule)."""
    two_r = 2.0 * ball.radius_m
    s = d_max * (1.0 - sigma[..., None] ** 2 * x)
    f = undamped_force(s, ball, model)
    scale = 4.0 * ball.radius_m * d_max / ball.mass_kg
    return scale * jnp.sum(w * f / (two_r - s), axis=-1), scale * jnp.sum(
        w * f * (two_r - s), axis=-1
    )


def _time_rates(sigma, d_max, ball, model, x, w):
    """dt/dσ of the compression and restitution phases: 2δ_max/√W_c and 2δ_max(2R − δ)/√W_r."""
    w_c, w_r = _phase_weights(sigma, d_max, ball, model, x, w)
    gap = 2.0 * ball.radius_m - d_max * (1.0 - sigma**2)
    return 2.0 * d_max / jnp.sqrt(w_c), 2.0 * d_max * gap / jnp.sqrt(w_r)


def rule_error_estimate(d_max, two_r, n_nodes: int):
    """Bound-like estimate ρ^(−2n) of an n-point Gauss–Legendre rule's relative error here.

    The integrands carry 1/(2R − s) (Eq. 6's dynamic mass), a pole at s = 2R just outside the
    interval [0, δ_max]. For a function analytic inside the Bernstein ellipse through that pole
    the rule's error falls as ρ^(−2n), ρ = a + √(a² − 1), a = 2(2R/δ_max) − 1 (the pole's place on
    [−1, 1]'s axis). Near the mass singularity ρ → 1 and no fixed rule converges: at
    δ_max = 0.998·2R, 32 nodes miss the contact time by 6e-4 (estimate 3e-3), 128 by 1e-10.
    """
    return bernstein_decay(2.0 * two_r / jnp.maximum(d_max, 1e-300) - 1.0, n_nodes)


class _Solution(eqx.Module):
    v0: jax.Array
    d_max: jax.Array
    t_compression: jax.Array
    t_restitution: jax.Array
    v_out: jax.Array
    status: jax.Array


def _solve(height_m, ball, model, n_nodes) -> _Solution:
    x, w = (jnp.asarray(a) for a in gauss_legendre_01(n_nodes))
    height = jnp.asarray(height_m, dtype=jnp.float64)
    v0 = impact_velocity_m_per_s(height)
    two_r = 2.0 * ball.radius_m
    d_singular = SINGULAR_FRACTION * two_r
    d_limit = jnp.minimum(model.max_deflection_ratio * ball.wall_m, d_singular)

    # u_c is decreasing: a positive u_c at a bound means δ_max lies beyond it.
    singular = _compression_residual(d_singular, v0, ball, model, x, w) > 0.0
    too_deep = _compression_residual(d_limit, v0, ball, model, x, w) > 0.0
    d_max = _max_deflection(v0, ball, model, x, w, d_limit)
    converged = (
        jnp.abs(_compression_residual(d_max, v0, ball, model, x, w)) <= RESIDUAL_TOLERANCE * v0**2
    )

    rate_c, rate_r = _time_rates(x, d_max, ball, model, x, w)
    t_compression = jnp.sum(w * rate_c)
    t_restitution = jnp.sum(w * rate_r)
    s = d_max * x
    v_out = jnp.sqrt(
        d_max
        * jnp.sum(w * undamped_force(s, ball, model) * (two_r - s))
        / (ball.mass_kg * ball.radius_m)
    )

    finite = jnp.all(jnp.isfinite(jnp.stack([d_max, t_compression, t_restitution, v_out])))
    status = jnp.select(
        [
            singular,
            too_deep,
            ~(converged & finite)
            | (rule_error_estimate(d_max, two_r, n_nodes) > HISTORY_RULE_TOLERANCE),
        ],
        [
            STATUS_CODES["mass_singularity"],
            STATUS_CODES["deflection_limit"],
            STATUS_CODES["solver_failed"],
        ],
        STATUS_CODES["ok"],
    ).astype(jnp.int32)
    return _Solution(v0, d_max, t_compression, t_restitution, v_out, status)


def force_history_quadrature(
    height_m, ball: Ball, model: Model, times_s, *, n_nodes: int = HISTORY_NODES
) -> Trajectory:
    """Deflection, velocity and floor force of ONE elastic impact at the given times (0 after
    contact).

    t(δ) is inverted on each phase in the variable σ of δ = δ_max(1 − σ²), where the time from
    maximum compression, τ(σ) = ∫₀^σ (dt/dσ′) dσ′ (n-point rule on [0, σ], each node nested), is
    smooth with dτ/dσ = 2δ_max/√W_c (compression) or 2δ_max(2R − δ)/√W_r (restitution) bounded and
    positive: HISTORY_NEWTON_STEPS Newton steps from the linear-oscillator guess
    σ = √2 sin(π/4 · (fraction of the phase still to go)), then one differentiable step.
    δ̇ = σ√W_c in compression and −σ√W_r/(2R − δ) in restitution; the floor force is F(δ)
    (Eq. 7), plus (M/2R)δ̇² during compression for ``blocked_force="momentum"``.
    ``times_s`` is a 1-D array. Outputs are NaN where the impact's status is not 0. Cost:
    (HISTORY_NEWTON_STEPS + 1)·n(n + 1) + n + 1 force evaluations per sample.
    """
    check_quadrature(height_m, ball, model, n_nodes)
    times = jnp.asarray(times_s, dtype=jnp.float64)
    if times.ndim != 1:
        raise ValueError(f"times_s has shape {times.shape}; valid: a 1-D array of times")
    x, w = (jnp.asarray(a) for a in gauss_legendre_01(n_nodes))
    sol = _solve(height_m, ball, model, n_nodes)
    d_max, t_c, t_r = sol.d_max, sol.t_compression, sol.t_restitution
    compressing = times <= t_c
    # Time still to go to maximum compression, or already spent since it, clipped to the phase.
    target = jnp.where(
        compressing, jnp.clip(t_c - times, 0.0, t_c), jnp.clip(times - t_c, 0.0, t_r)
    )
    length = jnp.where(compressing, t_c, t_r)

    def rate(sigma, d_max, ball, model, phase=compressing):
        rate_c, rate_r = _time_rates(sigma, d_max, ball, model, x, w)
        return jnp.where(phase, rate_c, rate_r)

    def tau(sigma, d_max, ball, model):  # ∫₀^σ rate: the n-point rule at σ·x for every sample
        return sigma * jnp.sum(
            w * rate(sigma[:, None] * x, d_max, ball, model, compressing[:, None]), axis=-1
        )

    consts = jax.lax.stop_gradient((d_max, ball, model))
    target_c = jax.lax.stop_gradient(target)

    def step(_, sigma):
        sigma = sigma - (tau(sigma, *consts) - target_c) / rate(sigma, *consts)
        return jnp.clip(sigma, 0.0, 1.0)

    start = jnp.sqrt(2.0) * jnp.sin(0.25 * jnp.pi * target_c / jax.lax.stop_gradient(length))
    sigma = jax.lax.stop_gradient(jax.lax.fori_loop(0, HISTORY_NEWTON_STEPS, step, start))
    sigma = sigma - (tau(sigma, d_max, ball, model) - target) / jax.lax.stop_gradient(
        rate(sigma, *consts)
    )

    deflection = d_max * (1.0 - sigma**2)
    w_c, w_r = _phase_weights(sigma, d_max, ball, model, x, w)
    velocity = jnp.where(
        compressing,
        sigma * jnp.sqrt(w_c),
        -sigma * jnp.sqrt(w_r) / (2.0 * ball.radius_m - deflection),
    )
    force = undamped_force(deflection, ball, model)
    force = force + model.momentum_flux_weight * jnp.where(
        compressing, ball.mass_kg / (2.0 * ball.radius_m) * sigma**2 * w_c, 0.0
    )

    inside = (times >= 0.0) & (times < t_c + t_r)
    ok = sol.status == 0

    def out(a):
        return jnp.where(ok, jnp.where(inside, a, 0.0), jnp.nan)

    return Trajectory(
        time_s=times,
        deflection_m=out(deflection),
        velocity_m_per_s=out(velocity),
        force_N=out(force),
        in_contact=inside & ok,
        status=sol.status,
    )

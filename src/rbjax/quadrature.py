"""A fast, loop-free path for the elastic model: the impact as quadratures in δ.

For a contact force F(δ) of the deflection alone (the paper's elastic model: shell force F_B,
Eqs. 1–3, with optional ``CubicStiffening``, plus the gas force F_G, Eq. 4, when
``gas="adiabatic"``; no damping) the equation of motion (paper Eq. 7)

    M(1 − δ/2R) δ̈ − (M/2R) δ̇² H(−δ̇) = −F(δ),   δ(0) = 0,  δ̇(0) = v0 = √(2 g h_D) (Eq. 10)

is integrated in δ instead of t. With u = δ̇² and δ̈ = ½ du/dδ
(the energy balance of Eq. 7):

* compression (δ̇ > 0, no flux term): u_c(δ) = v0² − (4R/M) ∫₀^δ F(s)/(2R − s) ds, and the
  maximum deflection δ_max is the root of u_c;
* restitution (δ̇ < 0, flux term on; linear in u with integrating factor (2R − δ)²):
  (2R − δ)² u_r(δ) = (4R/M) ∫_δ^δmax F(s)(2R − s) ds, so v_out² = u_r(0) and the
  restitution coefficient is v_out / v0 (contact ends at δ = 0, where M − M_c = M);
* times t = ∫ dδ/√u. With δ = δ_max(1 − σ²) and s = δ_max(1 − σ² τ) inside the integrals,
  u_c = σ² W_c(σ) and (2R − δ)² u_r = σ² W_r(σ), with

      W_c(σ) = (4R δ_max/M) ∫₀¹ F(s)/(2R − s) dτ,   W_r(σ) = (4R δ_max/M) ∫₀¹ F(s)(2R − s) dτ,

  so the inverse-square-root singularity at δ_max cancels analytically:

      t_compression = ∫₀¹ 2δ_max / √W_c(σ) dσ,   t_restitution = ∫₀¹ 2δ_max (2R − δ) / √W_r(σ) dσ.

  Every integrand is analytic on its interval, so Gauss–Legendre rules converge
  exponentially; W_c and W_r at the outer nodes use an inner rule (nested, n² force
  evaluations, a fixed cost).

δ_max comes from a fixed number of Newton steps on u_c (no while loop, so the path works under
``jax.jit``, ``vmap``, ``grad`` and ``jacfwd``); derivatives go through one extra Newton step
on the converged root (the implicit-function theorem), not through the iterations.
Damped models (force depending on δ̇ or on an internal state) do not separate and need the ODE.
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._validate import check_range
from ._x64 import require_x64
from .ball import Ball
from .forces import contact_force_N, reissner_stiffness_N_per_m
from .impact import (
    SINGULAR_FRACTION,
    STATUS_CODES,
    ImpactScalars,
    Trajectory,
    impact_velocity_m_per_s,
)
from .model import Model

#: Newton steps for δ_max. The start lies right of the root and u_c is concave and decreasing
#: there (F > 0 increasing), so the iterates fall monotonically; 12 steps leave round-off only.
NEWTON_STEPS = 12
#: Newton steps on σ when inverting t(δ) for the force history (from a linear-oscillator guess).
HISTORY_NEWTON_STEPS = 4
#: Largest accepted |u_c(δ_max)| / v0² after the Newton steps (else status ``solver_failed``).
RESIDUAL_TOLERANCE = 1e-9
DEFAULT_NODES = 32
#: Largest accepted ``rule_error_estimate`` (else status ``solver_failed``: use more nodes or the
#: ODE path). It flags δ_max > 0.975·2R at 32 nodes, > 0.66·2R at 6.
RULE_TOLERANCE = 1e-9


@functools.cache
def gauss_legendre_01(n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [0, 1] (numpy's ``leggauss``, mapped)."""
    x, w = np.polynomial.legendre.leggauss(n_nodes)
    return 0.5 * (x + 1.0), 0.5 * w


gauss_legendre_01(DEFAULT_NODES)  # the default rule, computed at import time


def _check(height_m, ball, model, n_nodes) -> None:
    require_x64()
    check_range("height_m", height_m, lower=0.0)
    if not isinstance(ball, Ball):
        raise ValueError(f"ball={ball!r} must be an rbjax.Ball")
    if not isinstance(model, Model):
        raise ValueError(f"model={model!r} must be an rbjax.Model")
    if model.damping:
        raise ValueError(
            f"model.damping={model.damping!r}: the quadrature path needs a contact force F(δ) of the "
            "deflection alone; valid: damping=None (use rbjax.simulate for damped models)"
        )
    if not isinstance(n_nodes, (int, np.integer)) or isinstance(n_nodes, bool) or not 2 <= n_nodes <= 512:
        raise ValueError(f"n_nodes={n_nodes!r} must be an integer in the valid range [2, 512]")


def _force(d, ball, model):
    """F(δ) = F_B (+ stiffening) (+ F_G): the right-hand side of Eq. 7 without damping."""
    return contact_force_N(d, 0.0, jnp.zeros(0), ball, model)


def _compression_residual(d, v0, ball, model, x, w):
    """u_c(δ) = v0² − (4R/M) ∫₀^δ F(s)/(2R − s) ds on an n-point rule."""
    two_r = 2.0 * ball.radius_m
    s = d * x
    integral = d * jnp.sum(w * _force(s, ball, model) / (two_r - s))
    return v0**2 - 4.0 * ball.radius_m / ball.mass_kg * integral


def _compression_slope(d, ball, model):
    """du_c/dδ = −(4R/M) F(δ)/(2R − δ)."""
    return -4.0 * ball.radius_m / ball.mass_kg * _force(d, ball, model) / (2.0 * ball.radius_m - d)


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
        return d - _compression_residual(d, v0_c, ball_c, model_c, x, w) / _compression_slope(d, ball_c, model_c)

    d = jax.lax.stop_gradient(jax.lax.fori_loop(0, NEWTON_STEPS, step, start))
    slope = jax.lax.stop_gradient(_compression_slope(d, ball_c, model_c))
    return d - _compression_residual(d, v0, ball, model, x, w) / slope


def _phase_weights(sigma, d_max, ball, model, x, w):
    """W_c(σ) and W_r(σ) (see the module docstring) at the points ``sigma`` (inner n-point rule)."""
    two_r = 2.0 * ball.radius_m
    s = d_max * (1.0 - sigma[..., None] ** 2 * x)
    f = _force(s, ball, model)
    scale = 4.0 * ball.radius_m * d_max / ball.mass_kg
    return scale * jnp.sum(w * f / (two_r - s), axis=-1), scale * jnp.sum(w * f * (two_r - s), axis=-1)


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
    a = 2.0 * two_r / jnp.maximum(d_max, 1e-300) - 1.0
    rho = a + jnp.sqrt(jnp.maximum(a**2 - 1.0, 0.0))
    return jnp.exp(-2.0 * n_nodes * jnp.log(jnp.maximum(rho, 1.0 + 1e-16)))


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
    converged = jnp.abs(_compression_residual(d_max, v0, ball, model, x, w)) <= RESIDUAL_TOLERANCE * v0**2

    rate_c, rate_r = _time_rates(x, d_max, ball, model, x, w)
    t_compression = jnp.sum(w * rate_c)
    t_restitution = jnp.sum(w * rate_r)
    s = d_max * x
    v_out = jnp.sqrt(d_max * jnp.sum(w * _force(s, ball, model) * (two_r - s)) / (ball.mass_kg * ball.radius_m))

    finite = jnp.all(jnp.isfinite(jnp.stack([d_max, t_compression, t_restitution, v_out])))
    status = jnp.select(
        [singular, too_deep, ~(converged & finite) | (rule_error_estimate(d_max, two_r, n_nodes) > RULE_TOLERANCE)],
        [STATUS_CODES["mass_singularity"], STATUS_CODES["deflection_limit"], STATUS_CODES["solver_failed"]],
        STATUS_CODES["ok"],
    ).astype(jnp.int32)
    return _Solution(v0, d_max, t_compression, t_restitution, v_out, status)


def _num_force_evaluations(n: int) -> int:
    """Force evaluations of one impact: Newton (n + 1 per step, and the differentiable step),
    the two bound checks, the residual check, the nested time rule, v_out and the peak."""
    return (NEWTON_STEPS + 1) * (n + 1) + 2 * n + n + n * n + n + 1


def impact_quadrature(height_m, ball: Ball, model: Model, *, n_nodes: int = DEFAULT_NODES) -> ImpactScalars:
    """Scalar outputs of ONE elastic impact by quadrature (same fields and status codes as the ODE).

    Args:
        height_m: drop height h_D > 0 (Eq. 10).
        ball: an ``rbjax.Ball``.
        model: an ``rbjax.Model`` with ``damping=None`` (else ``ValueError``: F must depend on δ
            alone); gas, stiffening, blocked force and max_deflection_ratio are honoured.
        n_nodes: points of every Gauss–Legendre rule (the time rule is nested: n² evaluations).

    Returns:
        ``ImpactScalars``; where ``status != 0`` the outputs are NaN: 2 ``mass_singularity`` (δ_max
        beyond 0.999·2R), 3 ``deflection_limit`` (δ_max > max_deflection_ratio·h), 4
        ``solver_failed`` (Newton residual above RESIDUAL_TOLERANCE, a non-finite output, or
        δ_max so close to 2R that the n-node rule is not accurate: ``rule_error_estimate``
        above RULE_TOLERANCE).
        ``num_steps`` is the number of force evaluations.

    Peak force: with ``blocked_force="paper"`` the floor force F(δ) increases with δ, so its peak
    is F(δ_max) at the end of compression (§2.4). With ``"momentum"`` the compression floor force
    is F(δ) + (M/2R)u_c(δ); at δ_max the flux term vanishes (δ̇ = 0) and, as
    d/dδ[F + (M/2R)u_c] = F′(δ) − 2F(δ)/(2R − δ), it is largest there while F′(2R − δ) ≥ 2F on
    [0, δ_max]. That holds over the valid range δ ≤ 2h of the JIS ball with the gas force or with
    stiffening; for the bare linear shell it needs δ_max ≤ 2R/3 (59 mm for the JIS ball), beyond
    which the true maximum lies slightly before δ_max. As in the ODE path (``impact.py``) the
    reported peak is max(F(δ_max), floor force at first contact (M/2R)v0²), and the peak time is
    the compression time (or 0 if the first-contact value is larger).
    """
    _check(height_m, ball, model, n_nodes)
    sol = _solve(height_m, ball, model, n_nodes)
    peak = _force(sol.d_max, ball, model)
    first = model.momentum_flux_weight * ball.mass_kg / (2.0 * ball.radius_m) * sol.v0**2
    ok = sol.status == 0
    nan = jnp.nan
    return ImpactScalars(
        contact_time_s=jnp.where(ok, sol.t_compression + sol.t_restitution, nan),
        peak_force_N=jnp.where(ok, jnp.maximum(peak, first), nan),
        peak_time_s=jnp.where(ok, jnp.where(peak >= first, sol.t_compression, 0.0), nan),
        restitution=jnp.where(ok, sol.v_out / sol.v0, nan),
        max_deflection_m=jnp.where(ok, sol.d_max, nan),
        max_compression_time_s=jnp.where(ok, sol.t_compression, nan),
        status=sol.status,
        num_steps=jnp.asarray(_num_force_evaluations(n_nodes), dtype=jnp.int32),
    )


def _impact_positional(height_m, ball, model, n_nodes):
    return impact_quadrature(height_m, ball, model, n_nodes=n_nodes)


_batch = eqx.filter_jit(eqx.filter_vmap(_impact_positional, in_axes=(0, 0, 0, None)))


def impact_quadrature_batch(height_m, ball: Ball, model: Model, n_nodes: int = DEFAULT_NODES) -> ImpactScalars:
    """``impact_quadrature`` jitted and vmapped over a leading batch axis of height, ball and model
    array leaves (like ``impact.impact_batch``); model leaves given as scalars (e.g. the default
    ``momentum_flux_weight``) are broadcast to the batch."""
    n = jnp.shape(height_m)[0]
    model = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(jnp.asarray(x, dtype=jnp.float64), (n,) + jnp.shape(x)[1:]) if jnp.ndim(x) == 0 else x, model)
    return _batch(height_m, ball, model, n_nodes)


def force_history_quadrature(height_m, ball: Ball, model: Model, times_s, *, n_nodes: int = DEFAULT_NODES) -> Trajectory:
    """Deflection, velocity and floor force of ONE elastic impact at the given times (0 after contact).

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
    _check(height_m, ball, model, n_nodes)
    times = jnp.asarray(times_s, dtype=jnp.float64)
    if times.ndim != 1:
        raise ValueError(f"times_s has shape {times.shape}; valid: a 1-D array of times")
    x, w = (jnp.asarray(a) for a in gauss_legendre_01(n_nodes))
    sol = _solve(height_m, ball, model, n_nodes)
    d_max, t_c, t_r = sol.d_max, sol.t_compression, sol.t_restitution
    compressing = times <= t_c
    # Time still to go to maximum compression, or already spent since it, clipped to the phase.
    target = jnp.where(compressing, jnp.clip(t_c - times, 0.0, t_c), jnp.clip(times - t_c, 0.0, t_r))
    length = jnp.where(compressing, t_c, t_r)

    def rate(sigma, d_max, ball, model, phase=compressing):
        rate_c, rate_r = _time_rates(sigma, d_max, ball, model, x, w)
        return jnp.where(phase, rate_c, rate_r)

    def tau(sigma, d_max, ball, model):  # ∫₀^σ rate: the n-point rule at σ·x for every sample
        return sigma * jnp.sum(w * rate(sigma[:, None] * x, d_max, ball, model, compressing[:, None]), axis=-1)

    consts = jax.lax.stop_gradient((d_max, ball, model))
    target_c = jax.lax.stop_gradient(target)

    def step(_, sigma):
        sigma = sigma - (tau(sigma, *consts) - target_c) / rate(sigma, *consts)
        return jnp.clip(sigma, 0.0, 1.0)

    start = jnp.sqrt(2.0) * jnp.sin(0.25 * jnp.pi * target_c / jax.lax.stop_gradient(length))
    sigma = jax.lax.stop_gradient(jax.lax.fori_loop(0, HISTORY_NEWTON_STEPS, step, start))
    sigma = sigma - (tau(sigma, d_max, ball, model) - target) / jax.lax.stop_gradient(rate(sigma, *consts))

    deflection = d_max * (1.0 - sigma**2)
    w_c, w_r = _phase_weights(sigma, d_max, ball, model, x, w)
    velocity = jnp.where(compressing, sigma * jnp.sqrt(w_c), -sigma * jnp.sqrt(w_r) / (2.0 * ball.radius_m - deflection))
    force = _force(deflection, ball, model)
    force = force + model.momentum_flux_weight * jnp.where(compressing, ball.mass_kg / (2.0 * ball.radius_m) * sigma**2 * w_c, 0.0)

    inside = (times >= 0.0) & (times < t_c + t_r)
    ok = sol.status == 0

    def out(a):
        return jnp.where(ok, jnp.where(inside, a, 0.0), jnp.nan)

    return Trajectory(time_s=times, deflection_m=out(deflection), velocity_m_per_s=out(velocity), force_N=out(force), in_contact=inside & ok, status=sol.status)

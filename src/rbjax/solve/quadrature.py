"""A fast, loop-free path for the elastic model: the impact as integrals in δ.

For a contact force F(δ) of the deflection alone (the paper's elastic model: shell force F_B,
Eqs. 1–3, with optional ``CubicStiffening``, plus the gas force F_G, Eq. 4, when
``gas="adiabatic"``; no damping) the equation of motion (paper Eq. 7)

    M(1 − δ/2R) δ̈ − (M/2R) δ̇² H(−δ̇) = −F(δ),   δ(0) = 0,  δ̇(0) = v0 = √(2 g h_D) (Eq. 10)

is integrated in δ instead of t. With u = δ̇² and δ̈ = ½ du/dδ (the energy balance of Eq. 7):

* compression (δ̇ > 0, no flux term): u_c(δ) = (4R/M) [G(δ_max) − G(δ)] with
  G(δ) = ∫₀^δ g(s) ds, g = F(s)/(2R − s); the maximum deflection δ_max is the root of
  G(δ_max) = M v0²/(4R);
* restitution (δ̇ < 0, flux term on; linear in u with integrating factor (2R − δ)²):
  (2R − δ)² u_r(δ) = (4R/M) [H(δ_max) − H(δ)], H(δ) = ∫₀^δ F(s)(2R − s) ds, so
  v_out² = H(δ_max)/(MR) and the restitution coefficient is v_out / v0 (contact ends at δ = 0,
  where M − M_c = M);
* times t = ∫ dδ/√u. With δ = δ_max sin φ (φ from 0 to π/2) the inverse-square-root
  singularity at δ_max cancels analytically, and with ḡ(φ), r̄(φ) the averages of g and of
  F(2R − s) over [δ, δ_max]:

      t_compression = ∫₀^{π/2} √(δ_max (1 + sin φ) / ((4R/M) ḡ)) dφ,
      t_restitution = ∫₀^{π/2} (2R − δ) √(δ_max (1 + sin φ) / ((4R/M) r̄)) dφ.

  These integrands are analytic and nearly constant (exactly constant for a linear spring of
  constant mass); Gauss–Legendre rules in φ converge exponentially.

The scalar outputs (``impact_quadrature``) take n + 3 force evaluations and no loop over the
force: F is sampled at ``BRACKET_NODES`` Chebyshev–Lobatto points on [0, d0] (F(0) = 0 is not
evaluated), d0 an upper bound of δ_max in closed form, and the root of the interpolant's
antiderivative gives d1 ≈ δ_max (a few digits); F is sampled again at n points on [0, d1]. Every
quantity above is a linear functional of these n samples (integrals and sub-interval averages of
the degree-(n − 1) interpolant of g and of F(2R − s)), expanded in a short Taylor series in
ε = δ_max/d1 − 1, so one precomputed matrix product gives them all (the points and the matrices:
:mod:`rbjax.solve.quadrature_rules`); δ_max = d1(1 + ε) is the root of a polynomial in ε.
Accuracy: the interpolant's Chebyshev tail, the φ rule's analyticity ellipse and the Taylor
remainder give an error estimate; above ``RULE_TOLERANCE`` the impact is flagged
``solver_failed`` (more nodes, or the ODE, then; ``rbjax.simulate`` falls back to the ODE).

The force histories (:mod:`rbjax.solve.quadrature_history`) invert t(δ) with nested Gauss–Legendre
rules in σ, δ = δ_max(1 − σ²): W_c(σ) = (4R δ_max/M) ∫₀¹ g(s) dτ and
W_r(σ) = (4R δ_max/M) ∫₀¹ F(s)(2R − s) dτ, s = δ_max(1 − σ² τ), with dt/dσ = 2δ_max/√W_c and
2δ_max(2R − δ)/√W_r, δ_max from Newton steps on the same rule.

Root finding has a fixed number of steps (no while loop, so the path works under ``jax.jit``,
``vmap``, ``grad`` and ``jacfwd``); derivatives go through one extra Newton step on the
converged root (the implicit-function theorem), not through the iterations, and the sample
points are held fixed (stop-gradient) while the samples carry the derivatives.
Damped models (force depending on δ̇ or on an internal state) do not separate and need the ODE.
"""

from __future__ import annotations

import functools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._validate import check_range
from .._x64 import require_x64
from ..terms.ball import Ball
from ..terms.forces import (
    GAMMA_AIR,
    AMBIENT_PRESSURE_Pa,
    contact_force_N,
    reissner_stiffness_N_per_m,
)
from ..terms.model import Model
from .outcome import SINGULAR_FRACTION, STATUS_CODES, ImpactScalars, impact_velocity_m_per_s
from .quadrature_rules import (
    ROOT_TERMS,
    SUB_TERMS,
    TAIL_COEFFICIENTS,
    bernstein_decay,
    bracket_rules,
    legendre_tail,
    refine_rules,
    row_norms,
    time_nodes,
)

# --- scalar outputs (impact_quadrature) ---------------------------------------------------------
#: Chebyshev–Lobatto points of the interpolant on [0, δ_max] and Gauss–Legendre points of the
#: φ rule for the phase times (one n for both). 12 gives ≤ 1e-12 in every output of the JIS ball
#: over 0.1–1.6 m (tests/solve/test_simulate_method.py); with fewer the error estimate flags more.
DEFAULT_NODES = 12
#: Chebyshev–Lobatto points of the first, bracketing interpolant on [0, d0].
BRACKET_NODES = 5
#: Newton steps on the bracketing interpolant (from d0, right of the root).
BRACKET_NEWTON_STEPS = 4
#: Newton steps of the closed-form upper bound d0 (convex, from the right).
UPPER_BOUND_NEWTON_STEPS = 6
#: Newton steps on the refined root's polynomial in ε (then one differentiable step).
REFINE_NEWTON_STEPS = 2
#: Largest |ε| accepted (the bracketing root must be this close; else ``solver_failed``).
MAX_SHIFT = 1e-2
#: Largest accepted error estimate of the scalar path (else status ``solver_failed``).
RULE_TOLERANCE = 1e-9
#: Largest accepted |G(δ_max) − M v0²/4R| relative to M v0²/4R.
RESIDUAL_TOLERANCE = 1e-9


def check_quadrature(height_m, ball, model, n_nodes, lowest: int = 2, highest: int = 512) -> None:
    require_x64()
    check_range("height_m", height_m, lower=0.0)
    if not isinstance(ball, Ball):
        raise ValueError(f"ball={ball!r} must be an rbjax.Ball")
    if not isinstance(model, Model):
        raise ValueError(f"model={model!r} must be an rbjax.Model")
    if model.damping:
        raise ValueError(
            f"model.damping={model.damping!r}: the quadrature path needs a contact force F(δ) of "
            "the deflection alone; valid: damping=None (use rbjax.simulate for damped models)"
        )
    if (
        not isinstance(n_nodes, (int, np.integer))
        or isinstance(n_nodes, bool)
        or not lowest <= n_nodes <= highest
    ):
        raise ValueError(
            f"n_nodes={n_nodes!r} must be an integer in the valid range [{lowest}, {highest}]"
        )


def undamped_force(d, ball, model):
    """F(δ) = F_B (+ stiffening) (+ F_G): the right-hand side of Eq. 7 without damping."""
    return contact_force_N(d, 0.0, jnp.zeros(0), ball, model)


# ------------------------------------------------------------------------------------------------
# Scalar outputs: interpolants on Chebyshev–Lobatto points, one matrix product (the points and the
# matrices: quadrature_rules.py).


def _weighted_sum(weights, values):
    """Σ_i weights[i]·values[i] as a chain of additions: a reduction over a short axis becomes a
    slow library call on CPU, ~10× slower under jacfwd's batched tangents."""
    return functools.reduce(jnp.add, [weights[i] * values[i] for i in range(values.shape[0])])


def _clenshaw(coef, x):
    """Σ_k coef[k] T_k(x) (coefficients on the last axis)."""
    b1 = b2 = jnp.zeros_like(x)
    for k in range(coef.shape[-1] - 1, 0, -1):
        b1, b2 = 2.0 * x * b1 - b2 + coef[..., k], b1
    return x * b1 - b2 + coef[..., 0]


def _horner(coef, e):
    """Σ_q coef[q] e^q (coefficients on the first axis)."""
    acc = coef[-1]
    for c in coef[-2::-1]:
        acc = acc * e + c
    return acc


def _upper_bound(v0, ball, model, target):
    """d0 ≥ δ_max in closed form, the smaller of two lower bounds of G(δ) set equal to M v0²/4R.

    (1) g = F/(2R − s) ≥ ks/(2R − s) (the shell without stiffening or gas), whose integral is
    2Rk·(w − 1 + e^(−w)) with w = −ln(1 − δ/2R): solved for w by Newton steps from the right
    (the function is convex and increasing). (2) g ≥ ks(1 + β(s/h)²)/2R for the shell and, for
    the gas, (V0/V)^γ − 1 ≥ γ(V0/V − 1) ≥ γ(1 − V/V0) = γ s²(3R − s)/4R³ (Bernoulli), so
    F_G/(2R − s) = p_a π s ((V0/V)^γ − 1) ≥ p_a π γ s³ (3R − s)/4R³ with
    3R − s ≥ 3R − min(δ_lin, 2R): G(δ) ≥ a2 δ² + a4 δ⁴, a quadratic in δ².
    """
    r = ball.radius_m
    two_r = 2.0 * r
    k = reissner_stiffness_N_per_m(ball)
    c = target / (two_r * k)  # w − 1 + e^(−w) = c; w − 1 + e^(−w) ≥ w²/3 for w ≤ 1, ≥ w − 1 always
    w = jnp.where(c <= 1.0 / 3.0, jnp.sqrt(3.0 * c), 1.0 + c)
    for _ in range(UPPER_BOUND_NEWTON_STEPS):
        w = w - (w + jnp.expm1(-w) - c) / -jnp.expm1(-w)
    d_log = -two_r * jnp.expm1(-w)
    d_linear = v0 * jnp.sqrt(ball.mass_kg / k)
    a2 = k / (4.0 * r)
    a4 = jnp.zeros_like(a2)
    if model.gas == "adiabatic":
        a4 = a4 + AMBIENT_PRESSURE_Pa * math.pi * GAMMA_AIR * (
            3.0 * r - jnp.minimum(d_linear, two_r)
        ) / (16.0 * r**3)
    if model.stiffening is not None:
        a4 = a4 + k * model.stiffening.beta / (8.0 * r * ball.wall_m**2)
    squared = (
        2.0 * target / (a2 + jnp.sqrt(a2**2 + 4.0 * a4 * target))
    )  # the root of a4 y² + a2 y = target
    return jnp.minimum(jnp.sqrt(squared), d_log)


def _bracket(v0, ball, model, target, d_limit):
    """d1 ≈ δ_max from an interpolant of g on BRACKET_NODES points of [0, d0] (no derivatives)."""
    t, to_coef, to_anti = (jnp.asarray(a) for a in bracket_rules(BRACKET_NODES))
    d0 = jnp.minimum(_upper_bound(v0, ball, model, target), d_limit)
    s = d0 * t[1:]  # g(0) = 0: not evaluated
    g = jnp.concatenate([jnp.zeros(1), undamped_force(s, ball, model) / (2.0 * ball.radius_m - s)])
    coef, anti = g @ to_coef.T, g @ to_anti.T  # row-vector form: one GEMM under vmap

    def step(_, d):
        x = 2.0 * d / d0 - 1.0
        d_new = d - (d0 * _clenshaw(anti, x) - target) / _clenshaw(coef, x)
        return jnp.clip(d_new, 0.25 * d, d0)  # safeguards against a wiggling interpolant

    return jax.lax.fori_loop(0, BRACKET_NEWTON_STEPS, step, d0)


def _tail_estimate(tail):
    """The size of the first omitted Chebyshev coefficient, extrapolated geometrically from the
    last four kept ones (``tail``: c_{n−4} … c_{n−1}): the error of the interpolant's integrals."""
    last = jnp.abs(tail[-1]) + jnp.abs(tail[-2])
    before = jnp.abs(tail[-3]) + jnp.abs(tail[-4])
    return last * jnp.minimum(1.0, last / jnp.maximum(before, 1e-300))


def _phi_rule_error(d_max, two_r, n: int):
    """ρ^(−2n) for the n-point Gauss rule in φ on [0, π/2]: the integrands are analytic inside the
    ellipse through their nearest singularity, the pole s = 2R at φ = π/2 ± i·acosh(2R/δ_max), or on
    the left the turning point near δ = −δ_max (φ = −π/2) and the gas term's pole s = −R."""
    b = 4.0 / jnp.pi * jnp.arccosh(jnp.maximum(two_r / jnp.maximum(d_max, 1e-300), 1.0))
    alpha_right = 0.5 * (b + jnp.sqrt(4.0 + b**2))
    alpha_left = 1.0 + 4.0 / jnp.pi * jnp.arcsin(
        jnp.clip(0.5 * two_r / jnp.maximum(d_max, 1e-300), 0.0, 1.0)
    )
    return bernstein_decay(jnp.minimum(alpha_right, alpha_left), n)


class _Scalars(eqx.Module):
    v0: jax.Array
    d_max: jax.Array
    t_compression: jax.Array
    t_restitution: jax.Array
    v_out: jax.Array
    peak_force: jax.Array
    error_estimate: jax.Array
    status: jax.Array


def _solve_scalars(height_m, ball, model, n_nodes: int) -> _Scalars:
    t, sin_phi, w_phi, rows = (jnp.asarray(a) for a in refine_rules(n_nodes))
    m_phi = time_nodes(n_nodes)
    height = jnp.asarray(height_m, dtype=jnp.float64)
    v0 = impact_velocity_m_per_s(height)
    r, m = ball.radius_m, ball.mass_kg
    two_r = 2.0 * r
    target = m * v0**2 / (4.0 * r)  # G(δ_max)
    d_singular = SINGULAR_FRACTION * two_r
    d_limit = jnp.minimum(model.max_deflection_ratio * ball.wall_m, d_singular)

    consts = jax.lax.stop_gradient((v0, ball, model, target, d_limit))
    d1 = jax.lax.stop_gradient(_bracket(*consts))

    # n − 1 samples on (0, d1] (fixed points; the samples carry the derivatives)
    s = d1 * t
    f = undamped_force(s, ball, model)
    gap = two_r - s
    # every functional at once, (n,) @ (n, rows): a row vector on the left keeps the batch a free
    # dimension under vmap (one GEMM, ~5× faster than rows @ samples); two products, not one of
    # the stacked samples: XLA would fuse F into the stack and evaluate it (its pow) twice
    z_g, z_r = (f / gap) @ rows.T, (f * gap) @ rows.T
    k_root, k_sub = ROOT_TERMS, SUB_TERMS
    sub_g = z_g[k_root + 1 : k_root + 1 + k_sub * m_phi].reshape(k_sub, m_phi)
    sub_r = z_r[k_root + 1 : k_root + 1 + k_sub * m_phi].reshape(k_sub, m_phi)
    orders = jnp.arange(1, k_root + 1, dtype=z_g.dtype)

    def antiderivative(e, z):  # d1·∫₀^{1+ε} p(t) dt
        return d1 * (z[0] + e * _horner(z[1 : k_root + 1] / orders, e))

    def slope(e, z):  # d/dε of the above: d1·p(1 + ε)
        return d1 * _horner(z[1 : k_root + 1], e)

    z_c = jax.lax.stop_gradient(z_g)

    def step(_, e):
        return e - (antiderivative(e, z_c) - consts[3]) / slope(e, z_c)

    e = jax.lax.stop_gradient(jax.lax.fori_loop(0, REFINE_NEWTON_STEPS, step, jnp.zeros_like(d1)))
    e = e - (antiderivative(e, z_g) - target) / slope(e, z_c)
    d_max = d1 * (1.0 + e)

    scale = jnp.sqrt(d_max * (1.0 + sin_phi) / (4.0 * r / m))
    rate_c = scale / jnp.sqrt(_horner(sub_g, e))  # dt/dφ with ḡ(φ_i)
    rate_r = (two_r - d_max * sin_phi) * scale / jnp.sqrt(_horner(sub_r, e))  # and r̄(φ_i)
    t_compression, t_restitution = _weighted_sum(w_phi, rate_c), _weighted_sum(w_phi, rate_r)
    v_out = jnp.sqrt(antiderivative(e, z_r) / (m * r))
    peak = _horner(z_g[1 : k_root + 1], e) * (two_r - d_max)  # F(δ_max) = g(δ_max)(2R − δ_max)

    residual = jnp.abs(antiderivative(e, z_c) - consts[3]) / consts[3]
    d_max_c = jax.lax.stop_gradient(d_max)
    # (elementwise maxima, not reductions over small stacked axes: those run ~10× slower on CPU)
    z_r_c = jax.lax.stop_gradient(z_r)
    tail_estimate = jnp.maximum(
        _tail_estimate(z_c[-TAIL_COEFFICIENTS:]) / jnp.abs(z_c[0]),
        _tail_estimate(z_r_c[-TAIL_COEFFICIENTS:]) / jnp.abs(z_r_c[0]),
    )
    # the Taylor remainders in ε, and round-off in the rows of the higher Taylor terms (large for
    # large n)
    e_c = jnp.abs(jax.lax.stop_gradient(e))
    shift_estimate = (e_c * d1 / jnp.maximum(consts[1].radius_m * 2.0 - d1, 1e-300)) ** k_sub
    shift_estimate = shift_estimate + np.finfo(np.float64).eps * _horner(
        jnp.asarray(row_norms(n_nodes)), e_c
    )
    # the φ rule: a priori from the nearest singularities, a posteriori from the integrands'
    # Legendre tail (the rule's error falls as the square of the interpolant's)
    legendre_rows = jnp.asarray(legendre_tail(m_phi)).T
    phi_estimate = _phi_rule_error(d_max_c, jax.lax.stop_gradient(two_r), m_phi)
    for rate in (rate_c, rate_r):
        a = jax.lax.stop_gradient(rate) @ legendre_rows
        phi_estimate = jnp.maximum(
            phi_estimate, ((jnp.abs(a[1]) + jnp.abs(a[2])) / jnp.abs(a[0])) ** 2
        )
    error = jnp.maximum(jnp.maximum(tail_estimate, shift_estimate), phi_estimate)

    # δ_max beyond the deflection bound: the root lies past d1 = d_limit (G(d_limit) < M v0²/4R)
    # or past d_limit; trusted only where the interpolant is accurate (else solver_failed).
    at_limit = d1 >= consts[4] * (1.0 - 1e-12)
    shift_ok = jnp.abs(e) <= MAX_SHIFT
    beyond = (tail_estimate <= RULE_TOLERANCE) & (
        (at_limit & (z_c[0] * d1 < consts[3])) | (shift_ok & (d_max_c > consts[4]))
    )
    singular = beyond & (consts[4] >= jax.lax.stop_gradient(d_singular) * (1.0 - 1e-12))
    finite = functools.reduce(
        jnp.logical_and,
        [jnp.isfinite(x) for x in (d_max, t_compression, t_restitution, v_out, peak)],
    )
    failed = ~finite | (residual > RESIDUAL_TOLERANCE) | ~shift_ok | ~(error <= RULE_TOLERANCE)
    status = jnp.select(
        [singular, beyond, failed],
        [
            STATUS_CODES["mass_singularity"],
            STATUS_CODES["deflection_limit"],
            STATUS_CODES["solver_failed"],
        ],
        STATUS_CODES["ok"],
    ).astype(jnp.int32)
    return _Scalars(v0, d_max, t_compression, t_restitution, v_out, peak, error, status)


def _num_force_evaluations(n: int) -> int:
    """Force evaluations of one impact: the bracketing interpolant and the refined one (F(0) = 0
    is not evaluated); the peak force comes from the refined interpolant."""
    return BRACKET_NODES + n - 2


def quadrature_error_estimate(
    height_m, ball: Ball, model: Model, *, n_nodes: int = DEFAULT_NODES
) -> jax.Array:
    """The scalar path's error estimate for ONE impact (statuses ``ok`` need it ≤ RULE_TOLERANCE):
    the larger of the interpolants' Chebyshev tail (relative), the φ rule's ρ^(−2n) and the Taylor
    remainder in ε."""
    check_quadrature(height_m, ball, model, n_nodes, lowest=4, highest=128)
    return _solve_scalars(height_m, ball, model, n_nodes).error_estimate


# ------------------------------------------------------------------------------------------------
# The entry points: one impact, and a batch (the histories are in quadrature_history.py).


def impact_quadrature(
    height_m, ball: Ball, model: Model, *, n_nodes: int = DEFAULT_NODES
) -> ImpactScalars:
    """Scalar outputs of ONE elastic impact by quadrature (same fields and status codes as the ODE).

    Args:
        height_m: drop height h_D > 0 (Eq. 10).
        ball: an ``rbjax.Ball``.
        model: an ``rbjax.Model`` with ``damping=None`` (else ``ValueError``: F must depend on δ
            alone); gas, stiffening, blocked force and max_deflection_ratio are honoured.
        n_nodes: points of the interpolant on [0, δ_max] and of the φ rule (4–128).

    Returns:
        ``ImpactScalars``; where ``status != 0`` the outputs are NaN: 2 ``mass_singularity`` (δ_max
        beyond 0.999·2R where that is the deflection bound), 3 ``deflection_limit`` (δ_max >
        max_deflection_ratio·h; an impact beyond both bounds is reported here, where the ODE
        path reports ``mass_singularity``), 4 ``solver_failed`` (the error estimate
        ``quadrature_error_estimate`` above RULE_TOLERANCE, e.g. δ_max so close to 2R that n
        points do not resolve the pole of the dynamic mass; the bracketing root off by more than
        MAX_SHIFT; a residual above RESIDUAL_TOLERANCE; or a non-finite output).
        ``num_steps`` is the number of force evaluations.

    Peak force: with ``blocked_force="paper"`` the floor force F(δ) increases with δ, so its peak
    is F(δ_max) at the end of compression (§2.4). With ``"momentum"`` the compression floor force
    is F(δ) + (M/2R)u_c(δ); at δ_max the flux term vanishes (δ̇ = 0) and, as
    d/dδ[F + (M/2R)u_c] = F′(δ) − 2F(δ)/(2R − δ), it is largest there while F′(2R − δ) ≥ 2F on
    [0, δ_max]. That holds over the valid range δ ≤ 2h of the JIS ball with the gas force or with
    stiffening; for the bare linear shell it needs δ_max ≤ 2R/3 (59 mm for the JIS ball), beyond
    which the true maximum lies slightly before δ_max. As in the ODE path (``ode.py``) the
    reported peak is max(F(δ_max), floor force at first contact (M/2R)v0²), and the peak time is
    the compression time (or 0 if the first-contact value is larger).
    """
    check_quadrature(height_m, ball, model, n_nodes, lowest=4, highest=128)
    sol = _solve_scalars(height_m, ball, model, n_nodes)
    peak = sol.peak_force
    first = model.momentum_flux_weight * ball.mass_kg / (2.0 * ball.radius_m) * sol.v0**2
    return ImpactScalars.flagged(
        sol.status,
        _num_force_evaluations(n_nodes),
        contact_time_s=sol.t_compression + sol.t_restitution,
        peak_force_N=jnp.maximum(peak, first),
        peak_time_s=jnp.where(peak >= first, sol.t_compression, 0.0),
        restitution=sol.v_out / sol.v0,
        max_deflection_m=sol.d_max,
        max_compression_time_s=sol.t_compression,
    )


def _impact_positional(height_m, ball, model, n_nodes):
    return impact_quadrature(height_m, ball, model, n_nodes=n_nodes)


_batch = eqx.filter_jit(eqx.filter_vmap(_impact_positional, in_axes=(0, 0, 0, None)))


def impact_quadrature_batch(
    height_m, ball: Ball, model: Model, n_nodes: int = DEFAULT_NODES
) -> ImpactScalars:
    """``impact_quadrature`` jitted and vmapped over a leading batch axis of height, ball and model
    array leaves (like ``impact.impact_batch``); model leaves given as scalars (e.g. the default
    ``momentum_flux_weight``) are broadcast to the batch."""
    n = jnp.shape(height_m)[0]
    model = jax.tree_util.tree_map(
        lambda x: (
            jnp.broadcast_to(jnp.asarray(x, dtype=jnp.float64), (n,) + jnp.shape(x)[1:])
            if jnp.ndim(x) == 0
            else x
        ),
        model,
    )
    return _batch(height_m, ball, model, n_nodes)

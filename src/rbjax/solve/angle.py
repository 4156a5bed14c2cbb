"""The impact on the rigid floor integrated in the phase angle: fixed steps, no event search.

In the phase plane (δ, u = δ̇/ω₀), ω₀ = √(k/M) with k the shell's Reissner stiffness, the
contact is one half-turn around the origin. With polar coordinates

    δ = r sin φ,      δ̇ = ω₀ r cos φ,

first contact is φ = 0 (δ = 0, δ̇ = v₀ > 0, r = v₀/ω₀), maximum compression is φ = π/2 exactly
(δ̇ = 0) and the return of δ to 0 is φ = π exactly. Taking φ as the independent variable and
(r, t, z) as the unknowns (z: the damping laws' internal states), with a = −δ̈/ω₀² from Eq. 7,

    (M − M_c(δ)) δ̈ = −F(δ, δ̇, z) + (M/2R) δ̇² H(−δ̇),

the chain rule (φ̇ = (u δ̇ − δ u̇)/r² = ω₀ (u² + δ a)/r², ṙ = ω₀ u (δ − a)/r) gives

    dr/dφ = r u (δ − a) / D,   dt/dφ = r² / (ω₀ D),   dz/dφ = ż · dt/dφ,   D = u² + δ a.

For the linear shell a = δ and D = r²: r and t − φ/ω₀ are constant, and for every model of this
field the solution is a gently varying function of φ. So a fixed number of steps of an explicit
8th-order Runge–Kutta method (Dormand–Prince 8, diffrax's tableau) on [0, π/2] and on [π/2, π]
resolves it, in lockstep across a vmapped batch (no while loop, no lanes waiting for others),
and the phase ends need no root finder: the momentum flux switches on at a step boundary.
Valid while D > 0, i.e. the trajectory turns monotonically (checked at every node).

Events inside a phase (damped models: the peak of the floor force, where dF/dt = 0, and the
end of contact where the contact force returns to 0 before δ does) are bracketed by the signs
at the step ends and located on the continuous extension of the bracketing step (its 14 stages
computed once more; a quintic Hermite interpolant from the nodes alone was 1e-6 off: the steps
are long), by Newton's method with a bisection safeguard and one last unguarded Newton step (so
that derivatives of the event follow the implicit function theorem, not the bracket).

Accuracy is checked a posteriori: the embedded error estimate of every step, weighted
(r by r₀ = v₀/ω₀, t by 1/ω₀, internal states by k r₀), summed over the steps, must stay below
``ERROR_TOLERANCE``; otherwise, or where D ≤ 0 or a value is not finite, the impact is flagged
``solver_failed`` (``rbjax.simulate`` then solves it again with the diffrax ODE).
"""

from __future__ import annotations

import functools

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from diffrax._solver.dopri8 import _Dopri8Interpolation  # its table, not in diffrax's API

from .._x64 import require_x64
from ..terms.ball import Ball
from ..terms.forces import (
    contact_force_N,
    dynamic_mass_kg,
    internal_rates,
    momentum_flux_N,
    reissner_stiffness_N_per_m,
)
from ..terms.model import Model
from .outcome import SINGULAR_FRACTION, STATUS_CODES, ImpactScalars, impact_velocity_m_per_s
from .vector_field import floor_force_N

#: Steps of the 8th-order method per quarter turn (compression, restitution).
DEFAULT_STEPS = 6
#: Largest accepted sum of weighted local error estimates (see the module docstring).
ERROR_TOLERANCE = 1e-6
#: Newton (with bisection safeguard) iterations bracketing an event on the step's continuous
#: extension before the last, unguarded Newton step.
EVENT_ITERATIONS = 2
#: The end of contact is tested at φ = π − EDGE (δ ≈ r·EDGE > 0): whether the contact force is
#: still positive just before δ returns to 0.
EDGE = 1e-9


def angle_unsupported(model: Model) -> str | None:
    """Why the phase-angle path cannot solve ``model``; None if it can (rigid floor, no ball mode:
    the contact is a half-turn in (δ, δ̇) only when δ is the ball's rigid motion)."""
    return local_terms_unsupported(model) or model.coupling


def local_terms_unsupported(model: Model) -> str | None:
    """Why the fast paths (quadrature, phase angle) cannot solve a model with a contact layer
    or an arrest law (they are written for the shell's force and the share w of the paper's
    flux; the ODE and the sampled paths solve these terms); None without them."""
    names = [t.name for t in (model.layer, model.arrest) if t is not None]
    if not names:
        return None
    return (
        f"the {' and '.join(names)} term{'s' if len(names) > 1 else ''} run on the ODE and the "
        "sampled paths only"
    )


@functools.cache
def _tableau():
    """(c, A, b, b_error) of Dormand–Prince 8(7) as NumPy arrays (A strictly lower, s × s)."""
    tab = dfx.Dopri8.tableau
    s = len(tab.c) + 1
    a = np.zeros((s, s))
    for i, row in enumerate(tab.a_lower):
        a[i + 1, : len(row)] = row
    return np.concatenate([[0.0], tab.c]), a, np.asarray(tab.b_sol), np.asarray(tab.b_error)


class _Setup(eqx.Module):
    ball: Ball
    model: Model
    omega: jax.Array  # ω₀ (rad/s)
    r0: jax.Array  # v₀/ω₀ (m)
    stiffness: jax.Array  # k (N/m)


# The state is the tuple (r, t, z) of separate arrays (z: the internal states, shape (n_z,)):
# under vmap each is a contiguous batch vector, ~1.7× faster than one packed state vector.


def _cartesian(phi, y, setup: _Setup):
    """(δ, δ̇, z) from φ and (r, t, z)."""
    r, _, z = y
    return r * jnp.sin(phi), setup.omega * r * jnp.cos(phi), z


def _rates(phi, y, setup: _Setup):
    """d(r, t, z)/dφ (module docstring). The momentum-flux thrust acts where δ̇ < 0, i.e. for
    φ > π/2: in compression cos φ ≥ 0 (cos(π/2) is +6e-17 in floating point) and it vanishes."""
    ball, model, omega = setup.ball, setup.model, setup.omega
    r = y[0]
    d, v, z = _cartesian(phi, y, setup)
    u = v / omega
    force = contact_force_N(d, v, z, ball, model)
    thrust = jnp.where(v < 0.0, momentum_flux_N(v, ball), 0.0)
    a = (force - thrust) / (dynamic_mass_kg(d, ball) * omega**2)
    denom = u * u + d * a
    dt = r * r / (omega * denom)
    return r * u * (d - a) / denom, dt, internal_rates(d, v, z, ball, model) * dt


def _combine(y, h, weights, stages):
    """y + h Σ_j w_j k_j, component by component (stages: a tuple of (s, ...) arrays)."""
    return jax.tree_util.tree_map(
        lambda y_, k_: y_ + h * jnp.tensordot(weights, k_, axes=1), y, stages
    )


def _stages(phi, y, fy, h, setup: _Setup):
    """The stages of one Dormand–Prince 8 step from (φ, y) with y′ = fy given (FSAL), as a tuple
    of (14, ...) arrays for the continuous extension. A loop over the stages, not an unrolled
    sequence: the vector field appears once more in the compiled program, not 13 times (compile
    time), at the price of multiplying A's zeros (used once per event only)."""
    c, a, _, _ = _tableau()
    c, a = jnp.asarray(c), jnp.asarray(a)
    stages = jax.tree_util.tree_map(
        lambda f: jnp.zeros((c.shape[0],) + f.shape, f.dtype).at[0].set(f), fy
    )

    def body(i, stages):
        rates = _rates(phi + c[i] * h, _combine(y, h, a[i], stages), setup)
        return jax.tree_util.tree_map(lambda k_, f_: k_.at[i].set(f_), stages, rates)

    return jax.lax.fori_loop(1, c.shape[0], body, stages)


def _step_unrolled(phi, y, fy, h, setup: _Setup):
    """One Dormand–Prince 8 step with its stages written out (a Python list, only A's nonzero
    entries): (y at the step's end, y′ there (the FSAL stage), the embedded error estimate).
    ~2× faster than the looped stages of ``_stages`` (no stage array streamed through memory
    at every stage), at the price of 13 copies of the vector field in the program: used for the
    main steps only."""
    c, a, b, b_err = _tableau()
    stages = [fy]
    for i in range(1, len(c)):
        incr = jax.tree_util.tree_map(
            lambda *ks: sum(a[i, j] * ks[j] for j in range(i) if a[i, j] != 0.0), *stages
        )
        stages.append(
            _rates(
                phi + c[i] * h, jax.tree_util.tree_map(lambda y_, d_: y_ + h * d_, y, incr), setup
            )
        )

    def combine(coefficients, y_):
        return jax.tree_util.tree_map(
            lambda y0, *ks: y0 + h * sum(cj * k_ for cj, k_ in zip(coefficients, ks) if cj != 0.0),
            y_,
            *stages,
        )

    zero = jax.tree_util.tree_map(jnp.zeros_like, y)
    return combine(b, y), stages[-1], combine(b_err, zero)


def _weights(setup: _Setup):
    """Error weights of (r, t, z): 1/r₀, ω₀, 1/(k r₀)."""
    return 1.0 / setup.r0, setup.omega, 1.0 / (setup.stiffness * setup.r0)


def _half_turn(y0, setup: _Setup, n_steps: int):
    """2·n_steps of Dormand–Prince 8 over [0, π] (n_steps per quarter turn, so that φ = π/2 is a
    node): the nodes y_k and y′_k (k = 0..2n, each a tuple of arrays with a leading node axis)
    and the summed weighted error estimate."""
    h = 0.5 * np.pi / n_steps
    weights = _weights(setup)

    def step(carry, k):
        y, fy, err = carry
        # the FSAL stage (c = 1, last row of A = b) is y′ at the step's end
        y_next, f_next, local = _step_unrolled(h * k, y, fy, h, setup)
        err = err + jnp.max(
            jnp.concatenate([jnp.abs(e).reshape(-1) * w for e, w in zip(local, weights)])
        )
        out = (y_next, f_next)
        return (*out, err), out

    f0 = _rates(0.0, y0, setup)
    (_, _, err), (ys, fs) = jax.lax.scan(
        step, (y0, f0, jnp.zeros(())), jnp.arange(2 * n_steps, dtype=jnp.float64)
    )
    first = lambda x0, xs: jnp.concatenate([x0[None], xs])  # noqa: E731
    return jax.tree_util.tree_map(first, y0, ys), jax.tree_util.tree_map(first, f0, fs), err


@functools.cache
def _dense_coefficients() -> np.ndarray:
    """Dormand–Prince 8's continuous extension (Hairer, Nørsett & Wanner; diffrax's table):
    y(φ₀ + s h) = y₀ + h Σ_j s·p_j(s) k_j with p_j the rows' polynomials (highest power first)."""
    return np.asarray(_Dopri8Interpolation.eval_coeffs)


def _node(tree, k):
    return jax.tree_util.tree_map(lambda x: x[k], tree)


def _first_fall(g):
    """Index k ≥ 1 of the first sign change g[k−1] > 0 ≥ g[k], and whether there is one."""
    falls = (g[:-1] > 0.0) & (g[1:] <= 0.0)
    return jnp.argmax(falls) + 1, jnp.any(falls)


def _locate(event, k, phis, ys, fs, g, setup: _Setup, s_end=1.0):
    """The root of ``event(curve, s)`` in step k (from node k−1, where it is g[k−1] > 0, to node
    k, where it is g[k] ≤ 0, evaluated at s_end of the step), with ``curve(s)`` = (φ, y) on the
    step's continuous extension (its stages computed again): (φ*, y*). Newton's method with a
    bisection safeguard, started from the secant, and one last unguarded Newton step so that
    derivatives of the event follow the implicit function theorem rather than the bracket."""
    pa = phis[k - 1]
    h = phis[k] - pa
    ya = _node(ys, k - 1)
    stages = _stages(pa, ya, _node(fs, k - 1), h, setup)
    coef = _dense_coefficients()

    def curve_of(pa, h, ya, stages):
        def curve(s):
            weights = coef[:, 0]
            for column in coef[:, 1:].T:  # Horner: no pow
                weights = weights * s + column
            weights = weights * s
            # term by term: under vmap a product over the short stage axis with per-lane weights
            # is a batched matrix–vector product, a slow library call on the CPU
            return pa + s * h, jax.tree_util.tree_map(
                lambda y_, k_: y_ + h * sum(weights[j] * k_[j] for j in range(coef.shape[0])),
                ya,
                stages,
            )

        return curve

    def newton(curve, s):
        value, slope = jax.jvp(lambda ss: event(curve, ss), (s,), (jnp.ones_like(s),))
        return value, s - value / slope

    curve = curve_of(pa, h, ya, stages)
    # the bracketing iterations carry no tangents (gradients come from the last Newton step)
    fixed = curve_of(*jax.lax.stop_gradient((pa, h, ya, stages)))
    g0, g1 = jax.lax.stop_gradient((g[k - 1], g[k]))
    guess = jnp.clip(g0 / (g0 - g1), 0.0, 1.0) * s_end

    def body(_, carry):
        lo, hi, s = carry
        value, proposal = newton(fixed, s)
        lo, hi = jnp.where(value > 0.0, s, lo), jnp.where(value > 0.0, hi, s)
        inside = (proposal >= lo) & (proposal <= hi)
        return lo, hi, jnp.where(inside, proposal, 0.5 * (lo + hi))

    _, _, s = jax.lax.fori_loop(
        0, EVENT_ITERATIONS, body, jax.lax.stop_gradient((jnp.zeros(()), jnp.asarray(s_end), guess))
    )
    return curve(newton(curve, jax.lax.stop_gradient(s))[1])


def _start(height_m, ball: Ball, model: Model):
    """The setup and the state (r₀, 0, 0) at first contact."""
    k = reissner_stiffness_N_per_m(ball)
    omega = jnp.sqrt(k / ball.mass_kg)
    v0 = impact_velocity_m_per_s(height_m)
    setup = _Setup(ball, model, omega, v0 / omega, k)
    return v0, setup, (setup.r0, jnp.zeros_like(v0), jnp.zeros(model.num_internal_states))


def _solve(height_m, ball: Ball, model: Model, n_steps: int):
    """(v₀, setup, compression nodes (y, y′) on [0, π/2], restitution nodes on [π/2, π], error)."""
    v0, setup, y0 = _start(height_m, ball, model)
    ys, fs, err = _half_turn(y0, setup, n_steps)
    quarter = lambda tree, part: jax.tree_util.tree_map(lambda x: x[part], tree)  # noqa: E731
    first, second = slice(0, n_steps + 1), slice(n_steps, 2 * n_steps + 1)
    return (
        v0,
        setup,
        (quarter(ys, first), quarter(fs, first)),
        (quarter(ys, second), quarter(fs, second)),
        err,
    )


def impact_angle(
    height_m, ball: Ball, model: Model, *, n_steps: int = DEFAULT_STEPS
) -> ImpactScalars:
    """Scalar outputs of ONE impact on the rigid floor by the phase-angle integration.

    Same fields and status codes as the ODE path (``rbjax.solve.ode``); ``num_steps`` counts the
    fixed steps (2·``n_steps``). Any damping laws, gas, stiffening and blocked-force convention;
    not the ball mode or a moving floor (``angle_unsupported``).
    """
    require_x64()
    v0, setup, (ys1, fs1), (ys2, fs2), error = _solve(height_m, ball, model, n_steps)
    half = 0.5 * np.pi
    phis1 = jnp.linspace(0.0, half, n_steps + 1)
    phis2 = jnp.linspace(half, np.pi, n_steps + 1)

    def cartesian(phi, y):
        d, v, z = _cartesian(phi, y, setup)
        return jnp.concatenate([jnp.stack([d, v]), z])

    def floor_force(phi, y):
        return floor_force_N(cartesian(phi, y), ball, model)

    def contact(phi, y):
        d, v, z = _cartesian(phi, y, setup)
        return contact_force_N(d, v, z, ball, model) / (setup.stiffness * setup.r0)

    # maximum compression: the node at φ = π/2
    y_max = _node(ys1, -1)
    peak_phi, y_peak = jnp.asarray(half), y_max
    end_phi, y_end = jnp.asarray(np.pi), _node(ys2, -1)
    early = jnp.asarray(False)
    if model.velocity_dependent:
        # the force peak: dF/dφ falls through 0 in compression (else the peak is at π/2)
        def rate_on(curve, s):
            return jax.jvp(lambda ss: floor_force(*curve(ss)), (s,), (jnp.ones_like(s),))[1]

        g1 = jax.vmap(lambda p, y, f: jax.jvp(floor_force, (p, y), (jnp.ones_like(p), f))[1])(
            phis1, ys1, fs1
        )
        kp, found = _first_fall(g1)
        phi_p, y_p = _locate(rate_on, kp, phis1, ys1, fs1, g1, setup)
        peak_phi = jnp.where(found, phi_p, half)
        y_peak = jax.tree_util.tree_map(lambda a, b: jnp.where(found, a, b), y_p, y_max)

        # the end: the contact force returns to 0 before δ does (at the last node: whether it
        # is still positive at φ = π − EDGE, just before δ returns to 0)
        g2 = jax.vmap(contact)(phis2.at[-1].set(np.pi - EDGE), ys2)
        ke, ended = _first_fall(g2)
        s_end = jnp.where(ke == n_steps, 1.0 - EDGE / (phis2[1] - phis2[0]), 1.0)
        phi_e, y_e = _locate(
            lambda curve, s: contact(*curve(s)), ke, phis2, ys2, fs2, g2, setup, s_end=s_end
        )
        end_phi = jnp.where(ended, phi_e, np.pi)
        y_end = jax.tree_util.tree_map(lambda a, b: jnp.where(ended, a, b), y_e, y_end)
        early = g2[0] <= 0.0  # no contact force left at maximum compression: not this path's case

    t_max, d_max = y_max[1], y_max[0]
    d_end, v_end, _ = _cartesian(end_phi, y_end, setup)
    d_end = jnp.where(end_phi == np.pi, 0.0, d_end)  # sin(π) is 1.2e-16 in floating point
    peak = floor_force(peak_phi, y_peak)
    first = floor_force_N(
        jnp.concatenate([jnp.stack([jnp.zeros_like(v0), v0]), y_max[2] * 0.0]), ball, model
    )  # δ = 0, δ̇ = v₀
    peak_force = jnp.maximum(peak, first)
    peak_time = jnp.where(peak >= first, y_peak[1], 0.0)
    restitution = -dynamic_mass_kg(d_end, ball) * v_end / (ball.mass_kg * v0)
    t_end = y_end[1]

    turning = jnp.all(fs1[1] > 0.0) & jnp.all(fs2[1] > 0.0)  # dt/dφ > 0: D > 0 at every node
    outputs = jnp.stack([t_end, peak_force, restitution, d_max, t_max, peak_time, error])
    finite = jnp.all(jnp.isfinite(outputs))
    failed = ~finite | ~turning | (error > ERROR_TOLERANCE) | early
    singular = d_max >= SINGULAR_FRACTION * 2.0 * ball.radius_m * (1.0 - 1e-9)
    too_deep = d_max > model.max_deflection_ratio * ball.wall_m
    status = jnp.select(
        [failed, singular, too_deep],
        [
            STATUS_CODES["solver_failed"],
            STATUS_CODES["mass_singularity"],
            STATUS_CODES["deflection_limit"],
        ],
        STATUS_CODES["ok"],
    ).astype(jnp.int32)
    return ImpactScalars.flagged(
        status,
        2 * n_steps,
        contact_time_s=t_end,
        peak_force_N=peak_force,
        peak_time_s=peak_time,
        restitution=restitution,
        max_deflection_m=d_max,
        max_compression_time_s=t_max,
    )


def angle_error_estimate(
    height_m, ball: Ball, model: Model, *, n_steps: int = DEFAULT_STEPS
) -> jax.Array:
    """The summed weighted error estimate of ONE impact (``ok`` needs it ≤ ERROR_TOLERANCE)."""
    return _solve(height_m, ball, model, n_steps)[-1]

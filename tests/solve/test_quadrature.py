"""The quadrature path of the elastic model (rbjax.solve.quadrature) against independent solutions.

References: a minimal scipy solve_ivp (DOP853, rtol 1e-12) of paper Eq. 7 written below from the
paper's formulas (it does not call rbjax), the diffrax ODE path (``rbjax.simulate`` at a tight
solver) and central finite differences for the derivatives.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import rbjax
from rbjax.solve.quadrature import (
    _solve_scalars,
    impact_quadrature,
    impact_quadrature_batch,
)
from rbjax.solve.quadrature_history import force_history_quadrature

BALL = rbjax.JIS_RUBBER_BALL
HEIGHTS = np.array([0.01, 0.1, 1.0, 1.6])
BETA = 0.2
TIGHT = rbjax.Solver(rtol=1e-12, atol=1e-14)
FIELDS = ("contact_time_s", "restitution", "peak_force_N", "max_deflection_m")
CONFIGS = [
    (gas, blocked, stiff)
    for gas in ("adiabatic", "none")
    for blocked in ("paper", "momentum")
    for stiff in (False, True)
]


# --------------------------------------------------------------------------------------------
# Independent reference: Eq. 7 with the paper's force terms (Eqs. 1–4 corrected, Eq. 10).


def _reference(height_m, *, gas, blocked_force, beta, youngs_Pa=1.6e6, poisson=0.5, mass_kg=2.5):
    r, h, m = 0.089, 0.032, mass_kg
    k = 4.0 * youngs_Pa * h**2 / (r * math.sqrt(3.0 * (1.0 - poisson**2)))
    v0 = math.sqrt(2.0 * 9.80665 * height_m)

    def force(d):
        f = k * d * (1.0 + beta * (d / h) ** 2)
        if gas == "adiabatic":
            cavity = 4.0 * math.pi * r**3 / 3.0
            cap = math.pi * d**2 * (3.0 * r - d) / 3.0
            f = f + 101325.0 * ((cavity / (cavity - cap)) ** 1.4 - 1.0) * math.pi * d * (
                2.0 * r - d
            )
        return f

    def rhs(flux):
        def f(t, y):
            push = force(y[0]) - (m / (2.0 * r) * y[1] ** 2 if flux else 0.0)
            return [y[1], -push / (m * (1.0 - y[0] / (2.0 * r)))]

        return f

    def stop(index):
        def event(t, y):
            return y[index]

        event.terminal, event.direction = True, -1.0
        return event

    scale = v0 * math.sqrt(m / k)
    options = dict(method="DOP853", rtol=1e-12, atol=[1e-15 * scale, 1e-15 * v0], dense_output=True)
    span = 100.0 * math.sqrt(m / k)
    comp = solve_ivp(rhs(False), (0.0, span), [0.0, v0], events=stop(1), **options)
    t_max, d_max = comp.t_events[0][0], comp.y_events[0][0][0]
    rest = solve_ivp(rhs(True), (t_max, t_max + span), [d_max, 0.0], events=stop(0), **options)
    t_end, v_end = rest.t_events[0][0], rest.y_events[0][0][1]

    def floor(t):  # the blocked force at times t (zero outside the contact)
        t = np.asarray(t, dtype=float)
        y = np.where(
            t <= t_max, comp.sol(np.clip(t, 0.0, t_max)), rest.sol(np.clip(t, t_max, t_end))
        )
        f = force(y[0])
        if blocked_force == "momentum":
            f = f + np.where(t <= t_max, m / (2.0 * r) * y[1] ** 2, 0.0)
        return np.where((t >= 0.0) & (t < t_end), f, 0.0)

    # The peak of the floor force, searched on the dense solution around the candidates.
    grid = np.concatenate([np.linspace(0.0, t_end, 4001), [t_max]])
    peak = max(float(np.max(floor(grid[:-1]))), force(d_max))
    return dict(
        contact_time_s=t_end,
        restitution=abs(v_end) / v0,
        peak_force_N=peak,
        max_deflection_m=d_max,
        floor=floor,
    )


def _batched(tree, size):
    return jax.tree_util.tree_map(lambda x: jnp.full((size,), x, dtype=jnp.float64), tree)


def _model(gas, blocked, stiff, size=None):
    stiffening = None
    if stiff:
        stiffening = rbjax.CubicStiffening(BETA if size is None else jnp.full((size,), BETA))
    return rbjax.Model(gas=gas, blocked_force=blocked, stiffening=stiffening)


def _rel(a, b):
    return np.abs(np.asarray(a) / np.asarray(b) - 1.0)


@pytest.fixture(scope="module")
def references():
    return {
        (gas, blocked, stiff, h): _reference(
            h, gas=gas, blocked_force=blocked, beta=BETA if stiff else 0.0
        )
        for gas, blocked, stiff in CONFIGS
        for h in HEIGHTS
    }


@pytest.fixture(scope="module")
def quadrature_results():
    n = len(HEIGHTS)
    return {
        config: impact_quadrature_batch(
            jnp.asarray(HEIGHTS), _batched(BALL.as_arrays(), n), _model(*config, size=n)
        )
        for config in CONFIGS
    }


# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("config", CONFIGS, ids=["-".join(map(str, c)) for c in CONFIGS])
def test_matches_scipy_reference(config, references, quadrature_results):
    out = quadrature_results[config]
    assert np.all(np.asarray(out.status) == 0)
    for i, h in enumerate(HEIGHTS):
        ref = references[config + (h,)]
        for name in FIELDS:
            assert _rel(getattr(out, name)[i], ref[name]) <= 1e-10, (config, h, name)


@pytest.mark.parametrize("gas, blocked", [("adiabatic", "paper"), ("none", "momentum")])
def test_matches_ode_path(gas, blocked, quadrature_results):
    # Two ODE compilations cover gas on/off, both blocked-force options and, through β = 0 and
    # β = 0.2 as one broadcast array, the shell without and with stiffening.
    sim = rbjax.simulate(
        HEIGHTS[:, None],
        gas=gas,
        blocked_force=blocked,
        stiffening=rbjax.CubicStiffening(jnp.array([[0.0, BETA]])),
        solver=TIGHT,
    )
    assert np.all(np.asarray(sim.status) == 0)
    for j, stiff in enumerate((False, True)):
        out = quadrature_results[(gas, blocked, stiff)]
        for name in FIELDS:
            np.testing.assert_array_less(_rel(getattr(out, name), getattr(sim, name)[:, j]), 1e-10)
        np.testing.assert_array_less(_rel(out.peak_time_s, sim.peak_time_s[:, j]), 1e-10)


def test_error_falls_with_nodes_and_coarse_rules_are_flagged(references):
    # The raw values of the scalar path (before the status masks them) at growing node counts.
    ref = references[("adiabatic", "paper", False, 1.0)]
    errors, estimates, statuses = [], [], []
    for n in (4, 5, 6, 8, 12):
        sol = jax.jit(lambda h: _solve_scalars(h, BALL, rbjax.Model(), n))(1.0)
        raw = {
            "contact_time_s": sol.t_compression + sol.t_restitution,
            "restitution": sol.v_out / sol.v0,
            "max_deflection_m": sol.d_max,
        }
        errors.append(max(float(_rel(raw[name], ref[name])) for name in raw))
        estimates.append(float(sol.error_estimate))
        statuses.append(int(sol.status))
    assert errors[0] > errors[1] > errors[2] > errors[3] > errors[4]
    assert errors[0] >= 1e-6  # the coarse rule is visibly inexact, so the test can fail
    assert errors[4] <= 1e-12  # the default, 12 nodes
    # the estimate bounds the error, and every rule whose estimate exceeds the tolerance is flagged
    assert all(err <= est for err, est in zip(errors, estimates))
    assert statuses == [rbjax.STATUS_CODES["solver_failed"]] * 4 + [0]
    out = jax.jit(lambda h: impact_quadrature(h, BALL, rbjax.Model(), n_nodes=6))(1.0)
    assert int(out.status) == rbjax.STATUS_CODES["solver_failed"] and np.isnan(
        float(out.contact_time_s)
    )


# --------------------------------------------------------------------------------------------
# Derivatives with respect to (E, ν, M, h_D) at ν = 0.45 (inside the open range, so a central
# difference stays physical), against central finite differences of the forward model.

THETA = np.array([1.6e6, 0.45, 2.5, 1.0])


def _outputs(theta):
    ball = BALL.replace(youngs_Pa=theta[0], poisson=theta[1], mass_kg=theta[2])
    out = impact_quadrature(theta[3], ball, rbjax.Model())
    return jnp.stack([getattr(out, name) for name in FIELDS])


@pytest.fixture(scope="module")
def finite_difference_jacobian():
    steps = 1e-5 * THETA
    points = np.concatenate([THETA + np.diag(steps), THETA - np.diag(steps)])
    values = np.asarray(jax.jit(jax.vmap(_outputs))(jnp.asarray(points)))
    return (values[:4] - values[4:]).T / (2.0 * steps), np.asarray(
        jax.jit(_outputs)(jnp.asarray(THETA))
    )


def _assert_close_elasticities(jac, fd, values):
    # Compare the elasticities ∂ln y/∂ln θ, all O(0.01–1) here.
    scale = THETA[None, :] / values[:, None]
    assert np.max(np.abs(fd * scale)) > 0.1
    np.testing.assert_allclose(np.asarray(jac) * scale, fd * scale, rtol=0, atol=1e-7)


def test_jacfwd_matches_finite_differences(finite_difference_jacobian):
    fd, values = finite_difference_jacobian
    jac = jax.jit(jax.jacfwd(_outputs))(jnp.asarray(THETA))
    _assert_close_elasticities(jac, fd, values)


def test_grad_matches_finite_differences(finite_difference_jacobian):
    fd, values = finite_difference_jacobian
    weights = jnp.asarray(1.0 / values) * jnp.array([1.0, -2.0, 0.5, 3.0])  # every output counts
    grad = jax.jit(jax.grad(lambda theta: jnp.dot(weights, _outputs(theta))))(jnp.asarray(THETA))
    _assert_close_elasticities(grad[None, :], (np.asarray(weights) @ fd)[None, :], np.array([1.0]))


# --------------------------------------------------------------------------------------------


def test_force_history_matches_ode_and_reference():
    model = rbjax.Model(blocked_force="momentum")
    heights = np.array([0.1, 1.0])
    out = impact_quadrature_batch(jnp.asarray(heights), _batched(BALL.as_arrays(), 2), model)
    t_end = float(np.max(out.contact_time_s))
    times = np.linspace(-1e-3, 1.05 * t_end, 401)
    ode = rbjax.trajectory(heights, times, BALL, model, TIGHT)
    history = jax.jit(lambda h, t: force_history_quadrature(h, BALL, model, t))
    for i, h in enumerate(heights):
        quad = history(h, jnp.asarray(times))
        peak = float(out.peak_force_N[i])
        assert np.max(np.abs(np.asarray(quad.force_N) - np.asarray(ode.force_N[i]))) <= 1e-8 * peak
        assert np.max(
            np.abs(np.asarray(quad.deflection_m) - np.asarray(ode.deflection_m[i]))
        ) <= 1e-8 * float(out.max_deflection_m[i])
        ref = _reference(h, gas="adiabatic", blocked_force="momentum", beta=0.0)
        assert np.max(np.abs(np.asarray(quad.force_N) - ref["floor"](times))) <= 1e-8 * peak
        inside = (times >= 0.0) & (times < float(out.contact_time_s[i]))
        np.testing.assert_array_equal(np.asarray(quad.in_contact), inside)
        assert np.all(np.asarray(quad.force_N)[~inside] == 0.0)


def test_deflection_limit_at_10_m():
    out = jax.jit(lambda h: impact_quadrature(h, BALL, rbjax.Model()))(10.0)
    assert int(out.status) == rbjax.STATUS_CODES["deflection_limit"]
    assert all(np.isnan(float(getattr(out, name))) for name in FIELDS)
    # Independent: the scipy compression passes δ = 2h while the ball is still moving in.
    r, h, m = 0.089, 0.032, 2.5
    k = 4.0 * 1.6e6 * h**2 / (r * math.sqrt(3.0 * (1.0 - 0.5**2)))

    def rhs(t, y):
        return [y[1], -k * y[0] / (m * (1.0 - y[0] / (2.0 * r)))]

    def at_limit(t, y):
        return y[0] - 2.0 * h

    at_limit.terminal = True
    sol = solve_ivp(
        rhs, (0.0, 1.0), [0.0, math.sqrt(2.0 * 9.80665 * 10.0)], events=at_limit, rtol=1e-10
    )
    assert sol.t_events[0].size == 1 and sol.y_events[0][0][1] > 0.0  # (gas only stiffens it)


def test_damped_model_raises():
    with pytest.raises(ValueError, match="damping"):
        impact_quadrature(1.0, BALL, rbjax.Model(damping=rbjax.KelvinVoigt(10.0)))
    with pytest.raises(ValueError, match="n_nodes"):
        impact_quadrature(1.0, BALL, rbjax.Model(), n_nodes=1)
    with pytest.raises(ValueError, match="height_m"):
        impact_quadrature(-1.0, BALL, rbjax.Model())


def test_too_coarse_a_rule_near_the_mass_singularity_is_flagged():
    # δ_max = 0.998·2R: the integrands' pole at s = 2R sits 0.2 % outside the interval, so no
    # interpolant of up to 128 points resolves g = F/(2R − s): the quadrature flags the impact
    # (solver_failed, not mass_singularity: δ_max < 0.999·2R) instead of a plausible wrong value
    youngs, height = 25_118.8643151, 5.41169527
    ball = BALL.replace(youngs_Pa=youngs)
    model = rbjax.Model(gas="none", max_deflection_ratio=100.0)
    ref = _reference(height, gas="none", blocked_force="paper", beta=0.0, youngs_Pa=youngs)
    assert ref["max_deflection_m"] / (2 * 0.089) > 0.998
    for n in (12, 128):
        coarse = impact_quadrature(height, ball, model, n_nodes=n)
        assert int(coarse.status) == rbjax.STATUS_CODES["solver_failed"]
        assert np.isnan(float(coarse.contact_time_s))
    # further from the pole (δ_max = 0.84·2R), 48 points resolve it
    fine_height = 1.0
    fine_ref = _reference(
        fine_height, gas="none", blocked_force="paper", beta=0.0, youngs_Pa=youngs
    )
    fine = impact_quadrature(fine_height, ball, model, n_nodes=48)
    assert int(fine.status) == 0
    for name in FIELDS:
        assert float(getattr(fine, name)) == pytest.approx(fine_ref[name], rel=1e-8), name
    # the ODE path needs no such care: adaptive steps resolve the fast passage near 2R, and
    # rbjax.simulate falls back to it for the impacts the quadrature flags
    for method in ("ode", "auto"):
        res = rbjax.simulate(height, ball, gas="none", max_deflection_ratio=100.0, path=method)
        assert float(res.contact_time_s) == pytest.approx(ref["contact_time_s"], rel=1e-8)
    assert res.path == "quadrature+ode"

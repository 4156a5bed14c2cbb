"""Failure modes of the forward model at the corners of the parameter space, pinned.

Each point is either solved correctly (within 1e-6 of the independent scipy reference,
tests/scipy_reference.py: paper Eq. 7 by DOP853 at rtol 1e-12) or returned with a clear status
and NaN outputs; never silently wrong (``benchmarks/accuracy.py --only stability_map`` maps
the whole space).

* status names: ``deflection_limit`` beyond δ_max = 2h (paper §2.1: the small-deflection shell
  model holds below buckling), ``mass_singularity`` where δ reaches 2R and the dynamic mass
  M(1 − δ/2R) of Eq. 6 vanishes (gas="none"), ``step_limit`` when max_steps is exhausted;
* correct values at the corners that are valid: 1 mm drops, E = 1 GPa, near the singularity,
  heavy Kelvin–Voigt damping (5× critical);
* derivatives of contact time and peak force (forward mode, ``Solver(adjoint="forward")``, and
  reverse mode at the default solver) against central finite differences of the scipy reference.

Every configuration is one batched call (module-scoped), so each compiles once.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rbjax

from scipy_reference import reference_impact

BALL = rbjax.JIS_RUBBER_BALL
REL = 1e-6
FIELDS = ("contact_time_s", "peak_force_N", "restitution")
FORWARD = rbjax.Solver(adjoint="forward")


def critical_damping_Ns_per_m(ball=BALL):
    return 2.0 * math.sqrt(float(ball.stiffness_N_per_m) * float(ball.mass_kg))


# ------------------------------------------------------------------------------------------------
# status names at the corners of the (E, height) grid: one batched call

# (height_m, youngs_Pa, expected status). Four points: the flattened batch has the shape of
# test_impact_reference's default configuration, so the compiled solve is shared in a session.
CORNERS = [
    (1e-3, 1.6e6, "ok"),  # the smallest drop of the map, JIS ball
    (1e-3, 1e9, "ok"),  # tiny drop, stiffest ball: contact ~0.9 ms, δ_max ~ 1 µm
    (1e-3, 1e4, "ok"),  # tiny drop, softest ball (contact ~0.18 s)
    (10.0, 1.6e6, "deflection_limit"),  # JIS ball from 10 m: δ_max > 2h
]


@pytest.fixture(scope="module")
def corners():
    h = np.array([c[0] for c in CORNERS])
    e = np.array([c[1] for c in CORNERS])
    return rbjax.simulate(h, BALL.replace(youngs_Pa=e))


@pytest.fixture(scope="module")
def corner_refs():
    return [reference_impact(h, BALL.replace(youngs_Pa=e)) for h, e, _ in CORNERS]


def test_corner_status_names(corners):
    assert list(corners.status_name) == [c[2] for c in CORNERS]


def test_corner_values_match_reference(corners, corner_refs):
    for i, (h, e, expected) in enumerate(CORNERS):
        if expected != "ok":
            continue
        for field in FIELDS:
            got = float(getattr(corners, field)[i])
            want = getattr(corner_refs[i], field)
            assert got == pytest.approx(want, rel=REL), (h, e, field)


def test_deflection_limit_is_physical_and_nan(corners, corner_refs):
    """The flag is right (the reference's δ_max exceeds 2h) and its outputs are NaN."""
    for i, (h, e, expected) in enumerate(CORNERS):
        beyond = corner_refs[i].max_deflection_m > 2.0 * BALL.wall_m
        assert beyond == (expected == "deflection_limit"), (h, e)
        if expected != "ok":
            for field in FIELDS + ("max_deflection_m", "peak_time_s"):
                assert np.isnan(float(getattr(corners, field)[i])), (h, e, field)
    with pytest.raises(RuntimeError, match="deflection_limit"):
        corners.raise_for_status()


# ------------------------------------------------------------------------------------------------
# the mass singularity (gas none: nothing stops δ before 2R) and just short of it


# (height_m, youngs_Pa, expected status) with gas="none" and max_deflection_ratio=100
SINGULAR_POINTS = [
    (6.0, 1e5, "ok"),  # δ_max ≈ 0.91·2R
    (10.0, 1e4, "mass_singularity"),  # δ reaches 2R
    (10.0, 1e9, "ok"),  # highest drop, stiffest ball
    (1e-3, 1e4, "ok"),
]


@pytest.fixture(scope="module")
def near_singular():
    h = np.array([p[0] for p in SINGULAR_POINTS])
    e = np.array([p[1] for p in SINGULAR_POINTS])
    return rbjax.simulate(h, BALL.replace(youngs_Pa=e), gas="none", max_deflection_ratio=100.0)


def test_mass_singularity_status(near_singular):
    assert list(near_singular.status_name) == [p[2] for p in SINGULAR_POINTS]
    for field in FIELDS + ("max_deflection_m",):
        assert np.isnan(float(getattr(near_singular, field)[1]))


def test_gas_none_points_are_correct(near_singular):
    for i, (h, e, expected) in enumerate(SINGULAR_POINTS):
        if expected != "ok":
            continue
        ref = reference_impact(h, BALL.replace(youngs_Pa=e), gas="none")
        if i == 0:
            assert ref.max_deflection_m > 0.9 * 2.0 * BALL.radius_m  # really close to 2R
        for field in FIELDS + ("max_deflection_m",):
            assert float(getattr(near_singular, field)[i]) == pytest.approx(
                getattr(ref, field), rel=REL
            ), (h, e, field)


# ------------------------------------------------------------------------------------------------
# step_limit


def test_step_limit_with_tiny_budget():
    res = rbjax.simulate(np.array([0.1, 1.0]), solver=rbjax.Solver(max_steps=4))
    assert list(res.status_name) == ["step_limit", "step_limit"]
    assert np.all(np.isnan(np.asarray(res.contact_time_s)))
    assert np.all(np.isnan(np.asarray(res.peak_force_N)))
    assert np.all(np.asarray(res.num_steps) > 0)


def test_failed_solve_gives_a_nan_history_not_a_plausible_one():
    # the same heights with a step budget that runs out, and with the default one
    heights = np.array([0.1, 1.0])
    bad = rbjax.simulate(heights, solver=rbjax.Solver(max_steps=4)).history(duration_s=0.05)
    good = rbjax.simulate(heights).history(duration_s=0.05)
    assert np.asarray(bad.status).tolist() == [rbjax.STATUS_CODES["step_limit"]] * 2
    assert np.all(np.isnan(np.asarray(bad.force_N))) and not np.any(np.asarray(bad.in_contact))
    assert np.asarray(good.status).tolist() == [0, 0]
    assert (
        np.all(np.isfinite(np.asarray(good.force_N))) and np.max(np.asarray(good.force_N)) > 400.0
    )


# ------------------------------------------------------------------------------------------------
# heavy damping: over-damped Kelvin–Voigt (contact ends where the contact force returns to zero)

ZETAS = (2.0, 5.0)
DAMPED_HEIGHTS = (1e-3, 1.0)


@pytest.fixture(scope="module")
def damped():
    zeta, h = np.meshgrid(ZETAS, DAMPED_HEIGHTS, indexing="ij")
    c = zeta * critical_damping_Ns_per_m()
    return h, c, rbjax.simulate(h, BALL, damping=rbjax.KelvinVoigt(c))


def test_heavy_damping_is_correct(damped):
    h, c, res = damped
    assert np.all(np.asarray(res.status) == 0)
    for idx in np.ndindex(h.shape):
        ref = reference_impact(h[idx], BALL, damping=("kv", float(c[idx])))
        for field in FIELDS:
            assert float(getattr(res, field)[idx]) == pytest.approx(getattr(ref, field), rel=REL), (
                idx,
                field,
            )
        assert 0.0 <= float(res.restitution[idx]) < 0.2  # strongly over-damped: little rebound


# ------------------------------------------------------------------------------------------------
# derivatives near the boundaries against central differences of the scipy reference


def _central_difference(fn, x, rel_step):
    step = rel_step * x
    return (fn(x + step) - fn(x - step)) / (2.0 * step)


def _ref_outputs(h, e, c=None):
    damping = None if c is None else ("kv", c)
    r = reference_impact(h, BALL.replace(youngs_Pa=e), damping=damping)
    return np.array([r.contact_time_s, r.peak_force_N])


# (height_m, youngs_Pa): tiny drop, stiff ball, both
ELASTIC_POINTS = [(1e-3, 1.6e6), (1.0, 1e9), (1e-3, 1e9)]


@pytest.fixture(scope="module")
def elastic_tangents():
    h = jnp.array([p[0] for p in ELASTIC_POINTS])
    e = jnp.array([p[1] for p in ELASTIC_POINTS])

    def outputs(h, e):
        r = rbjax.simulate(h, BALL.replace(youngs_Pa=e), solver=FORWARD)
        return jnp.stack([r.contact_time_s, r.peak_force_N], axis=-1)

    # each impact depends on its own (h, E) only: a tangent of ones gives every derivative at once
    _, d_h = jax.jvp(outputs, (h, e), (jnp.ones_like(h), jnp.zeros_like(e)))
    _, d_e = jax.jvp(outputs, (h, e), (jnp.zeros_like(h), jnp.ones_like(e)))
    return np.asarray(d_h), np.asarray(d_e)


def _assert_elasticity(ad, fd, value, param):
    """Compare d ln y / d ln p (O(1) or small): 1e-4 relative plus 1e-6 absolute."""
    a, f = ad * param / value, fd * param / value
    assert np.all(np.isfinite(a))
    np.testing.assert_allclose(a, f, rtol=1e-4, atol=1e-6)


def test_forward_derivatives_elastic_match_finite_differences(elastic_tangents):
    d_h, d_e = elastic_tangents
    for i, (h, e) in enumerate(ELASTIC_POINTS):
        value = _ref_outputs(h, e)
        fd_h = _central_difference(lambda x: _ref_outputs(x, e), h, 1e-4)
        fd_e = _central_difference(lambda x: _ref_outputs(h, x), e, 1e-4)
        _assert_elasticity(d_h[i], fd_h, value, h)
        _assert_elasticity(d_e[i], fd_e, value, e)


def test_reverse_gradient_tiny_height():
    """jax.grad at the default (reverse-mode) solver, as in docs/getting-started.md, for a
    1 mm drop: contact time with respect to E and M (the same traced structure as
    test_impact_reference's 1 m case, so the compiled gradient is shared within a test session)."""
    e0, m0 = float(BALL.youngs_Pa), float(BALL.mass_kg)

    def outputs(e, m):
        res = rbjax.simulate(1e-3, BALL.replace(youngs_Pa=e, mass_kg=m))
        return jnp.stack([res.contact_time_s, res.peak_force_N])

    grad = np.array(
        [float(g) for g in jax.jit(jax.grad(lambda e, m: outputs(e, m)[0], argnums=(0, 1)))(e0, m0)]
    )

    def ref(e, m):
        r = reference_impact(1e-3, BALL.replace(youngs_Pa=e, mass_kg=m))
        return r.contact_time_s

    fd = np.array(
        [
            _central_difference(lambda x: ref(x, m0), e0, 1e-4),
            _central_difference(lambda x: ref(e0, x), m0, 1e-4),
        ]
    )
    assert np.all(np.isfinite(grad))
    np.testing.assert_allclose(grad, fd, rtol=1e-5)


def test_forward_derivatives_heavy_damping_match_finite_differences():
    c_crit = critical_damping_Ns_per_m()
    h = jnp.array([1e-3, 1.0])
    c = jnp.array([3.0, 3.0]) * c_crit
    e = jnp.array([1.6e6, 1.6e6])

    def outputs(h, e, c):
        r = rbjax.simulate(
            h, BALL.replace(youngs_Pa=e), damping=rbjax.KelvinVoigt(c), solver=FORWARD
        )
        return jnp.stack([r.contact_time_s, r.peak_force_N], axis=-1)

    zeros = jnp.zeros(2)
    _, d_h = jax.jvp(outputs, (h, e, c), (jnp.ones(2), zeros, zeros))
    _, d_e = jax.jvp(outputs, (h, e, c), (zeros, jnp.ones(2), zeros))
    _, d_c = jax.jvp(outputs, (h, e, c), (zeros, zeros, jnp.ones(2)))
    for i in range(2):
        hi, ei, ci = float(h[i]), float(e[i]), float(c[i])
        value = _ref_outputs(hi, ei, ci)
        _assert_elasticity(
            np.asarray(d_h[i]),
            _central_difference(lambda x: _ref_outputs(x, ei, ci), hi, 1e-4),
            value,
            hi,
        )
        _assert_elasticity(
            np.asarray(d_e[i]),
            _central_difference(lambda x: _ref_outputs(hi, x, ci), ei, 1e-4),
            value,
            ei,
        )
        _assert_elasticity(
            np.asarray(d_c[i]),
            _central_difference(lambda x: _ref_outputs(hi, ei, x), ci, 1e-4),
            value,
            ci,
        )

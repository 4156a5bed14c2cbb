"""The phase-angle path (``rbjax.solve.angle``) against independent references.

References: the scipy solution of Eq. 7 (tests/scipy_reference.py, DOP853 at rtol 1e-12, written
from the paper, calling nothing of rbjax) and central finite differences of it for gradients.
The path must agree with it where it reports ``ok``, flag what its error estimate cannot vouch
for (``solver_failed``; ``simulate`` then re-solves with the ODE), and refuse models it cannot
solve with a named reason.
"""

from __future__ import annotations

import jax
import numpy as np
import pytest

import rbjax
from rbjax.solve.angle import ERROR_TOLERANCE, angle_error_estimate

from scipy_reference import reference_impact

BALL = rbjax.JIS_RUBBER_BALL
HEIGHTS = np.array([0.05, 0.5, 2.0])
#: Every law, both blocked-force conventions, gas or none; moderate to strong damping.
MODELS = {
    "elastic-momentum-no-gas": {"blocked_force": "momentum", "gas": "none"},
    "kelvin-voigt": {"damping": rbjax.KelvinVoigt(damping_Ns_per_m=300.0)},
    "hunt-crossley": {"damping": rbjax.HuntCrossley(alpha_s_per_m=0.3)},
    "hunt-crossley-momentum": {
        "damping": rbjax.HuntCrossley(alpha_s_per_m=0.05),
        "blocked_force": "momentum",
    },
    "zener-momentum": {
        "damping": rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3),
        "blocked_force": "momentum",
    },
    "zener-stiff": {"damping": rbjax.Zener(stiffness_ratio=1.0, relaxation_time_s=2e-3)},
}
SCALARS = ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m")


def _rel(a, b):
    return abs(float(a) / float(b) - 1.0)


@pytest.mark.parametrize("name", list(MODELS))
def test_agrees_with_scipy_reference(name):
    kw = MODELS[name]
    res = rbjax.simulate(HEIGHTS, BALL, path="angle", **kw)
    assert res.path == "angle"
    assert list(res.status_name) == ["ok"] * HEIGHTS.size
    for i, h in enumerate(HEIGHTS):
        ref = reference_impact(h, BALL, **kw)
        for field in SCALARS:
            assert _rel(getattr(res, field)[i], getattr(ref, field)) <= 1e-7, (field, h)
        # the peak of a damped pulse is flat: its time is the least sharply defined output
        assert _rel(res.peak_time_s[i], ref.peak_time_s) <= 2e-6, ("peak_time_s", h)


def test_error_estimate_flags_what_fixed_steps_cannot_resolve_and_simulate_falls_back():
    # a relaxation time 1/100 of the contact: far too fast for 12 steps in the phase angle
    kw = {"damping": rbjax.Zener(stiffness_ratio=0.5, relaxation_time_s=2e-4)}
    estimate = jax.vmap(lambda h: angle_error_estimate(h, BALL.as_arrays(), rbjax.Model(**kw)))(
        HEIGHTS
    )
    assert np.all(np.asarray(estimate) > ERROR_TOLERANCE)
    only = rbjax.simulate(HEIGHTS, BALL, path="angle", **kw)
    assert list(only.status_name) == ["solver_failed"] * HEIGHTS.size
    assert np.all(np.isnan(np.asarray(only.contact_time_s)))
    auto = rbjax.simulate(HEIGHTS, BALL, **kw)
    assert auto.path == "angle+ode" and list(auto.status_name) == ["ok"] * HEIGHTS.size
    for i, h in enumerate(HEIGHTS):
        ref = reference_impact(h, BALL, **kw)
        assert _rel(auto.contact_time_s[i], ref.contact_time_s) <= 1e-6


@pytest.mark.xla_smoke  # two paths' statuses against each other: no accuracy claim
def test_limits_are_reported_like_the_ode():
    kw = {"damping": rbjax.HuntCrossley(alpha_s_per_m=0.05), "max_deflection_ratio": 0.5}
    angle = rbjax.simulate(HEIGHTS, BALL, path="angle", **kw)
    ode = rbjax.simulate(HEIGHTS, BALL, path="ode", **kw)
    assert list(angle.status_name) == list(ode.status_name)
    assert "deflection_limit" in list(angle.status_name)
    assert np.all(np.isnan(np.asarray(angle.contact_time_s)[np.asarray(angle.status) != 0]))


def test_models_it_cannot_solve_are_refused_by_name():
    with pytest.raises(
        ValueError, match=r"path='angle' cannot solve this model: the floor \(dashpot\) moves"
    ):
        rbjax.simulate(1.0, floor=rbjax.Dashpot(1e5), path="angle")
    with pytest.raises(ValueError, match="path='angle' cannot solve this model: the ball mode"):
        rbjax.simulate(1.0, ball_mode=rbjax.BallMode(0.5, 300.0, 0.1), path="angle")


def test_jacobian_matches_finite_differences_of_the_reference():
    law = rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3)
    theta = np.array([1.6e6, 2e-3])

    def ours(th):
        res = rbjax.simulate(
            1.0,
            BALL.replace(youngs_Pa=th[0]),
            damping=rbjax.Zener(law.stiffness_ratio, th[1]),
            path="angle",
        )
        return jax.numpy.stack([res.contact_time_s, res.peak_force_N, res.restitution])

    def reference(th):
        ref = reference_impact(
            1.0, BALL.replace(youngs_Pa=th[0]), damping=rbjax.Zener(law.stiffness_ratio, th[1])
        )
        return np.array([ref.contact_time_s, ref.peak_force_N, ref.restitution])

    jac = np.asarray(jax.jit(jax.jacfwd(ours))(theta))
    steps = 1e-4 * theta
    fd = np.stack(
        [
            (reference(theta + e) - reference(theta - e)) / (2 * e[j])
            for j, e in enumerate(np.diag(steps))
        ],
        axis=1,
    )
    assert np.allclose(jac, fd, rtol=2e-5, atol=0.0), (jac, fd)

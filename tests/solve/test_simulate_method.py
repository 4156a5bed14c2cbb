"""``rbjax.simulate(path=...)``: the path it picks, and the default path against independent
references.

References: the scipy solution of Eq. 7 (tests/scipy_reference.py, DOP853 at rtol 1e-12, written
from the paper and calling nothing of rbjax) and central finite differences of it. The default
``path="auto"`` runs the quadrature (``rbjax.solve.quadrature``) for undamped models, the
phase-angle integration (``rbjax.solve.angle``; its own tests: tests/test_angle.py) for damped ones
on the rigid floor and the diffrax ODE otherwise; all must agree with the reference, and so must
the histories.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rbjax
from rbjax.solve.options import PATHS
from rbjax.solve.path import quadrature_unsupported, resolve_path

from scipy_reference import HEIGHTS_M, reference_impact, reference_scalars

BALL = rbjax.JIS_RUBBER_BALL
#: Heights over the paper's range 0.1–1.6 m (one batch per configuration).
HEIGHTS = np.array([0.1, 0.25, 0.5, 0.8, 1.0, 1.3, 1.6])
ELASTIC = [
    ("adiabatic", "paper"),
    ("adiabatic", "momentum"),
    ("none", "paper"),
    ("none", "momentum"),
]
DAMPED = {
    "kelvin-voigt": rbjax.KelvinVoigt(damping_Ns_per_m=100.0),
    "hunt-crossley": rbjax.HuntCrossley(alpha_s_per_m=0.3),
    "zener": rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3),
}


#: docs/accuracy.md, "Against an independent reference" (and the README's validated table,
#: "≤ 1.1e-8 measured"): the largest relative error of the default path over 10–160 cm of the
#: contact time, peak force and restitution. The elastic models (the quadrature): "< 1e-12",
#: asserted as printed; the damped ones (the phase angle): the printed figures, asserted at 10×
#: (these heights lie in that range).
ELASTIC_BOUND = 1e-12
ACCURACY_PAGE = {
    "kelvin-voigt": (2.7e-09, 4.8e-10, 2.0e-09),
    "hunt-crossley": (1.6e-09, 4.1e-09, 2.9e-09),
    "zener": (7.6e-09, 2.4e-09, 1.1e-08),
}
STATED_FIELDS = ("contact_time_s", "peak_force_N", "restitution")


def _rel(a, b):
    return np.abs(np.asarray(a) / np.asarray(b) - 1.0)


def _assert_the_accuracy_page(res, ref, key):
    bounds = ACCURACY_PAGE[key] if key in ACCURACY_PAGE else (ELASTIC_BOUND / 10,) * 3
    for field, stated in zip(STATED_FIELDS, bounds, strict=True):
        err = np.max(_rel(getattr(res, field), ref[field]))
        assert err <= 10 * stated, (key, field, err, stated)


# ------------------------------------------------------------------------------------------------
# which path runs


def test_auto_picks_the_quadrature_for_undamped_models():
    for gas, blocked in ELASTIC:
        model = rbjax.Model(gas=gas, blocked_force=blocked)
        assert quadrature_unsupported(model) is None
        assert resolve_path("auto", model) == "quadrature"
    assert resolve_path("auto", rbjax.Model(stiffening=rbjax.CubicStiffening(0.2))) == "quadrature"
    assert rbjax.simulate(1.0).path == "quadrature"


@pytest.mark.parametrize("name", list(DAMPED))
def test_auto_picks_the_phase_angle_path_for_damped_models_on_the_rigid_floor(name):
    model = rbjax.Model(damping=DAMPED[name])
    reason = quadrature_unsupported(model)
    assert reason is not None and name in reason
    assert resolve_path("auto", model) == "angle"
    assert (
        resolve_path("auto", rbjax.Model(damping=DAMPED[name], floor=rbjax.Dashpot(1e5))) == "ode"
    )
    with pytest.raises(ValueError, match="path='quadrature' cannot solve this model.*damping"):
        resolve_path("quadrature", model)


def test_a_given_solver_asks_for_the_ode():
    assert resolve_path("auto", rbjax.Model(), rbjax.Solver()) == "ode"
    assert resolve_path("quadrature", rbjax.Model(), rbjax.Solver()) == "quadrature"
    assert rbjax.simulate(1.0, solver=rbjax.Solver()).path == "ode"


def test_method_is_validated():
    assert PATHS == ("auto", "ode", "quadrature", "angle")
    with pytest.raises(
        ValueError,
        match=r"path='rk4' is not a known option; valid: 'auto', 'ode', 'quadrature', 'angle'",
    ):
        rbjax.simulate(1.0, path="rk4")
    with pytest.raises(
        ValueError, match="path='quadrature' cannot solve this model: the damping \\(zener\\)"
    ):
        rbjax.simulate(1.0, damping=DAMPED["zener"], path="quadrature")


# ------------------------------------------------------------------------------------------------
# the default path against the scipy reference


@pytest.mark.parametrize("gas, blocked", ELASTIC, ids=["-".join(c) for c in ELASTIC])
def test_default_elastic_agrees_with_scipy_reference(gas, blocked):
    res = rbjax.simulate(HEIGHTS, BALL, gas=gas, blocked_force=blocked)
    assert res.path == "quadrature"
    assert list(res.status_name) == ["ok"] * HEIGHTS.size
    ref = reference_scalars(HEIGHTS, BALL, gas=gas, blocked_force=blocked)
    # the bar is 1e-6 in the contact time; the quadrature holds 1e-9 in every output
    assert np.max(_rel(res.contact_time_s, ref["contact_time_s"])) <= 1e-9
    for name in ("peak_force_N", "restitution", "max_deflection_m", "peak_time_s"):
        assert np.max(_rel(getattr(res, name), ref[name])) <= 1e-9, name
    _assert_the_accuracy_page(res, ref, (gas, blocked))  # < 1e-12 as printed


@pytest.mark.parametrize("name", list(DAMPED))
def test_default_damped_runs_the_phase_angle_path_and_agrees_with_scipy_reference(name):
    blocked = "momentum" if name == "zener" else "paper"
    res = rbjax.simulate(HEIGHTS_M, BALL, damping=DAMPED[name], blocked_force=blocked)
    assert res.path == "angle"
    ref = reference_scalars(HEIGHTS_M, BALL, damping=DAMPED[name], blocked_force=blocked)
    for field in ("contact_time_s", "peak_force_N", "restitution"):
        assert np.max(_rel(getattr(res, field), ref[field])) <= 1e-6, field
    _assert_the_accuracy_page(res, ref, name)


def test_quadrature_and_ode_agree():
    quad = rbjax.simulate(HEIGHTS, path="quadrature")
    ode = rbjax.simulate(HEIGHTS, path="ode")
    assert (quad.path, ode.path) == ("quadrature", "ode")
    for name in ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m"):
        assert np.max(_rel(getattr(quad, name), getattr(ode, name))) <= 1e-8, name


def test_history_after_quadrature_scalars_matches_reference():
    """Histories come from the ODE trajectory; the window is sized from the quadrature's contact
    times. Compared with the scipy dense solution on the 44.1 kHz grid of a 50 ms record."""
    heights = np.array([0.1, 1.6])
    res = rbjax.simulate(heights, duration_s=0.05)
    assert res.path == "quadrature"
    force = np.asarray(res.force_N)
    assert force.shape == (2, 2205)
    times = res.time_s
    for i, h in enumerate(heights):
        ref = reference_impact(h, BALL)
        expected = ref.force_N(times)
        peak = ref.peak_force_N
        assert np.max(np.abs(force[i] - expected)) <= 1e-7 * peak
        last = int(np.ceil(ref.contact_time_s * 44_100.0))
        assert np.all(force[i, last + 1 :] == 0.0) and force[i, last - 1] > 0.0


# ------------------------------------------------------------------------------------------------
# derivatives through the default path against finite differences of the reference


THETA = np.array(
    [1.6e6, 0.45]
)  # E, ν (ν inside its open range, so the central difference is physical)


def _reference_outputs(theta, height=1.0):
    r = reference_impact(height, BALL.replace(youngs_Pa=theta[0], poisson=theta[1]))
    return np.array([r.contact_time_s, r.peak_force_N, r.restitution])


def _fd_jacobian(theta, rel_step=1e-4):
    cols = []
    for j in range(theta.size):
        step = np.zeros_like(theta)
        step[j] = rel_step * theta[j]
        cols.append(
            (_reference_outputs(theta + step) - _reference_outputs(theta - step)) / (2.0 * step[j])
        )
    return np.stack(cols, axis=1)


def _outputs(theta):
    res = rbjax.simulate(1.0, BALL.replace(youngs_Pa=theta[0], poisson=theta[1]))
    return jnp.stack([res.contact_time_s, res.peak_force_N, res.restitution])


@pytest.fixture(scope="module")
def fd_jacobian():
    return _fd_jacobian(THETA), _reference_outputs(THETA)


def _elasticities(jac, values):
    return np.asarray(jac) * THETA[None, :] / values[:, None]


def test_jacfwd_through_auto_matches_finite_differences(fd_jacobian):
    fd, values = fd_jacobian
    jac = jax.jit(jax.jacfwd(_outputs))(jnp.asarray(THETA))  # no Solver(adjoint="forward") needed
    assert np.max(np.abs(_elasticities(fd, values))) > 0.1
    np.testing.assert_allclose(
        _elasticities(jac, values), _elasticities(fd, values), rtol=0, atol=1e-6
    )


def test_grad_through_auto_matches_finite_differences(fd_jacobian):
    fd, values = fd_jacobian
    grad = jax.jit(jax.grad(lambda th: _outputs(th)[0]))(jnp.asarray(THETA))
    np.testing.assert_allclose(
        np.asarray(grad) * THETA / values[0], fd[0] * THETA / values[0], rtol=0, atol=1e-6
    )


def test_auto_under_jit_uses_the_quadrature():
    fn = jax.jit(lambda h: rbjax.simulate(h).contact_time_s)
    tc = np.asarray(fn(jnp.asarray(HEIGHTS)))
    ref = reference_scalars(HEIGHTS, BALL)["contact_time_s"]
    assert np.max(_rel(tc, ref)) <= 1e-9


def test_a_model_is_the_one_calling_convention():
    """simulate(h, ball, model) (docs/getting-started.md): the keywords are a shortcut that
    builds the same Model; giving both is refused by name."""
    model = rbjax.Model(gas="none", blocked_force="momentum", damping=rbjax.KelvinVoigt(30.0))
    by_model = rbjax.simulate(1.0, rbjax.JIS_RUBBER_BALL, model)
    by_keywords = rbjax.simulate(
        1.0,
        rbjax.JIS_RUBBER_BALL,
        gas="none",
        blocked_force="momentum",
        damping=rbjax.KelvinVoigt(30.0),
    )
    assert by_model.model == by_keywords.model
    assert float(by_model.contact_time_s) == float(by_keywords.contact_time_s)
    elastic = rbjax.simulate(1.0, rbjax.JIS_RUBBER_BALL, rbjax.Model(gas="none"))
    assert (
        abs(float(elastic.contact_time_s) - float(by_model.contact_time_s)) > 1e-5
    )  # the model is used
    with pytest.raises(ValueError, match="keyword options \\['gas'\\]"):
        rbjax.simulate(1.0, rbjax.JIS_RUBBER_BALL, model, gas="none")
    with pytest.raises(ValueError, match="model="):
        rbjax.simulate(1.0, rbjax.JIS_RUBBER_BALL, "kelvin-voigt")


def test_batches_up_to_a_power_of_two_share_one_program_and_keep_each_impact():
    """A concrete batch of up to 128 impacts is solved padded to the next power of two: batches
    of 5 to 8 impacts compile one program, and each impact is the one the unpadded program
    (the same batch staged under ``jax.jit``) computes."""
    from rbjax.solve.devices import cached_jit
    from rbjax.solve.inputs import as_arrays
    from rbjax.solve.path_runner import Rows, rows_program

    model = rbjax.Model()
    heights = np.linspace(0.2, 1.6, 8)
    spec = Rows.of(*as_arrays((heights, BALL, model))).spec
    program = cached_jit(rows_program("quadrature", spec, rbjax.Solver()))
    program.clear_cache()
    for n in (5, 6, 7, 8):
        res = rbjax.simulate(heights[:n], model=model)
        staged = jax.jit(lambda h: rbjax.simulate(h, model=model))(jnp.asarray(heights[:n]))
        assert res.path == staged.path == "quadrature"
        assert res.contact_time_s.shape == (n,)
        for name in STATED_FIELDS:
            np.testing.assert_allclose(getattr(res, name), getattr(staged, name), rtol=1e-13)
    assert program._cache_size() == 1

"""Bad input raises ValueError naming the parameter; a failed solve is a status with NaN outputs."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import numpy as np
import pytest

import rbjax

from scipy_reference import HEIGHTS_M, reference_impact

# A smoke test (tests/conftest.py: compiled with most optimisations off): errors and status codes;
# the accuracy of the paths is tests/solve's other modules.
pytestmark = pytest.mark.xla_smoke

JIS = rbjax.JIS_RUBBER_BALL
GOOD = dict(radius_m=0.089, wall_m=0.032, mass_kg=2.5, youngs_Pa=1.6e6, poisson=0.5)


# --- heights ------------------------------------------------------------------------------------


@pytest.mark.parametrize("height", [0.0, -1.0, math.inf, -math.inf, math.nan])
def test_bad_scalar_height(height):
    with pytest.raises(ValueError, match=r"height_m=.*valid range"):
        rbjax.simulate(height)
    with pytest.raises(ValueError, match=r"height_m="):
        rbjax.trajectory(height, np.linspace(0.0, 0.02, 5))


@pytest.mark.parametrize("bad", [0.0, -0.5, math.inf, math.nan])
def test_bad_height_inside_an_array(bad):
    with pytest.raises(ValueError, match=r"height_m=.*element 2"):
        rbjax.simulate(np.array([0.5, 1.0, bad, 1.6]))


# --- ball parameters -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "field, value",
    [
        ("poisson", 0.6),
        ("poisson", -1.0),
        ("poisson", -1.5),
        ("poisson", math.nan),
        *[
            (f, v)
            for f in ("youngs_Pa", "radius_m", "wall_m", "mass_kg")
            for v in (0.0, -1.0, math.nan, math.inf)
        ],
    ],
)
def test_bad_ball_field(field, value):
    with pytest.raises(ValueError, match=rf"{field}="):
        rbjax.Ball(**{**GOOD, field: value})
    with pytest.raises(ValueError, match=rf"{field}="):
        JIS.replace(**{field: value})


def test_bad_ball_field_inside_an_array():
    with pytest.raises(ValueError, match=r"youngs_Pa=.*element 1"):
        JIS.replace(youngs_Pa=np.array([1.6e6, -2.0]))


def test_edges_of_the_valid_ranges_are_accepted():
    assert float(rbjax.Ball(**{**GOOD, "poisson": 0.5}).poisson) == 0.5  # incompressible rubber
    assert float(rbjax.Ball(**{**GOOD, "poisson": -0.99}).poisson) == -0.99


@pytest.mark.parametrize("wall", [0.089, 0.1])
def test_wall_not_thinner_than_radius(wall):
    with pytest.raises(ValueError, match=r"wall_m=.*radius_m"):
        rbjax.Ball(**{**GOOD, "wall_m": wall})


def test_replace_with_unknown_field():
    with pytest.raises(ValueError, match=r"colour"):
        JIS.replace(colour="red")


def test_ball_argument_must_be_a_ball():
    with pytest.raises(ValueError, match=r"ball="):
        rbjax.simulate(1.0, ball=dict(GOOD))


@pytest.mark.parametrize(
    "call",
    [
        lambda: rbjax.simulate(1.0, model="paper"),
        lambda: rbjax.trajectory(1.0, np.linspace(0.0, 1e-3, 4), model="paper"),
        lambda: rbjax.energy_balance(1.0, model="paper"),
    ],
    ids=["simulate", "trajectory", "energy_balance"],
)
def test_model_argument_must_be_a_model(call):
    with pytest.raises(ValueError, match=r"model='paper' must be an rbjax.Model"):
        call()


# --- model and solver options ------------------------------------------------------------------


@pytest.mark.parametrize(
    "option, value",
    [("gas", "isothermal"), ("gas", None), ("blocked_force", "total"), ("blocked_force", "Paper")],
)
def test_unknown_model_option(option, value):
    with pytest.raises(ValueError, match=rf"{option}="):
        rbjax.simulate(1.0, **{option: value})


def test_unknown_solver_scheme():
    with pytest.raises(ValueError, match=r"scheme='rk4'"):
        rbjax.Solver(scheme="rk4")
    with pytest.raises(ValueError, match=r"adjoint="):
        rbjax.Solver(adjoint="backward")
    with pytest.raises(ValueError, match=r"step_s"):
        rbjax.Solver(scheme="euler")  # a fixed-step scheme needs its step
    with pytest.raises(ValueError, match=r"rtol="):
        rbjax.Solver(rtol=-1e-9)


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: rbjax.KelvinVoigt(-1.0), "damping_Ns_per_m"),
        (lambda: rbjax.HuntCrossley(math.nan), "alpha_s_per_m"),
        (lambda: rbjax.HuntCrossley(0.5, exponent=0.5), "exponent"),
        (lambda: rbjax.Zener(0.3, 0.0), "relaxation_time_s"),
        (lambda: rbjax.Zener(-0.3, 1e-3), "stiffness_ratio"),
        (lambda: rbjax.CubicStiffening(-1.0), "beta"),
    ],
)
def test_bad_extension_parameters(make, name):
    with pytest.raises(ValueError, match=rf"{name}="):
        make()


def test_damping_must_be_a_damping_model():
    with pytest.raises(ValueError, match=r"damping="):
        rbjax.simulate(1.0, damping=100.0)


# --- failed solves: a status and NaN, never a plausible number ---------------------------------

SCALARS = ("contact_time_s", "peak_force_N", "peak_time_s", "restitution", "max_deflection_m")


def test_step_limit_is_reported():
    result = rbjax.simulate(HEIGHTS_M, solver=rbjax.Solver(max_steps=4))
    assert list(result.status_name) == ["step_limit"] * len(HEIGHTS_M)
    assert np.all(np.asarray(result.status) == rbjax.STATUS_CODES["step_limit"])
    for name in SCALARS:
        assert np.all(np.isnan(np.asarray(getattr(result, name)))), name
    with pytest.raises(RuntimeError, match=r"step_limit"):
        result.raise_for_status()


def test_deflection_beyond_the_shell_model_is_flagged():
    # A 10 m drop: δ_max ≈ 0.1 m > 2h = 0.064 m, outside the small-deflection shell model (§2.1).
    heights = np.array([0.1, 0.5, 10.0, 1.6])  # the batch shape of the other tests: no new compile
    result = rbjax.simulate(heights)
    assert list(result.status_name) == ["ok", "ok", "deflection_limit", "ok"]
    for name in SCALARS:
        values = np.asarray(getattr(result, name))
        assert np.isnan(values[2]), name
        assert np.all(np.isfinite(values[[0, 1, 3]])), name
    with pytest.raises(RuntimeError, match=r"height_m=10: deflection_limit"):
        result.raise_for_status()
    # The other heights of the batch are unaffected.
    for i in (0, 1, 3):
        ref = reference_impact(heights[i], JIS)
        assert float(result.contact_time_s[i]) == pytest.approx(ref.contact_time_s, rel=1e-6)
        assert float(result.peak_force_N[i]) == pytest.approx(ref.peak_force_N, rel=1e-6)
    # The reference agrees that the deflection passes 2h there.
    assert reference_impact(10.0, JIS).max_deflection_m > 2 * float(JIS.wall_m)


def test_a_failed_solve_has_nan_derivatives_not_zero():
    # Inside jax.jit the default path cannot fall back to the ODE: a Hunt–Crossley impact the
    # phase-angle path flags (α = 0.5 s/m at 1 m) is NaN, and so must be its gradient (it was a
    # plausible 0.0); an impact that solves keeps a finite, nonzero one.
    def contact_time(youngs_Pa, alpha):
        ball = eqx.tree_at(lambda b: b.youngs_Pa, JIS, youngs_Pa)
        model = rbjax.Model(damping=rbjax.HuntCrossley(alpha))
        return rbjax.simulate(1.0, ball, model).contact_time_s

    value_and_grad = jax.jit(jax.value_and_grad(contact_time))
    value, grad = value_and_grad(1.6e6, 0.5)
    assert np.isnan(value) and np.isnan(grad)
    value, grad = value_and_grad(1.6e6, 0.05)
    assert np.isfinite(value) and np.isfinite(grad) and grad < 0  # stiffer: shorter contact


def test_raise_for_status_returns_the_result_when_ok():
    result = rbjax.simulate(HEIGHTS_M)
    assert result.raise_for_status() is result
    assert result.status_name.tolist() == ["ok"] * len(HEIGHTS_M)


# ------------------------------------------------------------------------------------------------
# records, sample times, parameter files, sweeps


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"rate_Hz": -1.0}, "rate_Hz"),
        ({"duration_s": float("nan")}, "duration_s"),
        ({"duration_s": 1e-9}, "duration_s"),
    ],
)
def test_bad_record_for_a_history(kwargs, name):
    result = rbjax.simulate(1.0)
    with pytest.raises(ValueError, match=name):
        result.history(**kwargs)


@pytest.mark.parametrize("times", [np.array([0.0, np.nan]), np.zeros((2, 3))])
def test_bad_sample_times_for_a_trajectory(times):
    with pytest.raises(ValueError, match="times_s"):
        rbjax.trajectory(1.0, times)


@pytest.mark.parametrize(
    ("model", "match"),
    [
        (
            {
                "damping": {
                    "name": "zener",
                    "stiffness_ratio": 1.0,
                    "relaxation_time_s": 1e-3,
                    "foo": 1,
                }
            },
            "unknown keys",
        ),
        ({"damping": 5}, "damping"),
        ({"stiffening": {"b": 1.0}}, "stiffening"),
        (3, "model"),
    ],
)
def test_bad_model_in_a_parameter_file(model, match):
    from rbjax.terms.serialize import model_from_dict

    with pytest.raises(ValueError, match=match):
        model_from_dict(model)


def test_sweep_samples_are_validated_jointly():
    # each value alone is a valid wall or radius; the pair (wall 40 mm, radius 30 mm) is not
    from rbjax.solve.batch import evaluate

    with pytest.raises(ValueError, match="wall_m"):
        evaluate({"radius_m": np.array([0.09, 0.03]), "wall_m": np.array([0.03, 0.04])})


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"extra_weights": {"lfe": float("nan")}}, "extra_weights"),
        ({"max_steps": -1}, "max_steps"),
        ({"max_steps": 2.5}, "max_steps"),
    ],
)
def test_bad_fit_options(kwargs, name):
    from rbjax.fit import FitOptions, fit

    with pytest.raises(ValueError, match=name):
        fit(None, "paper", options=FitOptions(**kwargs))  # rejected before any data are read


def test_record_features_of_a_cut_off_pulse_are_nan_not_made_up():
    from rbjax.fit import record_features

    t = np.arange(441) / 44100.0
    whole = np.where(t < 0.005, 0.0, np.sin(np.pi * (t - 0.005) / 0.004)).clip(
        min=0.0
    )  # 4 ms pulse, inside
    cut = np.sin(np.pi * (t + 0.001) / 0.004).clip(min=0.0)  # already at 70 % of its peak at t = 0
    f = record_features(np.stack([whole, cut]), 44100.0)
    assert f["contact_time_s"][0] == pytest.approx(
        0.004 * (1 - 2 * np.arcsin(0.05) / np.pi), rel=1e-3
    )
    assert np.isnan(f["contact_time_s"][1]) and np.isnan(f["onset_s"][1])

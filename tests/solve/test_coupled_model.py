"""The coupled model's plumbing: terms validated at the edge, serialised, and the energy
balance checked against the independent scipy reference on the rigid floor."""

import jax.numpy as jnp
import numpy as np
import pytest

import rbjax
from rbjax.terms.ball_mode import from_modal_mass
from rbjax.terms.serialize import model_from_dict, model_to_dict

from scipy_reference import reference_scalars

BALL = rbjax.JIS_RUBBER_BALL


@pytest.mark.parametrize(
    "model",
    [
        rbjax.Model(),
        rbjax.Model(blocked_force="momentum", ball_mode=rbjax.BallMode(12.0, 450.0, 0.3)),
        rbjax.Model(floor=rbjax.ModalFloor([40.0, 9.0], [25.0, 180.0], [0.03, 0.05])),
        rbjax.Model(
            damping=rbjax.Zener(0.2, 1e-3), floor=rbjax.InfinitePlate(0.015, 4.9e9, 600.0, 0.3)
        ),
        rbjax.Model(floor=rbjax.Dashpot(2500.0)),
    ],
)
def test_model_json_round_trip(model):
    again = model_from_dict(model_to_dict(model))
    assert again.name == model.name
    assert type(again.floor) is type(model.floor)
    assert model_to_dict(again) == model_to_dict(model)


def test_unknown_floor_name_in_json_is_named():
    with pytest.raises(ValueError, match="floor name='carpet'"):
        model_from_dict({"floor": {"name": "carpet"}})


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: rbjax.BallMode(-1.0, 400.0, 0.1), "mode_mass_ratio=-1.0"),
        (lambda: rbjax.BallMode(5.0, 0.0, 0.1), "mode_frequency_Hz=0.0"),
        (lambda: rbjax.BallMode(5.0, 400.0, -0.1), "mode_loss_factor=-0.1"),
        (lambda: from_modal_mass(0.0, 400.0, 0.1, BALL), "mass_kg=0.0"),
        (lambda: from_modal_mass(-0.2, 400.0, 0.1, BALL), "mass_kg=-0.2"),
        (lambda: rbjax.ModalFloor([10.0, 0.0], [20.0, 30.0], [0.1, 0.1]), r"mass_kg\[1\]=0.0"),
        (lambda: rbjax.ModalFloor([10.0], [20.0], [-0.1]), r"loss_factor\[0\]=-0.1"),
        (lambda: rbjax.ModalFloor([10.0], [-20.0], [0.1]), r"frequency_Hz\[0\]=-20.0"),
        (lambda: rbjax.ModalFloor([10.0, 5.0], [20.0], [0.1]), "one value per mode"),
        (lambda: rbjax.Dashpot(0.0), "floor_impedance_Ns_per_m=0.0"),
        (lambda: rbjax.InfinitePlate(-0.01, 3e10, 2300.0, 0.2), "plate_thickness_m=-0.01"),
        (lambda: rbjax.Model(floor="concrete"), "floor='concrete' is not a floor"),
        (lambda: rbjax.Model(ball_mode=3.0), "ball_mode=3.0 must be None"),
    ],
)
def test_bad_terms_get_named_errors(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_from_modal_mass_is_the_mass_ratio():
    assert float(from_modal_mass(0.125, 600.0, 0.2, BALL).mode_mass_ratio) == pytest.approx(
        2.5 / 0.125
    )


def test_energy_balance_on_the_rigid_floor_matches_the_reference_restitution():
    """Rigid floor, elastic ball: the rebound energy is ½M(e v0)² with e from the scipy
    reference, the floor takes nothing, and the flux loss closes the balance."""
    heights = np.array([0.1, 1.0])
    out = rbjax.energy_balance(heights, BALL, rbjax.Model())
    ref = reference_scalars(heights, BALL)
    v0 = np.sqrt(2 * 9.80665 * heights)
    np.testing.assert_allclose(
        np.asarray(out.rebound_energy_J), 0.5 * 2.5 * (ref["restitution"] * v0) ** 2, rtol=1e-8
    )
    np.testing.assert_allclose(np.asarray(out.floor_energy_J), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(out.cap_work_J), 0.0, atol=1e-12)
    assert np.all(np.abs(np.asarray(out.residual_J)) < 1e-8 * np.asarray(out.impact_energy_J))


def test_energy_balance_refuses_a_ball_mode():
    with pytest.raises(ValueError, match="ball_mode"):
        rbjax.energy_balance(1.0, BALL, rbjax.Model(ball_mode=rbjax.BallMode(5.0, 400.0, 0.1)))


def test_quadrature_refuses_coupled_models_with_the_reason():
    with pytest.raises(ValueError, match="floor"):
        rbjax.simulate(1.0, floor=rbjax.Dashpot(1e4), path="quadrature")
    with pytest.raises(ValueError, match="ball mode"):
        rbjax.simulate(1.0, ball_mode=rbjax.BallMode(5.0, 400.0, 0.1), path="quadrature")
    assert rbjax.simulate(1.0, floor=rbjax.Dashpot(1e4)).path == "ode"


def test_parameter_layer_sees_the_new_terms():
    model = rbjax.Model(
        damping=rbjax.KelvinVoigt(3.0),
        ball_mode=rbjax.BallMode(5.0, 400.0, 0.1),
        floor=rbjax.Dashpot(1e4),
    )
    names = rbjax.parameter_names(1.0, BALL, model)
    assert {
        "mode_mass_ratio",
        "mode_frequency_Hz",
        "mode_loss_factor",
        "floor_impedance_Ns_per_m",
        "damping_Ns_per_m",
    } <= set(names)
    assert jnp.shape(rbjax.terms.parameters.to_vector(1.0, BALL, model)) == (len(names),)

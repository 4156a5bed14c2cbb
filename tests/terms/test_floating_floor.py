"""``FloatingFloor``: its two drive-point modes against scipy's generalised eigensolver of the
mass–spring–mass system, its parameters declared (named errors), and traceable."""

import math

import jax
import numpy as np
import pytest
from scipy.linalg import eigh

from rbjax.terms import FloatingFloor, parameter_names
from rbjax.terms.model import Model


def _reference(t, rho, area, s, m2, f2, eta1, eta2):
    """Modal masses at the screed, frequencies and strain-energy loss factors by scipy."""
    m1, k1, k2 = rho * t * area, s * area, m2 * (2 * math.pi * f2) ** 2
    w2, phi = eigh(np.array([[k1, -k1], [-k1, k1 + k2]]), np.diag([m1, m2]))  # φᵀMφ = 1
    w2 = np.where(w2 > 1e-9 * w2.max(), w2, 0.0)
    strain = eta1 * k1 * (phi[0] - phi[1]) ** 2 + eta2 * k2 * phi[1] ** 2
    return (
        1 / phi[0] ** 2,
        np.sqrt(w2) / (2 * math.pi),
        np.where(w2 > 0, strain / np.where(w2 > 0, w2, 1), 0.0),
    )


@pytest.mark.parametrize(
    "args",
    [
        (0.07, 2200.0, 1.0, 40e6, 1725.0, 27.0, 0.1, 0.02),  # on a 150 mm slab's first mode
        (0.05, 2000.0, 0.01, 1e6, 5000.0, 60.0, 0.1, 0.02),  # soft layer, heavy base: λ₋ ≪ λ₊
        (0.05, 2000.0, 0.01, 1e7, 100.0, 0.0, 0.2, 0.05),  # free base: a rigid-body mode
    ],
)
def test_modes_match_scipy_eigh(args):
    floor = FloatingFloor(*args[:6], layer_loss_factor=args[6], base_loss_factor=args[7])
    for got, want in zip((floor.mass_kg, floor.frequency_Hz, floor.loss_factor), _reference(*args)):
        np.testing.assert_allclose(np.asarray(got), want, rtol=1e-9, atol=1e-12)
    # the drive-point flexibility at low frequency: Σ 1/m_k = 1/m₁
    assert float(np.sum(1 / np.asarray(floor.mass_kg))) == pytest.approx(
        1 / (args[0] * args[1] * args[2]), rel=1e-12
    )


def test_parameters_are_declared_leaves():
    floor = FloatingFloor(0.07, 2200.0, 1.0, 40e6, 1725.0, 27.0)
    names = parameter_names(1.0, model=Model(floor=floor))
    assert {"screed_thickness_m", "dynamic_stiffness_N_per_m3", "layer_loss_factor"} <= set(names)
    # traceable: the modes under jit follow the stiffness given
    f = jax.jit(lambda s: FloatingFloor(0.07, 2200.0, 1.0, s, 1725.0, 27.0).frequency_Hz)
    np.testing.assert_allclose(
        np.asarray(f(20e6)),
        np.asarray(FloatingFloor(0.07, 2200.0, 1.0, 20e6, 1725.0, 27.0).frequency_Hz),
        rtol=1e-14,
    )


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("screed_thickness_m", 0.0),
        ("dynamic_stiffness_N_per_m3", -1.0),
        ("base_frequency_Hz", -5.0),
        ("layer_loss_factor", -0.1),
    ],
)
def test_bad_parameters_are_named(field, value):
    args = dict(
        screed_thickness_m=0.07,
        screed_density_kg_per_m3=2200.0,
        area_m2=1.0,
        dynamic_stiffness_N_per_m3=40e6,
        base_mass_kg=1725.0,
        base_frequency_Hz=27.0,
    )
    with pytest.raises(ValueError, match=f"{field}={value}"):
        FloatingFloor(**(args | {field: value}))


def test_model_json_round_trip():
    from rbjax.terms.serialize import model_from_dict, model_to_dict

    d = model_to_dict(Model(floor=FloatingFloor(0.07, 2200.0, 1.0, 40e6, 1725.0, 27.0)))
    assert d["floor"]["name"] == "floating" and d["floor"]["dynamic_stiffness_N_per_m3"] == 40e6
    assert model_to_dict(model_from_dict(d)) == d

"""The series element (``rbjax.SeriesKelvinVoigt``, the ball mode's massless limit) against an
independent scipy reference (state (X, Ẋ, w), the element's velocity found by a root at every
right-hand side), the limit of the ball mode it stands for, its off switch, named errors, and
its place in the model names, the files and the fit layer."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import rbjax
from rbjax import JIS_RUBBER_BALL as BALL
from rbjax import BallMode, HuntCrossley, SeriesKelvinVoigt
from rbjax.fit import all_model_names, model_from_name, parse_model_terms
from rbjax.fit.layout import (
    ARREST_SUFFIX,
    BALL_MODE_SUFFIX,
    LAYER_SUFFIX,
    SERIES_SUFFIX,
    STIFFENING_SUFFIX,
    fitted_parameter_names,
)
from rbjax.fit.physical import series_structure
from rbjax.studies.selection.candidates import shared_structure, shared_structures
from rbjax.terms import model_from_dict, model_to_dict
from rbjax.terms.damping import DAMPING_MODELS

from scipy_series_reference import reference_series_impact

#: (height, damping, blocked force, C, τ): near the fit on the bundled recordings
#: (k_b ≈ 330 kN/m, c_b ≈ 1.5 kN s/m), and a softer, faster element with the paper's blocked
#: force (one model structure: one compiled solve for both).
CASES = [
    (1.0, HuntCrossley(0.04), "momentum", 3.0e-6, 4.6e-3),
    (0.2, HuntCrossley(0.1), "paper", 1.0e-5, 1.0e-3),
]


def _model(damping, blocked_force, compliance, tau):
    return rbjax.Model(
        blocked_force=blocked_force, damping=damping, series=SeriesKelvinVoigt(compliance, tau)
    )


@pytest.mark.parametrize("case", CASES, ids=["momentum", "paper"])
def test_impact_matches_the_scipy_reference(case):
    """Contact time and restitution to 1e-8, the floor force at 200 times to 1e-7 of its peak,
    the peak to 1e-6 (the reference's is the maximum on a 4 000-point grid)."""
    h, damping, bf, compliance, tau = case
    ref = reference_series_impact(h, BALL, compliance, tau, damping=damping, blocked_force=bf)
    model = _model(damping, bf, compliance, tau)
    res = rbjax.simulate(h, BALL, model)
    assert res.path == "ode" and int(res.status) == 0
    assert float(res.contact_time_s) == pytest.approx(ref.contact_time_s, rel=1e-8)
    assert float(res.restitution) == pytest.approx(ref.restitution, rel=1e-8)
    assert float(res.peak_force_N) == pytest.approx(ref.max_force_N, rel=1e-6)
    times = np.linspace(0.0, 0.999 * ref.contact_time_s, 200)
    force = np.asarray(rbjax.trajectory(h, times, BALL, model).force_N)
    assert np.max(np.abs(force - ref.force_N(times))) <= 1e-7 * ref.max_force_N
    # the element matters here: held off, the contact time differs by more than 1 %
    off = rbjax.simulate(h, BALL, _model(damping, bf, 0.0, tau))
    assert abs(float(off.contact_time_s) / ref.contact_time_s - 1.0) > 0.01


def test_the_ball_mode_tends_to_it_as_its_mass_vanishes():
    """m_b(ẅ + ηωẇ + ω²w) = −F_c at fixed k_b = m_b ω², c_b = ηω m_b: the contact time, the
    restitution and the peak force approach the series element's linearly in m_b (10× less
    mass, 10× closer; at 1 g: 5e-7 of the contact time, 6e-6 in restitution, 6e-6 of the peak)."""
    h, damping, bf, compliance, tau = CASES[0]
    ref = rbjax.simulate(h, BALL, _model(damping, bf, compliance, tau))
    k_b, c_b = 1.0 / compliance, tau / compliance
    gaps = []
    for mass in (1e-2, 1e-3):
        omega = math.sqrt(k_b / mass)
        mode = BallMode(float(BALL.mass_kg) / mass, omega / (2 * math.pi), c_b / (mass * omega))
        res = rbjax.simulate(
            h,
            BALL,
            rbjax.Model(blocked_force=bf, damping=damping, ball_mode=mode),
            solver=rbjax.Solver(max_steps=65536),
        )
        assert int(res.status) == 0
        gaps.append(
            np.abs(
                [
                    float(res.contact_time_s - ref.contact_time_s) / float(ref.contact_time_s),
                    float(res.restitution - ref.restitution),
                    float(res.peak_force_N - ref.peak_force_N) / float(ref.peak_force_N),
                ]
            )
        )
    coarse, fine = gaps
    assert np.all(fine <= np.array([1e-6, 1e-5, 1e-5]))
    assert np.all((coarse / fine >= 7.0) & (coarse / fine <= 13.0))


def test_zero_compliance_is_the_model_without_it():
    """C = 0 holds w ≡ 0: the ODE with the element off equals the phase-angle path without it."""
    h, damping, bf, _, _ = CASES[1]
    off = rbjax.simulate(
        h, BALL, rbjax.Model(blocked_force=bf, damping=damping, series=SeriesKelvinVoigt.off())
    )
    plain = rbjax.simulate(h, BALL, rbjax.Model(blocked_force=bf, damping=damping))
    assert off.path == "ode" and plain.path != "ode"
    assert float(off.contact_time_s) == pytest.approx(float(plain.contact_time_s), rel=1e-7)
    assert float(off.restitution) == pytest.approx(float(plain.restitution), rel=1e-7)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (
            {"series_compliance_m_per_N": -1e-6, "series_time_constant_s": 1e-3},
            "series_compliance_m_per_N=-1e-06",
        ),
        (
            {"series_compliance_m_per_N": 1e-6, "series_time_constant_s": 0.0},
            "series_time_constant_s=0.0",
        ),
        (
            {"series_compliance_m_per_N": float("nan"), "series_time_constant_s": 1e-3},
            "series_compliance_m_per_N=nan",
        ),
    ],
)
def test_bad_values_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace("+", r"\+")):
        SeriesKelvinVoigt(**kwargs)


def test_a_series_that_is_not_the_element_is_named():
    with pytest.raises(ValueError, match="series="):
        rbjax.Model(series=BallMode(20.0, 800.0, 0.3))


def test_energy_balance_says_it_does_not_cover_it():
    with pytest.raises(ValueError, match="series"):
        rbjax.energy_balance(1.0, BALL, _model(None, "paper", 3e-6, 4.6e-3))


def test_names_files_and_the_fit_layer():
    name = "hunt-crossley+series-kelvin-voigt"
    assert name in all_model_names() and "zener+stiffening+series-kelvin-voigt" in all_model_names()
    assert parse_model_terms(name) == ((HuntCrossley,), False, False, True, False, False)
    # the ball mode is the other term, not the series element (its full tuple: test_ball_mode)
    mode = parse_model_terms("hunt-crossley+ball-mode")
    assert mode.ball_mode and not mode.series
    model = model_from_name(
        name, blocked_force="momentum", values={"series_compliance_m_per_N": 3e-6}
    )
    assert model.name == name and float(model.series.series_compliance_m_per_N) == 3e-6
    assert fitted_parameter_names(model) == (
        "youngs_Pa",
        "poisson",
        "alpha_s_per_m",
        "series_compliance_m_per_N",
        "series_time_constant_s",
    )
    back = model_from_dict(model_to_dict(model))
    assert back.name == name and float(back.series.series_time_constant_s) == float(
        model.series.series_time_constant_s
    )
    assert "series" not in model_to_dict(
        rbjax.Model()
    )  # files without the element stay as they were
    structure = shared_structure(["hunt-crossley", name, "hunt-crossley+ball-mode"])
    assert (
        float(structure.series.series_compliance_m_per_N) == 0.0
        and float(structure.ball_mode.mode_mass_ratio) == 0.0
    )
    # a selection fits the candidates without the element in a structure without it
    structures = shared_structures(["paper", "hunt-crossley+ball-mode", name])
    assert (
        structures["paper"] is structures["hunt-crossley+ball-mode"]
        and structures["paper"].series is None
    )
    assert structures[name].series is not None and structures[name].ball_mode is None
    reading = series_structure(_model(None, "paper", 1.0 / 3.3e5, 1.5e3 / 3.3e5))
    assert "3.3e+05 N/m" in reading and "1.5e+03 N s/m" in reading
    assert series_structure(structure) == ""


def test_every_name_the_parser_accepts_is_listed_and_builds_its_model():
    # the grammar: a base, then up to five suffixes in any order, repeats included
    suffixes = (STIFFENING_SUFFIX, LAYER_SUFFIX, ARREST_SUFFIX, BALL_MODE_SUFFIX, SERIES_SUFFIX)
    bases = ("paper", *DAMPING_MODELS, "maxwell", "")
    accepted = set()
    for base in bases:
        for count in range(6):
            for tail in itertools.product(suffixes, repeat=count):
                name = base + "".join(tail)
                try:
                    parse_model_terms(name)
                except ValueError:
                    continue
                accepted.add(name)
    listed = all_model_names()
    assert len(listed) == len(set(listed)) and set(listed) == accepted
    both = "hunt-crossley+stiffening+ball-mode+series-kelvin-voigt"
    assert both in listed and parse_model_terms(both) == (
        (HuntCrossley,),
        True,
        True,
        True,
        False,
        False,
    )
    for name in listed:  # each builds the model that Model.name writes back as the name
        assert model_from_name(name).name == name

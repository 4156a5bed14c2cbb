"""The fitted ball mode read in physical terms, and parameters on a bound of their fit range
(docs/guides/fitting.md, "With the ball mode")."""

from __future__ import annotations

import math

import pytest

import rbjax
from rbjax.fit.layout import FIT_RANGES, fit_declaration, model_from_name
from rbjax.fit.physical import at_bounds, ball_mode_structure


def test_the_mode_is_a_mass_a_spring_and_a_damper():
    ball = rbjax.JIS_RUBBER_BALL  # M = 2.5 kg
    model = rbjax.Model(ball_mode=rbjax.BallMode(5.0, 100.0, 3.0))
    text = ball_mode_structure(ball, model)
    mass = 2.5 / 5.0
    omega = 2 * math.pi * 100.0
    assert "500 g mass" in text
    assert f"{omega**2 * mass:.3g} N/m" in text and f"{3.0 * omega * mass:.3g} N s/m" in text
    assert "overdamped" in text
    assert "ringing mode" in ball_mode_structure(
        ball, rbjax.Model(ball_mode=rbjax.BallMode(20.0, 600.0, 0.2))
    )
    assert ball_mode_structure(ball, rbjax.Model()) == ""
    assert ball_mode_structure(ball, rbjax.Model(ball_mode=rbjax.BallMode.off())) == ""


def test_a_parameter_on_a_bound_is_named():
    lo, hi = FIT_RANGES["mode_loss_factor"]
    assert "mode_loss_factor" in at_bounds(
        {"mode_loss_factor": hi - 1e-4 * (hi - lo), "youngs_Pa": 1e6}
    )
    assert "upper bound" in at_bounds({"mode_loss_factor": hi})
    assert at_bounds({"mode_loss_factor": 0.5 * (lo + hi)}) == ""


def test_the_fit_keeps_the_mode_in_its_range_and_the_term_does_not():
    model = model_from_name("hunt-crossley+ball-mode")
    spec = fit_declaration("mode_frequency_Hz", rbjax.JIS_RUBBER_BALL, model)
    lo, hi = FIT_RANGES["mode_frequency_Hz"]
    assert spec.transform == "interval" and (spec.lower, spec.upper) == (lo, hi)
    assert float(spec.from_unconstrained(-50.0)) == pytest.approx(lo) and float(
        spec.from_unconstrained(50.0)
    ) == pytest.approx(hi)
    # simulate still takes any positive frequency (the term's own declaration)
    assert rbjax.BallMode(20.0, 1e5, 0.1).mode_frequency_Hz == 1e5
    assert fit_declaration("youngs_Pa", rbjax.JIS_RUBBER_BALL, model).transform == "log"

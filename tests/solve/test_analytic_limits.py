"""rbjax against closed forms and quadratures that need no ODE solver.

1. Linear-oscillator limit. With gas="none" and a ball of huge radius R the dynamic mass
   M(1 − δ/2R) → M and the momentum flux (M/2R)δ̇² → 0 in Eq. 7, leaving M δ̈ = −kδ:
   t_c = π√(M/k), F_max = v0√(kM), restitution 1, F(t) = v0√(kM) sin(t√(k/M)).
   Both neglected terms are of relative size ε = δ_max/(2R) (δ_max = v0√(M/k); the flux over
   the shell force is (M/2R)v0²/(kδ_max) = ε as well), so every quantity is off by O(ε).
   The first-order terms follow from the energy balance below: δ_max = v0√(M/k)(1 − ε/3 + O(ε²))
   and e² = (1 − 2ε/3)/(1 + 2ε/3), i.e. F_max = v0√(kM)(1 − ε/3), e = 1 − 2ε/3, to O(ε²).
2. The energy-balance reduction (the one src/rbjax/quadrature.py implements, see its module
   docstring) for a force F(δ) that depends on δ only (the paper's elastic model), done here
   with scipy.integrate.quad:
   u = δ̇², compression u_c(δ) = (4R/M)∫_δ^δmax F(s)/(2R − s) ds, restitution
   (2R − δ)² u_r(δ) = (4R/M)∫_δ^δmax F(s)(2R − s) ds, v_out² = u_r(0), and
   t_c = ∫₀¹ 2δ_max σ [u_c^(−1/2) + u_r^(−1/2)] dσ at δ = δ_max(1 − σ²).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import rbjax

from scipy_reference import (
    HEIGHTS_M,
    HISTORY_TIMES_S,
    STANDARD_GRAVITY,
    gas_force,
    reference_impact,
    shell_stiffness,
)

# ---------------------------------------------------------------------------------------------
# 1. linear-oscillator limit

STIFFNESS_N_PER_M = 5.0e4
MASS_KG = 2.5
HUGE_RADIUS_M = 1.0e4
WALL_M, POISSON = 0.032, 0.3
OMEGA = math.sqrt(STIFFNESS_N_PER_M / MASS_KG)
V0 = np.sqrt(2.0 * STANDARD_GRAVITY * HEIGHTS_M)
EPS = V0 / OMEGA / (2.0 * HUGE_RADIUS_M)  # δ_max/2R ≤ 2.0e-6 at 1.6 m
SOLVER_REL = 1e-8  # rbjax's own integration error at its defaults is ~1e-10


@pytest.fixture(scope="module")
def linear_ball():
    # Choose E so that Reissner's k = 4Eh²/(R√(3(1−ν²))) is the chosen stiffness.
    youngs = (
        STIFFNESS_N_PER_M * HUGE_RADIUS_M * math.sqrt(3.0 * (1.0 - POISSON**2)) / (4.0 * WALL_M**2)
    )
    return rbjax.Ball(
        radius_m=HUGE_RADIUS_M, wall_m=WALL_M, mass_kg=MASS_KG, youngs_Pa=youngs, poisson=POISSON
    )


@pytest.fixture(scope="module")
def linear(linear_ball):
    result = rbjax.simulate(HEIGHTS_M, linear_ball, gas="none")
    history = rbjax.trajectory(HEIGHTS_M, HISTORY_TIMES_S, linear_ball, rbjax.Model(gas="none"))
    return result, history


def test_linear_ball_has_the_chosen_stiffness(linear_ball):
    assert float(linear_ball.stiffness_N_per_m) == pytest.approx(STIFFNESS_N_PER_M, rel=1e-13)
    assert np.all(EPS < 2.1e-6)


def test_linear_limit_contact_time(linear):
    result, _ = linear
    assert np.all(np.asarray(result.ok))
    err = np.abs(np.asarray(result.contact_time_s) / (math.pi / OMEGA) - 1.0)
    assert np.all(err <= EPS), err / EPS


def test_linear_limit_peak_force(linear):
    result, _ = linear
    expected = V0 * math.sqrt(STIFFNESS_N_PER_M * MASS_KG)
    err = np.abs(np.asarray(result.peak_force_N) / expected - 1.0)
    assert np.all(err <= EPS)
    # The first-order correction −ε/3 (mass reduction during compression).
    np.testing.assert_allclose(
        np.asarray(result.peak_force_N), expected * (1.0 - EPS / 3.0), rtol=SOLVER_REL
    )
    np.testing.assert_allclose(
        np.asarray(result.peak_time_s), math.pi / (2.0 * OMEGA), rtol=EPS.max()
    )


def test_linear_limit_restitution(linear):
    result, _ = linear
    e = np.asarray(result.restitution)
    assert np.all(e < 1.0)
    assert np.all(np.abs(e - 1.0) <= EPS)
    # First order: the flux term of the restitution phase loses 2ε/3 of the rebound speed.
    np.testing.assert_allclose(e, 1.0 - 2.0 * EPS / 3.0, rtol=SOLVER_REL)


def test_linear_limit_history(linear):
    _, history = linear
    t = HISTORY_TIMES_S
    tc = math.pi / OMEGA
    amplitude = V0[:, None] * math.sqrt(STIFFNESS_N_PER_M * MASS_KG)
    expected = np.where(t[None, :] < tc, amplitude * np.sin(OMEGA * t[None, :]), 0.0)
    err = np.max(np.abs(np.asarray(history.force_N) - expected), axis=1) / amplitude[:, 0]
    # Amplitude error ε/3 plus a phase lag of at most ε t_c/π·ω = ε at the end of contact.
    assert np.all(err <= 2.0 * EPS), err / EPS
    deflection = np.where(t[None, :] < tc, V0[:, None] / OMEGA * np.sin(OMEGA * t[None, :]), 0.0)
    err_d = np.max(np.abs(np.asarray(history.deflection_m) - deflection), axis=1) / (V0 / OMEGA)
    assert np.all(err_d <= 2.0 * EPS)


# ---------------------------------------------------------------------------------------------
# 2. the energy-balance quadrature (elastic model, JIS ball)

QUAD = dict(epsabs=0.0, epsrel=1e-13, limit=200)


def energy_balance(height_m, ball, gas):
    """δ_max, contact time, rebound speed by quadrature (the reduction of the module docstring,
    item 2)."""
    r, m = float(ball.radius_m), float(ball.mass_kg)
    k = shell_stiffness(r, float(ball.wall_m), float(ball.youngs_Pa), float(ball.poisson))

    def force(s):
        return k * s + (gas_force(s, r) if gas == "adiabatic" else 0.0)

    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * height_m)

    def compression_work(d):  # (4R/M)∫₀^δ F/(2R − s) ds; u_c(δ) = v0² − this
        return 4.0 * r / m * quad(lambda s: force(s) / (2.0 * r - s), 0.0, d, **QUAD)[0]

    # F ≥ kδ and 4R/(2R − s) ≥ 2 bound δ_max by the linear v0√(M/k).
    d_lin = v0 * math.sqrt(m / k)
    d_max = brentq(
        lambda d: v0**2 - compression_work(d),
        0.5 * d_lin,
        d_lin * (1 + 1e-9),
        xtol=1e-17,
        rtol=1e-15,
    )

    def u_c(d):  # written from δ_max downwards: no cancellation near the turning point
        return 4.0 * r / m * quad(lambda s: force(s) / (2.0 * r - s), d, d_max, **QUAD)[0]

    def u_r(d):
        return (
            4.0
            * r
            / m
            * quad(lambda s: force(s) * (2.0 * r - s), d, d_max, **QUAD)[0]
            / (2.0 * r - d) ** 2
        )

    def integrand(sigma):
        d = d_max * (1.0 - sigma**2)
        return 2.0 * d_max * sigma * (1.0 / math.sqrt(u_c(d)) + 1.0 / math.sqrt(u_r(d)))

    contact_time = quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-12, limit=200)[0]
    v_out_sq = quad(lambda s: force(s) * (2.0 * r - s), 0.0, d_max, **QUAD)[0] / (
        m * r
    )  # the note's v_out²
    return dict(
        max_deflection_m=d_max,
        peak_force_N=force(d_max),
        contact_time_s=contact_time,
        restitution=math.sqrt(v_out_sq) / v0,
        v_out_sq=v_out_sq,
    )


@pytest.fixture(scope="module", params=["adiabatic", "none"])
def balance(request):
    gas = request.param
    ball = rbjax.JIS_RUBBER_BALL
    result = rbjax.simulate(HEIGHTS_M, ball, gas=gas)
    quads = [energy_balance(float(h), ball, gas) for h in HEIGHTS_M]
    expected = {name: np.array([q[name] for q in quads]) for name in quads[0]}
    return gas, result, expected


@pytest.mark.parametrize(
    "quantity", ["contact_time_s", "restitution", "max_deflection_m", "peak_force_N"]
)
def test_energy_balance_quadrature(balance, quantity):
    gas, result, expected = balance
    np.testing.assert_allclose(
        np.asarray(getattr(result, quantity)), expected[quantity], rtol=SOLVER_REL, err_msg=gas
    )


def test_energy_balance_checks_the_reference_too(balance):
    gas, _, expected = balance
    for i, h in enumerate(HEIGHTS_M):
        ref = reference_impact(h, rbjax.JIS_RUBBER_BALL, gas=gas)
        assert ref.contact_time_s == pytest.approx(expected["contact_time_s"][i], rel=1e-10)
        assert ref.restitution == pytest.approx(expected["restitution"][i], rel=1e-10)


def test_rebound_speed_formula(balance):
    """v_out² = (1/(MR))∫₀^δmax F(s)(2R − s) ds, with rbjax's restitution e = v_out/v0."""
    _, result, expected = balance
    v_out = np.asarray(result.restitution) * V0
    np.testing.assert_allclose(v_out**2, expected["v_out_sq"], rtol=2 * SOLVER_REL)


def test_restitution_below_one_and_falling_with_height(balance):
    # The flux term dissipates (M/2R)δ̇²·δ̇ during restitution: more at higher impact speed.
    _, result, _ = balance
    e = np.asarray(result.restitution)
    assert np.all(e < 1.0) and np.all(e > 0.5)
    assert np.all(np.diff(e) < 0.0)

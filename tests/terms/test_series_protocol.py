"""A new element in series with the shell is one class: ``ToyDashpot`` below is defined here
only (a massless dashpot in series with the shell, ẇ = −φ F_c: a fluidity φ of its own), and
with no edit to the library it simulates (against an independent scipy reference, written
here), is refused by name by the energy balance, is fitted through the public API (records
from that reference: the fit must recover φ), is held off in a shared structure, and round-trips
through parameter files.

The reference is not the formulation rbjax solves: rbjax carries δ̇ as a state and solves for
δ̈ in closed form (ẅ = −φ dF_c/dt); here the state is (X, Ẋ, w), all downward positive:

    δ = X + w,   ẇ = −φ F_c(δ),   δ̇ = Ẋ + ẇ,
    M(1 − δ/2R) Ẍ = −F_c(δ) + (M/2R) δ̇² H(−δ̇),
    X(0) = w(0) = 0,  Ẋ(0) = √(2 g h_D),

with F_c = F_B + F_G (the paper's elastic model, §2). Contact ends at the first return of δ to
0 after its maximum; restitution M(1 − δ_end/2R)(−Ẋ_end)/(M v0).
"""

from __future__ import annotations

import math
from typing import ClassVar

import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal
from scipy.integrate import solve_ivp

import rbjax
from rbjax import JIS_RUBBER_BALL, Model, Parameter
from rbjax.data import Recording
from rbjax.fit import prepare_data
from rbjax.terms import SERIES_ELEMENTS, AbstractSeriesElement, structure_model
from rbjax.terms.serialize import load_params, model_to_dict, save_params

from scipy_reference import ball_parameters, gas_force, shell_stiffness
from scipy_series_reference import SeriesReference
from synthetic_records import CUTOFF_HZ, NOISE_N, RATE_HZ, SOS, sampled_force


class ToyDashpot(AbstractSeriesElement):
    """A massless dashpot in series with the shell: ẇ = −φ F_c (φ = 1/c, 0: rigid, off)."""

    toy_fluidity_m_per_Ns: float
    name = "toy-dashpot"  # registers the element: model name, parameter files
    num_states = 1
    state_names = ("w",)
    massless = True
    PARAMETERS: ClassVar = {
        "toy_fluidity_m_per_Ns": Parameter(
            "m/(N s)", lower=0.0, lower_open=False, transform="log", description="toy φ"
        )
    }

    def velocity_m_per_s(self, states, contact_force_N):
        return -self.toy_fluidity_m_per_Ns * contact_force_N

    def rates(self, states, contact_force_N, ball):
        return self.velocity_m_per_s(states, contact_force_N)[None]

    def acceleration_m_per_s2(self, states, rates):
        return jnp.zeros_like(rates[0])  # ẅ = −φ dF_c/dt, all of it through the weight

    def force_rate_weight(self):
        return self.toy_fluidity_m_per_Ns

    def recontact_horizon_s(self):
        return 0.0  # no time scale of its own

    def free_change_m(self, states, times_s):
        return jnp.zeros_like(times_s)  # a dashpot without force stays where it is

    @classmethod
    def start(cls, stiffness_N_per_m, mass_kg, restitution, contact_time_s, speed_m_per_s):
        return {"toy_fluidity_m_per_Ns": 3e-5}


BALL = JIS_RUBBER_BALL.replace(youngs_Pa=1.9e6)
FLUIDITY = 1e-4
HEIGHTS = (0.2, 0.8, 1.6)
STANDARD_GRAVITY = 9.80665


def reference_toy_impact(height_m, ball, fluidity, rtol=1e-12):
    """The impact with the toy dashpot in series (module docstring), by scipy."""
    radius, wall, mass, youngs, poisson = ball_parameters(ball)
    k = shell_stiffness(radius, wall, youngs, poisson)
    flux = mass / (2.0 * radius)
    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * height_m)

    def shell(y):
        d = y[0] + y[2]
        force = k * d + gas_force(d, radius)
        w_rate = -fluidity * force
        return d, y[1] + w_rate, w_rate, force

    def rhs(t, y):
        d, dd, w_rate, force = shell(y)
        thrust = flux * dd**2 if dd < 0.0 else 0.0
        return np.array([y[1], (thrust - force) / (mass * (1.0 - d / (2.0 * radius))), w_rate])

    t_scale = math.pi * math.sqrt(mass / k)
    d_scale = v0 * t_scale / math.pi
    kw = dict(
        method="DOP853",
        rtol=rtol,
        atol=np.array([d_scale, v0, d_scale]) * rtol * 1e-3,
        dense_output=True,
        max_step=t_scale / 50.0,
    )

    def first_max(t, y):
        return shell(y)[1]

    def back_to_zero(t, y):
        return (y[0] + y[2]) / d_scale

    first_max.terminal, first_max.direction = True, -1.0
    back_to_zero.terminal, back_to_zero.direction = True, -1.0
    s1 = solve_ivp(rhs, (0.0, 50 * t_scale), np.array([0.0, v0, 0.0]), events=[first_max], **kw)
    t1 = s1.t[-1]
    s2 = solve_ivp(rhs, (t1, t1 + 50 * t_scale), s1.y[:, -1], events=[back_to_zero], **kw)
    assert s1.status == 1 and s2.status == 1
    y2 = s2.y[:, -1]
    restitution = (1.0 - (y2[0] + y2[2]) / (2.0 * radius)) * (-y2[1]) / v0
    solutions = [(t1, s1.sol), (s2.t[-1], s2.sol)]  # the force read as the series reference's
    return SeriesReference(
        height_m, float(s2.t[-1]), 0.0, float(restitution), solutions, lambda y: shell(y)[3]
    )


def _model(fluidity=FLUIDITY):
    return Model(series_elements=ToyDashpot(fluidity))


def test_it_is_registered_named_and_walked_by_the_model():
    assert SERIES_ELEMENTS["toy-dashpot"] is ToyDashpot
    model = _model()
    assert model.name == "paper+toy-dashpot" and model.coupled
    assert model.internal_state_names == ("toy-dashpot:w",)
    assert "toy_fluidity_m_per_Ns" in rbjax.parameter_names(1.0, BALL, model)
    assert "toy-dashpot" in model.coupling
    with pytest.raises(ValueError, match=r"toy_fluidity_m_per_Ns=-1.0 .*valid range \[0, inf\)"):
        ToyDashpot(-1.0)
    with pytest.raises(ValueError, match="each element may appear once"):
        Model(series_elements=(ToyDashpot(1e-4), ToyDashpot(2e-4)))


@pytest.mark.parametrize("height_m", [0.2, 1.6])
def test_it_simulates_as_the_scipy_reference(height_m):
    """Contact time and restitution to 1e-8, the floor force at 200 times to 1e-7 of its peak."""
    ref = reference_toy_impact(height_m, BALL, FLUIDITY)
    res = rbjax.simulate(height_m, BALL, _model())
    assert res.path == "ode" and int(res.status) == 0
    assert float(res.contact_time_s) == pytest.approx(ref.contact_time_s, rel=1e-8)
    assert float(res.restitution) == pytest.approx(ref.restitution, rel=1e-8)
    times = np.linspace(0.0, 0.999 * ref.contact_time_s, 200)
    force = np.asarray(rbjax.trajectory(height_m, times, BALL, _model()).force_N)
    peak = np.max(ref.force_N(times))
    assert np.max(np.abs(force - ref.force_N(times))) <= 1e-7 * peak
    assert float(res.peak_force_N) == pytest.approx(peak, rel=1e-4)  # the grid's maximum
    # the element matters: the elastic model rebounds with e ≈ 1, the dashpot takes ~3 %
    assert ref.restitution < 0.99 * float(rbjax.simulate(height_m, BALL).restitution)


def test_held_off_in_a_shared_structure_it_is_the_elastic_model():
    structure = structure_model(Model(), laws=(), stiffening=False, elements=(ToyDashpot,))
    assert structure.name == "paper+toy-dashpot"
    assert float(structure.series_elements[0].toy_fluidity_m_per_Ns) == 0.0
    off, plain = rbjax.simulate(1.0, BALL, structure), rbjax.simulate(1.0, BALL, Model())
    assert float(off.contact_time_s) == pytest.approx(float(plain.contact_time_s), rel=1e-9)
    assert float(off.restitution) == pytest.approx(float(plain.restitution), rel=1e-9)


def test_the_energy_balance_refuses_it_by_name():
    with pytest.raises(ValueError, match="toy-dashpot"):
        rbjax.energy_balance(1.0, BALL, _model())


def test_it_round_trips_through_a_parameter_file(tmp_path):
    model = Model(damping=rbjax.HuntCrossley(0.05), series_elements=ToyDashpot(2.5e-5))
    save_params(tmp_path / "p.json", BALL, model)
    ball, back = load_params(tmp_path / "p.json")
    assert model_to_dict(model)["toy-dashpot"] == {"toy_fluidity_m_per_Ns": 2.5e-5}
    assert back.name == model.name and isinstance(back.series_elements[0], ToyDashpot)
    assert model_to_dict(back) == model_to_dict(model) and ball == BALL


def _records(seed=5):
    """Measured-like records of the reference: the sample holding the first contact takes its
    in-contact fraction, white noise, the measuring chain's Butterworth (synthetic_records)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(0.05 * RATE_HZ)) / RATE_HZ
    out = []
    for h in HEIGHTS:
        ref = reference_toy_impact(h, BALL, FLUIDITY, rtol=1e-11)
        start = 0.010 + rng.uniform(0.0, 1.0 / RATE_HZ)
        force = sampled_force(ref, t - start) + rng.normal(0.0, NOISE_N, t.size)
        out.append(
            Recording(
                source=f"toy_h{int(round(h * 100)):03d}.csv",
                height_m=h,
                rate_Hz=RATE_HZ,
                force_N=scipy.signal.sosfilt(SOS, force),
                lowpass_Hz=CUTOFF_HZ,
            )
        )
    return prepare_data(out)


def test_it_is_fitted_through_the_public_api():
    res = rbjax.fit.fit(_records(), _model(3e-5), progress=False)
    assert res.converged, res.message
    est = res.parameters["toy_fluidity_m_per_Ns"]
    assert est.unit == "m/(N s)"
    assert abs(est.value - FLUIDITY) <= max(3 * est.std, 0.01 * FLUIDITY)  # found: 0.8σ
    assert res.parameters["youngs_Pa"].value == pytest.approx(1.9e6, rel=2e-3)
    assert isinstance(res.model.series_elements[0], ToyDashpot)

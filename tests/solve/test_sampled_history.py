"""Force histories sampled inside a fixed-step solve (``rbjax.solve.sampled``, the default
history path of the rigid-floor models) against the independent scipy reference.

The reference (tests/scipy_reference.py) integrates Eq. 7 with DOP853 at rtol 1e-12 and locates
the end of contact by an event; its dense output gives the force at the samples. The records
here go through ``force_history`` (what ``ImpactResult.history()`` calls) with the reference's
contact times, so the scalar solve is not compiled; one batch of heights per configuration.
"""

from __future__ import annotations

import functools
import importlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import rbjax
from rbjax.solve.sampled import sampled_history
from rbjax.solve.simulate import force_history
from rbjax.spectrum.levels import lfe_octave_dB

from scipy_reference import reference_impact

# the modules (``rbjax.simulate`` the attribute is the function)
sim = importlib.import_module("rbjax.solve.simulate")
BALL = rbjax.JIS_RUBBER_BALL
RATE_Hz = 44_100.0
HEIGHTS = np.array([0.1, 0.8, 1.6])
FORCE_REL = 1e-8  # of the peak force
LFE_dB = 1e-6
CONFIGS = {
    "elastic-gas": dict(gas="adiabatic"),
    "elastic-momentum": dict(gas="adiabatic", blocked_force="momentum"),
    "kelvin-voigt": dict(damping=rbjax.KelvinVoigt(100.0)),
    "hunt-crossley": dict(damping=rbjax.HuntCrossley(0.5)),
    "zener-momentum": dict(damping=rbjax.Zener(0.3, 2e-3), blocked_force="momentum"),
}


@functools.cache
def _case(name):
    refs = [reference_impact(h, BALL, **CONFIGS[name]) for h in HEIGHTS]
    contact = np.array([r.contact_time_s for r in refs])
    history = force_history(
        HEIGHTS,
        BALL,
        rbjax.Model(**CONFIGS[name]),
        rbjax.Solver(),
        rate_Hz=RATE_Hz,
        contact_time_s=contact,
    )
    return refs, history


@pytest.mark.parametrize("name", list(CONFIGS))
def test_force_samples_and_contact_mask_match_reference(name):
    refs, history = _case(name)
    t = np.asarray(history.time_s)
    assert t.shape == (44_100,) and np.asarray(history.status).tolist() == [0] * len(HEIGHTS)
    for i, ref in enumerate(refs):
        force = np.asarray(history.force_N[i])
        err = np.max(np.abs(force - ref.force_N(t))) / ref.peak_force_N
        assert err <= FORCE_REL, (name, HEIGHTS[i], err)
        # the mask: equal but possibly at a sample within round-off of the end of contact
        differ = np.asarray(history.in_contact[i]) != (t < ref.contact_time_s)
        assert np.all(np.abs(t[differ] - ref.contact_time_s) < 1e-9), (name, HEIGHTS[i], t[differ])
        assert np.all(force[t >= ref.contact_time_s + 1e-9] == 0.0)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_octave_lfe_of_the_record_matches_reference(name):
    refs, history = _case(name)
    t = np.asarray(history.time_s)
    got = np.asarray(lfe_octave_dB(history.force_N, RATE_Hz))
    want = np.asarray(lfe_octave_dB(np.stack([r.force_N(t) for r in refs]), RATE_Hz))
    assert np.max(np.abs(got - want)) <= LFE_dB, (name, got - want)


def test_jacfwd_matches_central_differences_of_the_reference():
    """d/dE of Σ F_k² over the samples (Zener with the momentum term: an internal state and the
    flux), jitted, against central differences of the reference."""
    options = CONFIGS["zener-momentum"]
    model = rbjax.Model(**options)
    height, youngs = 1.0, float(BALL.youngs_Pa)
    t = np.arange(1000) / RATE_Hz

    def energy(e):
        return jnp.sum(
            sampled_history(height, BALL.replace(youngs_Pa=e), model, num_samples=t.size).force_N
            ** 2
        )

    got = float(jax.jit(jax.jacfwd(energy))(youngs))
    step = 1e-5 * youngs
    refs = [
        reference_impact(height, BALL.replace(youngs_Pa=e), **options)
        for e in (youngs - step, youngs + step)
    ]
    assert len({int(np.sum(t < r.contact_time_s)) for r in refs}) == 1  # no sample crosses the end
    minus, plus = (np.sum(r.force_N(t) ** 2) for r in refs)
    want = (plus - minus) / (2.0 * step)
    assert got == pytest.approx(want, rel=1e-6)


@pytest.mark.parametrize(
    ("height", "youngs", "options", "samples", "expected"),
    [
        (10.0, 1.6e6, {}, 1500, "deflection_limit"),  # the JIS ball from 10 m: δ_max > 2h
        (
            10.0,
            1e4,
            dict(gas="none", max_deflection_ratio=100.0),
            3000,
            "mass_singularity",
        ),  # δ reaches 2R
        (1.0, 1.6e6, {}, 100, "step_limit"),  # the contact goes on after the last sample
    ],
)
def test_failed_impact_gives_nan_samples_and_its_status(height, youngs, options, samples, expected):
    traj = sampled_history(
        height,
        BALL.replace(youngs_Pa=youngs),
        rbjax.Model(**options),
        num_samples=samples,
        substeps=2,
    )
    assert rbjax.STATUS_NAMES[int(traj.status)] == expected
    for field in ("force_N", "deflection_m", "velocity_m_per_s"):
        assert np.all(np.isnan(np.asarray(getattr(traj, field)))), field
    assert not np.any(np.asarray(traj.in_contact))


def test_deflection_limit_stays_nan_over_the_padded_record():
    # the scalar solve gives NaN for the 10 m drop; its history is NaN over the whole record
    contact = np.array([reference_impact(1.0, BALL).contact_time_s, np.nan])
    history = force_history(
        np.array([1.0, 10.0]),
        BALL,
        rbjax.Model(),
        rbjax.Solver(),
        duration_s=0.05,
        contact_time_s=contact,
    )
    assert np.asarray(history.status).tolist() == [0, rbjax.STATUS_CODES["deflection_limit"]]
    assert np.all(np.isnan(np.asarray(history.force_N[1]))) and np.all(
        np.isfinite(np.asarray(history.force_N[0]))
    )


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"num_samples": 0}, "num_samples"),
        ({"num_samples": 10.5}, "num_samples"),
        ({"num_samples": 10, "substeps": 0}, "substeps"),
        ({"num_samples": 10, "rate_Hz": -1.0}, "rate_Hz"),
        ({"num_samples": 10, "height_m": -0.1}, "height_m"),
        (
            {"num_samples": 10, "model": rbjax.Model(ball_mode=rbjax.BallMode(0.9, 60.0, 1.0))},
            "ball mode",
        ),
        ({"num_samples": 10, "model": rbjax.Model(floor=rbjax.Dashpot(1e4))}, "floor"),
    ],
)
def test_bad_input_gives_a_named_error(kwargs, name):
    kwargs = {"height_m": 1.0, **kwargs}
    with pytest.raises(ValueError, match=name):
        sampled_history(**kwargs)


def test_unknown_history_method_is_a_named_error():
    with pytest.raises(ValueError, match="path='sampled' is not a known option"):
        force_history(1.0, BALL, rbjax.Model(), rbjax.Solver(), path="sampled")


class _Ran(Exception):
    pass


@pytest.mark.parametrize(
    ("model", "solver", "method", "expected"),
    [
        (rbjax.Model(), rbjax.Solver(), "auto", "sampled"),
        (rbjax.Model(damping=rbjax.Zener(0.3, 2e-3)), None, "auto", "sampled"),
        (rbjax.Model(), rbjax.Solver(), "ode", "ode"),
        (
            rbjax.Model(),
            rbjax.Solver(rtol=1e-11),
            "auto",
            "ode",
        ),  # a solver of one's own asks for the ODE
        (rbjax.Model(floor=rbjax.Dashpot(1e4)), rbjax.Solver(), "auto", "ode"),
    ],
)
def test_force_history_path(monkeypatch, model, solver, method, expected):
    def ran(path):
        def fail(*args, **kwargs):
            raise _Ran(path)

        return fail

    monkeypatch.setattr(sim, "sampled_solve", ran("sampled"))  # the name simulate calls
    monkeypatch.setattr(sim, "trajectory", ran("ode"))
    with pytest.raises(_Ran) as info:
        force_history(1.0, BALL, model, solver, contact_time_s=0.02, path=method)
    assert info.value.args == (expected,)

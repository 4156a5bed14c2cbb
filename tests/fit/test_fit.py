"""Fitting rubber properties to force histories (rbjax.fit): recovery, Jacobian, identifiability.

Synthetic records are made without rbjax's solver: the scipy solution of paper Eq. 7
(tests/scipy_reference.py) is sampled at 44.1 kHz (the sample holding the first contact
takes the in-contact fraction of its interval, the sampling rule the fit documents), white
noise is added, and the sum goes through scipy.signal's 4th-order Butterworth at 1250 Hz
(the measuring chain); the records then pass through rbjax.data like measured files.

Every fit uses six heights and the default 30 ms window, the shapes of the shipped emulated
set, so that each model structure compiles once per session.
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest
import scipy.signal

import rbjax
from rbjax import JIS_RUBBER_BALL, HuntCrossley, KelvinVoigt, Zener
from rbjax.cli import main
from rbjax.data import examples_dir
from rbjax.fit import FitOptions, fit, fitted_parameter_names, model_histories

from scipy_reference import reference_impact
from synthetic_records import (
    HEIGHTS_M,
    NOISE_N,
    SOS,
    central_difference,
    sampled_force,
    synthetic_data,
)


def filtered_noise_tau():
    """τ = 1 + 2Σρ_k (summed while ρ_k > 0) of white noise through the chain, from its impulse
    response: the value the fit's effective-sample estimate should find on pure noise."""
    h = scipy.signal.sosfilt(SOS, np.r_[1.0, np.zeros(4095)])
    acf = np.correlate(h, h, "full")[h.size - 1 :] / np.dot(h, h)
    tau = 1.0
    for rho in acf[1:]:
        if rho <= 0:
            break
        tau += 2 * rho
    return tau


# (model, blocked force, true parameters); ν = 0.5 everywhere (the value the fit holds).
CASES = {
    "paper": ("paper", "paper", {"youngs_Pa": 1.75e6}),
    "kelvin-voigt": ("kelvin-voigt", "momentum", {"youngs_Pa": 1.9e6, "damping_Ns_per_m": 40.0}),
    "hunt-crossley": ("hunt-crossley", "momentum", {"youngs_Pa": 1.63e6, "alpha_s_per_m": 0.05}),
    "zener": (
        "zener",
        "momentum",
        {"youngs_Pa": 1.5e6, "stiffness_ratio": 0.7, "relaxation_time_s": 1.7e-3},
    ),
}


def damping_of(model, params):
    if model == "kelvin-voigt":
        return KelvinVoigt(params["damping_Ns_per_m"])
    if model == "hunt-crossley":
        return HuntCrossley(params["alpha_s_per_m"])
    if model == "zener":
        return Zener(params["stiffness_ratio"], params["relaxation_time_s"])
    return None


@pytest.fixture(scope="module")
def recovered():
    """Each case fitted from E twice its true value (and the default damping start)."""
    out = {}
    for seed, (key, (model, bf, true)) in enumerate(CASES.items()):
        ball = JIS_RUBBER_BALL.replace(youngs_Pa=true["youngs_Pa"])
        data = synthetic_data(ball, damping_of(model, true), bf, seed)
        res = fit(
            data,
            model,
            blocked_force=bf,
            start={"youngs_Pa": 2.0 * true["youngs_Pa"]},
            progress=False,
        )
        out[key] = (data, res)
    return out


@pytest.mark.parametrize("key", list(CASES))
def test_recovers_known_parameters_within_their_uncertainty(key, recovered):
    model, _, true = CASES[key]
    data, res = recovered[key]
    assert res.converged, res.message
    assert res.parameters["poisson"].fixed and res.parameters["poisson"].value == 0.5
    for name, value in true.items():
        est = res.parameters[name]
        assert not est.fixed and math.isfinite(est.std) and est.std > 0, (name, est)
        assert abs(est.value - value) <= 3 * est.std, (key, name, est, value)
        assert est.ci95[0] < est.value < est.ci95[1]
    # the uncertainty is informative: E to better than 1 %
    assert res.parameters["youngs_Pa"].std < 0.01 * true["youngs_Pa"]
    # the model is right, so the residual is the filtered noise (rms σ·‖h‖ of the chain)
    h = scipy.signal.sosfilt(SOS, np.r_[1.0, np.zeros(4095)])
    noise_rms = NOISE_N * np.linalg.norm(h)
    assert res.residual_rms_N == pytest.approx(noise_rms, rel=0.25)


def test_effective_sample_count_matches_the_filtered_noise(recovered):
    # On model-consistent data the residual is the chain's filtered noise: τ should be the
    # value computed from the filter's impulse response (same definition), within sampling error.
    expected = filtered_noise_tau()
    taus = [res.n_eff_factor for _, res in recovered.values()]
    assert expected > 5  # low-passed noise really is correlated at 44.1 kHz
    for tau in taus:
        assert tau == pytest.approx(expected, rel=0.35)


def test_fitted_ball_and_model_reproduce_the_truth(recovered):
    model, bf, true = CASES["zener"]
    _, res = recovered["zener"]
    assert res.model.name == "zener" and res.model.blocked_force == bf
    assert float(res.model.damping[0].stiffness_ratio) == res.parameters["stiffness_ratio"].value
    assert float(res.ball.youngs_Pa) == res.parameters["youngs_Pa"].value
    d = res.to_dict()
    loaded_ball = rbjax.terms.serialize.ball_from_dict(d["ball"])
    loaded_model = rbjax.terms.serialize.model_from_dict(d["model"])
    assert float(loaded_ball.youngs_Pa) == pytest.approx(true["youngs_Pa"], rel=0.03)
    assert (
        float(loaded_model.damping[0].relaxation_time_s)
        == res.parameters["relaxation_time_s"].value
    )
    json.dumps(d, allow_nan=False)  # strict JSON


def test_jacobian_matches_finite_differences_of_the_scipy_reference():
    # HC with the momentum blocked force at a point off the data: the forward-mode Jacobian of
    # the filtered, sampled floor force against central differences of the independent scipy
    # solution through scipy's filter, for every physical parameter and one onset shift.
    model, bf = "hunt-crossley", "momentum"
    true = {"youngs_Pa": 1.6e6, "poisson": 0.45, "alpha_s_per_m": 0.06}
    data = synthetic_data(JIS_RUBBER_BALL, HuntCrossley(0.05), bf, seed=7)
    shifts = data.onset_s - 3.7e-4
    force, jac, names = model_histories(data, model, true, shifts, blocked_force=bf)
    t = data.time_s

    def reference(params, shift):
        ball = JIS_RUBBER_BALL.replace(youngs_Pa=params["youngs_Pa"], poisson=params["poisson"])
        rows = []
        for k, h in enumerate(HEIGHTS_M):
            ref = reference_impact(
                h, ball, damping=HuntCrossley(params["alpha_s_per_m"]), blocked_force=bf, rtol=1e-12
            )
            rows.append(scipy.signal.sosfilt(SOS, sampled_force(ref, t - shift[k])))
        return np.array(rows)

    base = reference(true, shifts)
    assert np.max(np.abs(force - base)) <= 1e-6 * np.max(np.abs(base))
    for name in ("youngs_Pa", "poisson", "alpha_s_per_m", "shift[2]"):
        i = names.index(name)
        fd = central_difference(reference, true, shifts, name)
        err = np.max(np.abs(jac[..., i] - fd)) / np.max(np.abs(fd))
        assert err < 2e-4, (name, err)


def test_e_and_nu_are_flagged_as_not_separately_identifiable(recovered):
    data, res = recovered["paper"]
    # the Jacobian columns of E and ν are parallel: both act through E/√(1−ν²) only
    _, jac, names = model_histories(
        data, "paper", {"youngs_Pa": 1.7e6, "poisson": 0.3}, data.onset_s - 4e-4
    )
    a, b = jac[..., names.index("youngs_Pa")].ravel(), jac[..., names.index("poisson")].ravel()
    assert abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b)) > 1 - 1e-9
    assert "not separately identifiable" in res.identifiability
    assert "E/√(1−ν²)" in res.identifiability
    # what is fitted is the effective modulus; with ν = 0.5 held it is E/√0.75
    eff = res.parameters["effective_modulus_Pa"]
    assert eff.value == pytest.approx(
        res.parameters["youngs_Pa"].value / math.sqrt(0.75), rel=1e-12
    )


def test_a_prior_on_nu_makes_it_determined_by_the_prior(recovered):
    data, _ = recovered["paper"]
    res = fit(data, "paper", options=FitOptions(poisson_prior=(0.3, 0.05)), progress=False)
    nu = res.parameters["poisson"]
    assert not nu.fixed
    # the data say nothing about ν alone: the posterior is the prior
    assert nu.value == pytest.approx(0.3, abs=0.01)
    assert nu.std == pytest.approx(0.05, rel=0.1)
    # while E/√(1−ν²) is as well determined as with ν held (true value E/√0.75)
    eff = res.parameters["effective_modulus_Pa"]
    assert abs(eff.value - 1.75e6 / math.sqrt(0.75)) <= 3 * eff.std
    assert "prior" in res.identifiability


@pytest.mark.parametrize("optimizer", ["gauss-newton"])
def test_other_optimizers_reach_the_same_minimum(optimizer, recovered):
    data, lm = recovered["paper"]
    res = fit(
        data,
        "paper",
        start={"youngs_Pa": 2.5e6},
        options=FitOptions(optimizer=optimizer, max_steps=60),
        progress=False,
    )
    assert res.converged, res.message
    e = lm.parameters["youngs_Pa"]
    assert abs(res.parameters["youngs_Pa"].value - e.value) <= 0.1 * e.std


def test_max_steps_zero_evaluates_the_start_and_says_so(recovered):
    data, lm = recovered["paper"]
    start = fit(
        data, "paper", start={"youngs_Pa": 2.5e6}, options=FitOptions(max_steps=0), progress=False
    )
    assert not start.converged and "not converged" in start.message
    assert start.residual_rms_N > 2 * lm.residual_rms_N


def test_an_evaluation_with_free_parameters_stays_at_its_point(recovered):
    """The program evaluates by running its optimiser with an infinite tolerance (no second
    copy of the model for evaluating): with every parameter free and far from the optimum, the
    evaluation must still be at the given point: u = 0, no step counted, and the residuals and
    Jacobian those of the evaluation with every parameter held (θ = θ_held there, whatever the
    optimiser does), to the round-off of θ's transform there and back."""
    from rbjax.fit.setup import set_up

    data, _ = recovered["hunt-crossley"]
    setup = set_up(
        data,
        "hunt-crossley",
        blocked_force="momentum",
        gas="adiabatic",
        ball=JIS_RUBBER_BALL,
        fix=None,
        options=FitOptions(),
    )
    problem = setup.problem
    lay = problem.layout
    theta = lay.theta(JIS_RUBBER_BALL.replace(youngs_Pa=2.6e6), setup.candidate, data.onset_s)
    weights = problem.weights(setup.fit_mask)
    n = len(lay.names)
    held = problem.run(theta, np.zeros(n, bool), weights, setup.constants)
    free = problem.run(theta, np.ones(n, bool), weights, setup.constants)
    assert free["steps"] == 0 and np.all(free["u"] == 0) and free["successful"]
    for key in ("r", "jac_theta", "force", "features"):
        scale = np.max(np.abs(held[key]))
        np.testing.assert_allclose(free[key], held[key], rtol=0, atol=1e-9 * scale, err_msg=key)
    # the optimiser would have moved from here: one round from the same point does
    stepped = problem.run(theta, np.ones(n, bool), weights, setup.constants, atol=1e-9)
    assert stepped["steps"] > 0 and stepped["r"] @ stepped["r"] < 0.5 * (held["r"] @ held["r"])


def test_the_histories_reported_are_those_of_the_parameters_reported(recovered):
    """With ``max_steps=0`` the fit reports its start: the E–ν check holds ν at 0.5 after the
    start was evaluated at ν = 0.45, so the start is evaluated again there (the reported
    histories were once those of ν = 0.45, 2 % of the peak away)."""
    data, _ = recovered["hunt-crossley"]
    res = fit(
        data,
        "hunt-crossley",
        blocked_force="momentum",
        options=FitOptions(max_steps=0),
        progress=False,
    )
    assert res.parameters["poisson"].value == 0.5
    values = {n: p.value for n, p in res.parameters.items()}
    force, _, _ = model_histories(
        data, "hunt-crossley", values, res.onset_shift_s, blocked_force="momentum"
    )
    np.testing.assert_allclose(res.predicted_N, force, rtol=0, atol=1e-9 * np.max(force))


def test_e_held_and_nu_fitted_recovers_the_effective_modulus(recovered):
    """E held, ν fitted: ν alone sets E/√(1−ν²); holding E at the value that makes ν = 0.3 give
    the true effective modulus, the fit finds ν = 0.3 and that modulus within their uncertainty."""
    data, _ = recovered["paper"]
    true_eff = CASES["paper"][2]["youngs_Pa"] / math.sqrt(1.0 - 0.5**2)
    held_e = true_eff * math.sqrt(1.0 - 0.3**2)
    res = fit(data, "paper", fix={"youngs_Pa": held_e}, progress=False)
    assert res.converged, res.message
    nu, eff = res.parameters["poisson"], res.parameters["effective_modulus_Pa"]
    assert res.parameters["youngs_Pa"].fixed and not nu.fixed
    assert abs(nu.value - 0.3) <= 3 * nu.std
    assert 0 < eff.std and abs(eff.value - true_eff) <= 3 * eff.std


def test_held_out_heights_are_predicted_not_fitted(recovered):
    data, full = recovered["hunt-crossley"]
    res = fit(
        data,
        "hunt-crossley",
        blocked_force="momentum",
        options=FitOptions(fit_heights=[0.1, 0.4, 1.0, 1.6]),
        start=full,
        progress=False,
    )
    held = [r for r in res.per_height if not r["in_fit"]]
    assert sorted(r["height_m"] for r in held) == [0.2, 0.8]
    # the model is right, so the held-out records are predicted to the noise
    for r in held:
        assert abs(r["error"]["contact_time_pct"]) < 0.3
        assert abs(r["error"]["peak_force_pct"]) < 0.3
        assert r["residual_rms_N"] < 0.5
    assert (
        abs(res.parameters["alpha_s_per_m"].value - 0.05) <= 3 * res.parameters["alpha_s_per_m"].std
    )


def test_bad_input_names_the_parameter():
    data = examples_dir()
    with pytest.raises(ValueError, match="model='maxwell'"):
        fit(data, "maxwell")
    with pytest.raises(ValueError, match="unknown parameter 'beta'"):
        fit(data, "zener", fix={"beta": 1.0})
    with pytest.raises(ValueError, match="poisson=0.7"):
        fit(data, "paper", fix={"poisson": 0.7})
    with pytest.raises(ValueError, match="optimizer='newton'"):
        fit(data, "paper", options=FitOptions(optimizer="newton"))
    with pytest.raises(ValueError, match="hold_poisson='0.5' is outside"):
        FitOptions(hold_poisson="0.5")
    assert fitted_parameter_names("zener+stiffening") == (
        "youngs_Pa",
        "poisson",
        "stiffness_ratio",
        "relaxation_time_s",
        "beta",
    )


# --------------------------------------------------------------------------------------------
# command line


def run_cli(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture
def program_cache(tmp_path, monkeypatch):
    """The command line's caches in a temporary folder (restored afterwards)."""
    import jax

    from rbjax.fit import program_store

    before = jax.config.jax_compilation_cache_dir
    jax.config.update(
        "jax_compilation_cache_dir", None
    )  # the test session's cache (conftest.py): the CLI keeps a chosen one
    monkeypatch.setenv("RBJAX_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(program_store, "_LOADED", {})
    yield tmp_path / "cache"
    jax.config.update("jax_compilation_cache_dir", before)


def test_cli_fit_json_and_outputs(tmp_path, program_cache, monkeypatch):
    code, out, err = run_cli(
        ["fit", str(examples_dir()), "--model", "paper", "--json", "--out", str(tmp_path)]
    )
    assert code == 0, err
    # the fit's program was exported beside the compilation cache; a new process reads it back
    # instead of tracing the model again, and gets the same fit
    assert len(list((program_cache / "rbjax-programs").glob("*.jaxexport"))) == 1
    from rbjax.fit import program, program_store

    monkeypatch.setattr(program_store, "_LOADED", {})
    monkeypatch.setattr(
        program, "compiled", lambda *a: pytest.fail("traced again despite the stored program")
    )
    code2, out2, err2 = run_cli(["fit", str(examples_dir()), "--model", "paper", "--json"])
    assert code2 == 0, err2
    assert json.loads(out2)["parameters"] == json.loads(out)["parameters"]
    d = json.loads(out)
    for key in ("model_name", "ball", "model", "parameters", "per_height", "converged", "message"):
        assert key in d
    assert d["model_name"] == "paper" and d["converged"]
    assert len(d["per_height"]) == 6
    assert {"measured", "fitted", "error", "residual_rms_N"} <= set(d["per_height"][0])
    assert d["parameters"]["poisson"]["fixed"]
    # progress: a line per evaluation on stderr, nothing but JSON on stdout
    assert err.count("fit paper/paper round") >= 2
    # the written files: the same JSON (loadable as --params) and the plots
    ball, model = rbjax.terms.serialize.load_params(tmp_path / "fit.json")
    assert float(ball.youngs_Pa) == d["parameters"]["youngs_Pa"]["value"]
    assert model.damping == () and model.blocked_force == "paper"
    for name in ("histories.png", "lfe_bands.png", "correlations.png"):
        assert (tmp_path / name).stat().st_size > 1000


@pytest.mark.parametrize(
    "argv, message",
    [
        (["fit", "DIR", "--model", "paper", "--fix", "spring=3"], "unknown parameter 'spring'"),
        (["fit", "DIR", "--model", "maxwell"], "model='maxwell'"),
        (["fit", "DIR", "--model", "paper", "--fix", "poisson"], "expected NAME=VALUE"),
        (["fit", "DIR", "--fix", "stiffness_ratio=1"], "without --model"),
        (["fit", "EMPTY", "--model", "paper"], "no recording (*.csv, *.npy, *.wav, *.mat"),
        (["select", "EMPTY", "--candidates", "paper,maxwell"], "maxwell"),
    ],
)
def test_cli_bad_input_is_one_line_exit_2(argv, message, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    argv = [str(examples_dir()) if a == "DIR" else str(empty) if a == "EMPTY" else a for a in argv]
    code, out, err = run_cli(argv)
    assert code == 2
    assert err.startswith("rbjax: error:") and err.count("\n") == 1, err
    assert message in err
    assert out == ""

"""Sharded batched sweeps: padding, agreement with the scipy reference (values on every path,
L_FE, exact derivatives against central differences), 4 forced CPU devices against 1 (in a
subprocess), configuration files and the ``rbjax sweep`` command."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
import tomllib
import types
from importlib import resources

import jax
import numpy as np
import pytest

import rbjax
from rbjax.cli import main
from rbjax.solve.batch import evaluate_jacobian, evaluation_paths
from rbjax.spectrum.levels import lfe_octave_dB
from rbjax.studies.sweep import evaluate, load_config, parameter_names, run_sweep, sharded_map

import scipy_reference as ref


def _double_plus(batch, shared):
    return {"y": 2.0 * batch["a"] + shared, "n": batch["b"] * 0 + batch["a"].shape[0]}


def test_sharded_map_pads_and_trims():
    a = np.arange(10.0)
    out = sharded_map(_double_plus, {"a": a, "b": a}, np.float64(0.5), chunk_size=4)
    np.testing.assert_array_equal(out["y"], 2.0 * a + 0.5)
    np.testing.assert_array_equal(out["n"], 4.0)  # every call sees the same chunk shape
    with pytest.raises(ValueError, match="leading axis"):
        sharded_map(_double_plus, {"a": a, "b": a[:3]}, 0.0)


RATE = 44_100.0
FIELDS = ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")


def reference(height_m, damping=None, **changes):
    """Scalar outputs and L_FE per octave band of the scipy reference (44.1 kHz × 1 s record)."""
    ball = types.SimpleNamespace(
        **{k: float(getattr(rbjax.JIS_RUBBER_BALL, k)) for k in FIELDS} | changes
    )
    r = ref.reference_impact(height_m, ball, damping=damping)
    n = int(math.ceil(r.contact_time_s * RATE)) + 2
    force = np.zeros(int(RATE))
    force[:n] = r.force_N(np.arange(n) / RATE)
    return {
        "contact_time_s": r.contact_time_s,
        "peak_force_N": r.peak_force_N,
        "restitution": r.restitution,
        "max_deflection_m": r.max_deflection_m,
    } | dict(zip(rbjax.solve.batch.lfe_output_names(), np.asarray(lfe_octave_dB(force, RATE))))


SAMPLES = {
    "YOUNGS_PA": np.array([1.3e6, 1.9e6, 1.6e6]),
    "mass_kg": np.array([2.45, 2.55, 2.5]),
    "height_m": np.array([0.5, 1.2, 1.0]),
}


@pytest.fixture(scope="module")
def references():
    return [
        reference(
            SAMPLES["height_m"][i], youngs_Pa=SAMPLES["YOUNGS_PA"][i], mass_kg=SAMPLES["mass_kg"][i]
        )
        for i in range(3)
    ]


def test_evaluate_matches_scipy_reference(references):
    assert evaluation_paths(rbjax.Model()) == ("quadrature", "sampled")
    assert evaluation_paths(rbjax.Model(damping=rbjax.KelvinVoigt(5.0))) == ("angle", "sampled")
    assert evaluation_paths(rbjax.Model(), rbjax.Solver()) == ("ode", "ode")
    for method, lfe in (("auto", True), ("ode", False)):  # quadrature + sampled history; the ODE
        out = evaluate(
            SAMPLES, chunk_size=64, method=method, lfe=lfe
        )  # chunk 64 as in the CLI test: one compile
        assert out["status"].tolist() == [0, 0, 0]
        for i, r in enumerate(references):
            for k in [
                *rbjax.solve.batch.SCALAR_OUTPUTS,
                *(rbjax.solve.batch.lfe_output_names() if lfe else ()),
            ]:
                np.testing.assert_allclose(
                    out[k][i], r[k], rtol=1e-7, err_msg=f"{k} method={method}"
                )


def test_exact_derivatives_match_central_differences_of_the_reference(references):
    wrt = ("height_m", "youngs_Pa", "mass_kg")
    values, jac = evaluate_jacobian(SAMPLES, wrt, lfe=True, chunk_size=64)
    names = [*rbjax.solve.batch.SCALAR_OUTPUTS, *rbjax.solve.batch.lfe_output_names()]
    i, r = 2, references[2]
    for k in names:
        np.testing.assert_allclose(values[k][i], r[k], rtol=1e-7, err_msg=k)
    base = {"height_m": 1.0, "youngs_Pa": 1.6e6, "mass_kg": 2.5}
    for j, p in enumerate(wrt):
        step = 1e-5 * base[p]
        up, down = ({**base, p: base[p] + s} for s in (step, -step))
        fd_up = reference(up.pop("height_m"), **up)
        fd_down = reference(down.pop("height_m"), **down)
        for k in names:
            fd = (fd_up[k] - fd_down[k]) / (2 * step)
            np.testing.assert_allclose(
                jac[k][i, j], fd, rtol=2e-4, atol=1e-9 * abs(r[k]) / base[p], err_msg=f"d{k}/d{p}"
            )


def test_flagged_rows_are_computed_again_in_place():
    from rbjax.solve.batch import _redo

    out = {"y": np.zeros(10), "n": np.zeros(10)}
    batch = {"a": np.arange(10.0), "b": np.arange(10.0)}
    _redo(out, np.array([1, 4, 7]), _double_plus, batch, np.float64(0.5), sharded_map)
    np.testing.assert_array_equal(out["y"], [0, 2.5, 0, 0, 8.5, 0, 0, 14.5, 0, 0])
    # padded to a power of two, at least FALLBACK_MIN_BATCH (one compiled shape for few rows)
    np.testing.assert_array_equal(out["n"][[1, 4, 7]], 64.0)
    many = {"y": np.zeros(200), "n": np.zeros(200)}
    rows = np.arange(0, 200, 2)  # 100 rows: the next power of two
    _redo(
        many,
        rows,
        _double_plus,
        {"a": np.arange(200.0), "b": np.arange(200.0)},
        np.float64(0.5),
        sharded_map,
    )
    np.testing.assert_array_equal(many["y"][rows], 2.0 * rows + 0.5)
    np.testing.assert_array_equal(many["n"][rows], 128.0)


def test_evaluate_rejects_bad_samples():
    with pytest.raises(ValueError, match="poisson"):
        evaluate({"poisson": np.array([0.4, 0.6])})
    with pytest.raises(ValueError, match="same length"):
        evaluate({"mass_kg": np.ones(3), "height_m": np.ones(2)})
    with pytest.raises(ValueError, match="not known"):
        evaluate({"colour": np.ones(2)})
    assert "damping_Ns_per_m" in parameter_names(rbjax.Model(damping=rbjax.KelvinVoigt(1.0)))


SHARDED_SCRIPT = textwrap.dedent(
    """
    import sys
    import jax, numpy as np
    from rbjax.studies.sweep import evaluate
    assert jax.device_count() == 4, jax.devices()
    samples = dict(np.load(sys.argv[1]))
    out = evaluate(samples, chunk_size=16)  # steps of 4 devices x 16 impacts
    np.savez(sys.argv[2], **out)
    """
)


def test_sharded_sweep_on_four_cpu_devices_equals_one_device(tmp_path):
    rng = np.random.default_rng(0)
    n = 150  # not a multiple of the 64-impact step: the last step is padded
    samples = {
        "youngs_Pa": rng.uniform(1.2e6, 2e6, n),
        "mass_kg": rng.uniform(2.4, 2.6, n),
        "height_m": rng.uniform(0.3, 1.6, n),
    }
    np.savez(tmp_path / "samples.npz", **samples)
    script = tmp_path / "sharded.py"
    script.write_text(SHARDED_SCRIPT)
    env = dict(
        os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=4", JAX_PLATFORMS="cpu"
    )
    proc = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "samples.npz"), str(tmp_path / "four.npz")],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    four = np.load(tmp_path / "four.npz")
    one = evaluate(samples, chunk_size=64)  # this process: one CPU device
    assert jax.device_count() == 1
    assert four["status"].tolist() == one["status"].tolist() == [0] * n
    for k in ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m"):
        # the partitioned program is compiled apart from the one-device one: equal to the last bits
        np.testing.assert_allclose(four[k], one[k], rtol=1e-14, atol=0, err_msg=k)


def test_shipped_example_configs():
    folder = resources.files("rbjax") / "examples" / "sweeps"
    configs = {p.name: load_config(p) for p in folder.iterdir() if p.name.endswith(".toml")}
    assert set(configs) >= {"sobol.toml", "morris.toml", "conformance.toml"}
    sobol = configs["sobol.toml"]
    assert sobol["kind"] == "sobol" and not sobol["sobol"]["second_order"]
    assert sobol["sobol"]["n_base"] * (len(sobol["ranges"]) + 2) >= 100_000
    assert configs["conformance.toml"]["kind"] == "conformance"


def test_bad_configs_are_rejected(tmp_path):
    with pytest.raises(ValueError, match="kind"):
        run_sweep({"kind": "grid"})
    with pytest.raises(ValueError, match="unknown keys.*colour"):
        run_sweep({"kind": "sobol", "colour": 1})
    with pytest.raises(ValueError, match="ranges"):
        run_sweep({"kind": "sobol"})
    ranges = {"youngs_Pa": [1.2e6, 2e6]}
    with pytest.raises(ValueError, match=r"\[sobol\] has unknown keys \['n_levels'\].*n_base"):
        run_sweep({"kind": "sobol", "ranges": ranges, "sobol": {"n_levels": 4}})
    with pytest.raises(ValueError, match="n_base=1000 must be a power of two"):
        run_sweep({"kind": "sobol", "ranges": ranges, "sobol": {"n_base": 1000}})
    with pytest.raises(
        ValueError, match="kind='hdmr'.*sobol, morris, fast, pawn, dgsm, conformance"
    ):
        run_sweep({"kind": "hdmr", "ranges": ranges})
    bad = tmp_path / "bad.toml"
    bad.write_text("kind = \n")
    with pytest.raises(ValueError, match="cannot read TOML"):
        load_config(bad)


def test_cli_sweep_sobol_writes_json_and_samples(tmp_path, capsys):
    config = tmp_path / "study.toml"
    config.write_text(
        textwrap.dedent(
            """
            kind = "sobol"
            seed = 2
            outputs = ["contact_time_s", "restitution"]
            chunk_size = 64
            [sobol]
            n_base = 64
            second_order = false
            n_bootstrap = 20
            [ranges]
            youngs_pa = [1.2e6, 2.0e6]
            height_m = [0.5, 1.5]
            """
        )
    )
    out = tmp_path / "study.json"
    assert main(["sweep", str(config), "--out", str(out), "--no-progress"]) == 0
    assert "Sobol indices" in capsys.readouterr().out
    summary = json.loads(out.read_text())
    assert summary["config"] == tomllib.loads(config.read_text())
    assert summary["n_evaluations"] == 64 * 4
    assert summary["parameters"] == ["youngs_Pa", "height_m"]
    assert set(summary["outputs"]) == {"contact_time_s", "restitution"}
    assert summary["outputs"]["contact_time_s"]["driver"] == "youngs_Pa"  # t_c ∝ (M/k)^½ nearly
    samples = np.load(tmp_path / "study.samples.npz")
    assert samples["block"].shape == (256,)
    # every saved row is the impact of its saved inputs (scipy reference)
    for i in (0, 100, 255):
        r = ref.reference_impact(
            samples["height_m"][i],
            types.SimpleNamespace(
                **{
                    k: float(getattr(rbjax.JIS_RUBBER_BALL, k))
                    for k in ("radius_m", "wall_m", "mass_kg", "poisson")
                },
                youngs_Pa=samples["youngs_Pa"][i],
            ),
        )
        np.testing.assert_allclose(samples["contact_time_s"][i], r.contact_time_s, rtol=1e-7)
        np.testing.assert_allclose(samples["restitution"][i], r.restitution, rtol=1e-7)


def test_cli_sweep_bad_config_is_one_line_error(tmp_path, capsys):
    config = tmp_path / "bad.toml"
    config.write_text(
        'kind = "conformance"\n[distributions]\nmass_kg = {kind = "normal", mean = 2.5}\n'
    )
    assert main(["sweep", str(config), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and err[-1].startswith("rbjax: error:") and "mass_kg" in err[-1]


def test_dgsm_sweep_of_the_impact_model_exact_gradients_against_salib_finite_differences():
    config = {
        "kind": "dgsm",
        "outputs": ["contact_time_s", "peak_force_N", "lfe_63_dB"],
        "chunk_size": 64,
        "dgsm": {"n_base": 3, "delta": 1e-5},
        "ranges": {"height_m": [0.99, 1.01], "youngs_Pa": [1.3e6, 1.9e6], "mass_kg": [2.45, 2.55]},
    }
    res = run_sweep(config)
    assert res.n_evaluations == 3 * 4 and res.n_valid == {o: 3 for o in res.outputs}
    for o in res.outputs:  # one-sided differences of relative step 1e-5: ~1e-5 relative
        np.testing.assert_allclose(res.nu_fd[o], res.nu[o], rtol=1e-3, err_msg=o)
        np.testing.assert_allclose(res.total_bound_fd[o], res.total_bound[o], rtol=1e-3, err_msg=o)
    assert res.driver("contact_time_s") == "youngs_Pa"

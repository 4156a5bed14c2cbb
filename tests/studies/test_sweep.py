"""Sharded batched sweeps: padding, agreement with the scipy reference (values on every path,
L_FE, exact derivatives against central differences), 4 forced CPU devices against 1 (in a
subprocess), configuration files and the ``rbjax sweep`` command; a sweep in chunks on local
worker processes or a given executor, and in parts (``--shard``, ``--merge``), against the
in-process one (the Dask cluster: test_cluster.py)."""

from __future__ import annotations

import concurrent.futures as cf
import json
import math
import os
import re
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
from rbjax.solve.batch import evaluate, evaluate_jacobian, evaluation_paths
from rbjax.solve.devices import device_map
from rbjax.spectrum.levels import lfe_octave_dB
from rbjax.studies.parallel.executors import TaskError
from rbjax.studies.sweeps.parts import part_rows
from rbjax.studies.sweeps.sweep import load_config, run_sweep

import scipy_reference as ref

CHUNKS_OF_4 = rbjax.Parallel(chunk_size=4)


def _double_plus(batch, shared):
    return {"y": 2.0 * batch["a"] + shared, "n": batch["b"] * 0 + batch["a"].shape[0]}


def test_device_map_pads_and_trims():
    a = np.arange(10.0)
    out = device_map(_double_plus, {"a": a, "b": a}, np.float64(0.5), parallel=CHUNKS_OF_4)
    np.testing.assert_array_equal(out["y"], 2.0 * a + 0.5)
    np.testing.assert_array_equal(out["n"], 4.0)  # every call sees the same chunk shape
    with pytest.raises(ValueError, match="leading axis"):
        device_map(_double_plus, {"a": a, "b": a[:3]}, 0.0, parallel=CHUNKS_OF_4)


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
        spec = rbjax.EvaluationSpec(path=method)
        chunks = rbjax.Parallel(chunk_size=64)  # as in the CLI test: one compile
        out = evaluate(SAMPLES, lfe=lfe, evaluation=spec, parallel=chunks)
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
    values, jac = evaluate_jacobian(SAMPLES, wrt, lfe=True, parallel=rbjax.Parallel(chunk_size=64))
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
    _redo(out, np.array([1, 4, 7]), _double_plus, batch, np.float64(0.5), device_map)
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
        device_map,
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
    assert "damping_Ns_per_m" in rbjax.parameter_names(
        model=rbjax.Model(damping=rbjax.KelvinVoigt(1.0))
    )


SHARDED_SCRIPT = textwrap.dedent(
    """
    import sys
    import jax, numpy as np
    from rbjax import EvaluationSpec, Parallel
    from rbjax.solve.batch import evaluate
    assert jax.device_count() == 4, jax.devices()
    samples = dict(np.load(sys.argv[1]))
    out = {}
    for method in ("quadrature", "ode"):  # chunks of 16 impacts, split over the 4 devices
        run = evaluate(
            samples, evaluation=EvaluationSpec(path=method), parallel=Parallel(chunk_size=16)
        )
        out.update({f"{method}:{k}": v for k, v in run.items()})
    np.savez(sys.argv[2], **out)
    """
)


@pytest.mark.xla_smoke  # one program against its split over devices (as test_devices.py)
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
    assert jax.device_count() == 1
    # both paths: the quadrature (what a sweep of this elastic model runs by default) and the
    # diffrax ODE (a sweep with a solver, a ball mode or a floor), each against this process
    for method in ("quadrature", "ode"):
        # this process: one CPU device
        spec, chunks = rbjax.EvaluationSpec(path=method), rbjax.Parallel(chunk_size=64)
        one = evaluate(samples, evaluation=spec, parallel=chunks)
        assert four[f"{method}:status"].tolist() == one["status"].tolist() == [0] * n, method
        for k in ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m"):
            # the partitioned program is compiled apart from the one-device one: equal to the
            # last bits
            np.testing.assert_allclose(
                four[f"{method}:{k}"], one[k], rtol=1e-14, atol=0, err_msg=f"{method} {k}"
            )


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


# ----------------------------------------------------------------------------------------------
# The evaluation in chunks (worker processes, an executor) and in parts (job arrays).

#: 64 × (2 + 2) = 256 elastic impacts with L_FE, chunks of 64 as the tests above (one compile).
CHUNKED = {
    "kind": "sobol",
    "seed": 5,
    "outputs": ["contact_time_s", "restitution", "lfe_125_dB"],
    "chunk_size": 64,
    "sobol": {"n_base": 64, "second_order": False, "n_bootstrap": 20},
    "ranges": {"youngs_Pa": [1.2e6, 2.0e6], "height_m": [0.5, 1.5]},
}


@pytest.fixture(scope="module")
def in_process():
    return run_sweep(CHUNKED)


def _same_samples(result, reference, rtol=1e-12):
    assert set(result.samples) == set(reference.samples)
    for k, v in reference.samples.items():
        np.testing.assert_allclose(result.samples[k], v, rtol=rtol, atol=0, err_msg=k)


def _same_summary(a, b, path="summary", rtol=1e-12):
    """Two JSON-like summaries equal, their numbers to ``rtol`` (default 1e-12: a sharded
    program's rounding; 0: bit for bit, NaN where NaN)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), path
        for k in a:
            _same_summary(a[k], b[k], f"{path}.{k}", rtol)
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same_summary(x, y, f"{path}[{i}]", rtol)
    elif isinstance(a, float) and not isinstance(b, str):
        np.testing.assert_allclose(b, a, rtol=rtol, atol=0, err_msg=path)
    else:
        assert a == b, path


def test_parts_cover_the_rows_once():
    for n in (0, 1, 7, 100):
        for parts in (1, 3, 8):
            spans = [part_rows(n, i, parts) for i in range(1, parts + 1)]
            assert spans[0][0] == 0 and spans[-1][1] == n
            assert all(b == c for (_, b), (c, _) in zip(spans, spans[1:]))
            assert max(b - a for a, b in spans) - min(b - a for a, b in spans) <= 1


def test_a_sweep_on_local_worker_processes_equals_the_in_process_sweep(in_process):
    # 256 rows in chunks of 62 + the rows of the shortest and longest contact: 5 tasks, after a
    # first pass of contact times (L_FE)
    result = run_sweep(CHUNKED, parallel=rbjax.Parallel(workers=2))
    _same_samples(result, in_process)
    _same_summary(result.to_dict(), in_process.to_dict())
    with pytest.raises(ValueError, match="workers=0 is outside the valid range"):
        rbjax.Parallel(workers=0)
    with pytest.raises(ValueError, match="parallel=2 must be an rbjax Parallel"):
        run_sweep(CHUNKED, parallel=2)


class _FailingExecutor(cf.ThreadPoolExecutor):
    """Runs the tasks on a thread; the third task raises."""

    def __init__(self):
        super().__init__(max_workers=1)
        self.submitted = 0

    def submit(self, fn, /, *args, **kwargs):
        self.submitted += 1
        if self.submitted == 3:
            return super().submit(_broken_disk)
        return super().submit(fn, *args, **kwargs)


def _broken_disk():
    raise OSError("the worker's disk is full")


def test_a_failed_chunk_is_named_with_its_rows_and_no_result_comes_back():
    with _FailingExecutor() as executor, pytest.raises(TaskError) as caught:
        run_sweep(
            {**CHUNKED, "outputs": ["contact_time_s"]}, parallel=rbjax.Parallel(executor=executor)
        )
    message = str(caught.value)
    assert "OSError: the worker's disk is full" in message
    assert re.search(r"rows \d+–\d+ of 256 \(first: youngs_Pa=[\d.e+]+, height_m=[\d.]+\)", message)


def test_a_sweep_in_parts_merges_to_the_single_run(tmp_path, capsys, in_process):
    config = tmp_path / "study.toml"
    config.write_text(_toml(CHUNKED))
    parts = [tmp_path / f"part-{i}.npz" for i in (1, 2, 3)]
    for i, part in enumerate(parts, 1):
        argv = ["sweep", str(config), "--shard", f"{i}/3", "--out", str(part), "--workers", "1"]
        assert main([*argv, "--no-progress"]) == 0
    out = tmp_path / "merged.json"
    merge = ["sweep", str(config), "--merge", *map(str, parts), "--out", str(out), "--no-progress"]
    capsys.readouterr()
    assert main([*merge, "--json"]) == 0
    merged = json.loads(capsys.readouterr().out)
    assert merged == json.loads(out.read_text())
    assert merged["n_evaluations"] == 256 and merged["config"] == CHUNKED
    # the parts, merged, are the single run bit for bit (every row computed by the same
    # program in a chunk of the same length), its summary and every sample
    summary = {k: v for k, v in merged.items() if k != "config"}
    single = json.loads(rbjax.terms.serialize.to_json(in_process.to_dict()))
    _same_summary(summary, single, rtol=0)
    samples = dict(np.load(tmp_path / "merged.samples.npz"))
    _same_samples(types.SimpleNamespace(samples=samples), in_process, rtol=0)
    # and each row's values are the impact of its inputs by rbjax.simulate (the quadrature:
    # measured bit for bit)
    ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=samples["youngs_Pa"])
    direct = rbjax.simulate(samples["height_m"], ball)
    assert direct.path == "quadrature" and np.all(np.asarray(direct.status) == 0)
    for name in ("contact_time_s", "restitution"):
        np.testing.assert_array_equal(samples[name], np.asarray(getattr(direct, name)), name)

    def refused(*paths, config=config):
        code = main(["sweep", str(config), "--merge", *map(str, paths), "--no-progress"])
        assert code == 2
        return capsys.readouterr().err.strip().splitlines()[-1]

    assert "parts 2/3 are missing" in refused(parts[0], parts[2])
    assert "part 1/3 is given twice" in refused(parts[0], parts[0], parts[1], parts[2])
    other = tmp_path / "other.toml"
    other.write_text(_toml({**CHUNKED, "seed": 6}))
    assert "a part of another sweep" in refused(*parts, config=other)
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    assert "is not a part of an rbjax sweep" in refused(tmp_path / "junk.npz")
    argv = ["sweep", str(config), "--shard", "4/3", "--no-progress"]
    assert main(argv) == 2
    assert "--shard '4/3' is not a part" in capsys.readouterr().err
    assert main(["sweep", str(config), "--workers", "0", "--no-progress"]) == 2
    assert "workers=0 is outside the valid range" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["study.toml", "other.toml", "junk.npz", "merged.json", "merged.samples.npz"]
        + [p.name for p in parts]
    )


def test_a_dgsm_sweep_in_parts_merges_to_the_single_run(tmp_path):
    from rbjax.studies.sweeps.parts import merge_parts, run_part

    config = {  # as test_dgsm_sweep_of_the_impact_model... (the same compiled programs)
        "kind": "dgsm",
        "outputs": ["contact_time_s", "peak_force_N", "lfe_63_dB"],
        "chunk_size": 64,
        "dgsm": {"n_base": 3, "delta": 1e-5},
        "ranges": {"height_m": [0.99, 1.01], "youngs_Pa": [1.3e6, 1.9e6], "mass_kg": [2.45, 2.55]},
    }
    single = run_sweep(config)
    paths = [run_part(config, i, 2, tmp_path / f"p{i}.npz") for i in (1, 2)]
    merged = merge_parts(config, paths)
    for o in single.outputs:
        for field in ("nu", "nu_fd", "total_bound", "total_bound_fd"):
            np.testing.assert_allclose(
                getattr(merged, field)[o], getattr(single, field)[o], rtol=1e-12, err_msg=o
            )
    _same_samples(merged, single)


def _toml(config: dict) -> str:
    """A flat TOML text of a sweep configuration (tables of numbers and lists)."""
    lines, tables = [], []
    for k, v in config.items():
        (tables if isinstance(v, dict) else lines).append((k, v))
    text = [f"{k} = {json.dumps(v)}" for k, v in lines]
    for name, table in tables:
        text.append(f"[{name}]")
        text += [f"{k} = {json.dumps(v)}" for k, v in table.items()]
    return "\n".join(text) + "\n"


def test_a_planned_call_without_rows_or_parts_with_other_outputs_are_named(tmp_path, monkeypatch):
    from rbjax.studies.sweeps import parts as sweep_parts

    config = {"kind": "sobol"}  # the plan is given below: nothing is evaluated

    def plan_of(*counts):
        samples = [{"x": np.arange(n, dtype=float)} for n in counts]
        calls = [types.SimpleNamespace(samples=x, gradients=False, settings={}) for x in samples]
        monkeypatch.setattr(sweep_parts, "design_plan", lambda config: calls)
        return calls

    plan_of(0)  # a call of 0 rows: run_part writes no outputs for it
    paths = [sweep_parts.run_part(config, i, 2, tmp_path / f"empty{i}.npz") for i in (1, 2)]
    with pytest.raises(ValueError, match="merge: call 0 of this configuration's design has 0 rows"):
        sweep_parts.merge_parts(config, paths)
    plan = plan_of(2)
    digest = sweep_parts.design_digest(config, plan)
    paths = []
    for i, output in ((1, "y"), (2, "z")):
        meta = {"format": sweep_parts.PART_FORMAT, "digest": digest, "part": i, "parts": 2}
        meta["calls"] = [{"rows": [i - 1, i], "n": 2, "gradients": False}]
        paths.append(tmp_path / f"part{i}.npz")
        np.savez(paths[-1], meta=np.array(json.dumps(meta)), **{f"0/{output}": np.ones(1)})
    with pytest.raises(ValueError, match=r"part2\.npz': call 0's outputs \['z'\] differ from"):
        sweep_parts.merge_parts(config, paths)

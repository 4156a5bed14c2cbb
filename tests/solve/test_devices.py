"""Forward batches split over the local devices (``rbjax.solve.devices``): the one planner of
rows (``rbjax.solve.parallel.cut_rows``: device chunks, tasks, job-array parts), the device plan
(how many devices, chunks of what size), padding and trimming, and ``simulate`` / ``evaluate``
on two CPU devices (a subprocess: the device count is set before JAX starts) against this
process's one device, bit for bit, flagged impacts and the ODE fallback included, with no
collective in the per-device programs, and each case's chunks run on both devices (the device of
each chunk's output, noted in the subprocess)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import jax
import numpy as np
import pytest

import rbjax
from rbjax.solve.batch import evaluate
from rbjax.solve.devices import device_map
from rbjax.solve.parallel import Parallel, cut_rows, default_chunk_size

# one program against the same program elsewhere (chunks, devices), bit for bit: no accuracy claim
# at the optimisation level, so it compiles as a smoke test (tests/conftest.py)
pytestmark = pytest.mark.xla_smoke


def plan(n: int, n_devices: int, chunk_size: int) -> tuple[int, int]:
    """(devices used, rows per chunk) of ``Parallel.device_plan``, whose chunks are cut by
    ``cut_rows`` into pieces of that many rows."""
    used, chunks = Parallel.device_plan(n, n_devices, chunk_size)
    size = chunks[0][1] - chunks[0][0]
    assert chunks == cut_rows(0, n, size=size)
    return used, size


def test_one_planner_cuts_device_chunks_tasks_and_job_array_parts():
    assert cut_rows(0, 10, size=4) == [(0, 4), (4, 8), (8, 10)]
    assert cut_rows(5, 10, size=4) == [(5, 9), (9, 10)]
    assert cut_rows(0, 10, parts=3) == [(0, 3), (3, 6), (6, 10)]  # sizes within one
    assert cut_rows(0, 2, parts=3) == [(0, 0), (0, 1), (1, 2)]  # a part may be empty
    with pytest.raises(ValueError, match="size or parts"):
        cut_rows(0, 10)
    # tasks: whole steps of chunk_size rows, about four tasks a worker, at most eight steps
    assert Parallel(workers=2, chunk_size=64).task_rows(0, 1000) == cut_rows(0, 1000, size=64)
    assert Parallel(workers=1, chunk_size=16).task_rows(0, 10_000) == cut_rows(0, 10_000, size=128)
    assert Parallel(workers=2, chunk_size=64).task_rows(0, 1000, 2) == cut_rows(0, 1000, size=62)


def test_parallel_names_a_bad_field():
    for kwargs, needle in [
        ({"devices": 0}, "devices=0"),
        ({"devices": []}, r"devices=\[\]"),
        ({"chunk_size": 0}, "chunk_size=0 is outside the valid range"),
        ({"chunk_size": 2.5}, "chunk_size=2.5"),
        ({"workers": 0}, "workers=0 is outside the valid range"),
        ({"retries": -1}, "retries=-1"),
        ({"scheduler": "tcp://h:1", "executor": object()}, "not both"),
        ({"batch_fits": True, "workers": 2}, r"batch_fits=True .* workers=2"),
        ({"host": "no"}, "host='no'"),
    ]:
        with pytest.raises(ValueError, match=needle):
            Parallel(**kwargs)
    with pytest.raises(ValueError, match="devices=64: JAX has"):
        Parallel(devices=64).local_devices()
    assert Parallel(devices=1).local_devices() == tuple(jax.local_devices()[:1])
    with pytest.raises(ValueError, match="parallel=2 must be an rbjax Parallel"):
        rbjax.simulate([1.0, 2.0], parallel=2)


def test_plan_cuts_even_aligned_chunks_that_do_not_depend_on_the_devices():
    assert plan(3, 16, 8192) == (1, 3)  # one chunk: one call of its own size, on one device
    assert plan(8192, 16, 8192) == (1, 8192)
    assert plan(10_000, 16, 8192) == (2, 5120)  # two even chunks, a multiple of 128 rows
    assert plan(20_000, 1, 8192) == (1, 6784)  # three chunks, 352 rows of padding in all
    assert plan(10**6, 16, 8192) == (16, 8192)  # every device, 123 chunks in all
    assert plan(8 * 8192, 3, 8192) == (3, 8192)  # whole chunks keep their size
    assert plan(10, 4, 4) == (3, 4)  # at most the requested size; no device without a chunk
    for n in (9001, 123_457, 10**6):  # the chunks are the same for any number of devices
        assert len({plan(n, d, 8192)[1] for d in (1, 2, 3, 16, 64)}) == 1


def test_default_chunk_sizes_on_a_cpu():
    assert jax.local_devices()[0].platform == "cpu"
    assert default_chunk_size("quadrature") == 16384
    assert default_chunk_size("quadrature", width=4) == 4096  # a Jacobian of three parameters
    assert default_chunk_size("ode", width=3) == 128  # rounded down to a power of two
    assert default_chunk_size("sampled", width=100) == 32  # and at least 32
    assert Parallel(chunk_size=100).chunk_rows("ode", jax.local_devices()) == 100


def _chunk_and_sum(rows, shared):
    return {"y": rows["a"] + shared, "n": rows["a"] * 0 + rows["a"].shape[0]}


def test_device_map_pads_the_last_chunk_and_trims_the_padding():
    a = np.arange(10.0)
    out = device_map(_chunk_and_sum, {"a": a}, np.float64(0.5), parallel=Parallel(chunk_size=4))
    np.testing.assert_array_equal(out["y"], a + 0.5)
    np.testing.assert_array_equal(out["n"], 4.0)  # every call sees one shape
    with pytest.raises(ValueError, match="leading batch axis"):
        device_map(_chunk_and_sum, {"a": np.float64(1.0)}, 0.0, parallel=Parallel(chunk_size=4))


def test_a_large_batch_in_chunks_agrees_with_one_call():
    # 20 000 impacts: two chunks of 10 112 (the last one padded) against one call of them all
    # (XLA may round a row differently in a loop of another length: ~1e-16, not bit for bit)
    from rbjax.solve.inputs import as_arrays
    from rbjax.solve.path_runner import fast_program

    heights = np.linspace(0.05, 12.0, 20_000)
    chunked = rbjax.simulate(heights)
    assert chunked.path == "quadrature"
    _, whole = fast_program(
        "quadrature", *as_arrays((heights, rbjax.JIS_RUBBER_BALL, rbjax.Model()))
    )
    np.testing.assert_array_equal(chunked.status, whole.status)
    for name in ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m"):
        np.testing.assert_allclose(
            getattr(chunked, name), getattr(whole, name), rtol=1e-14, err_msg=name
        )
    assert "deflection_limit" in set(chunked.status_name)  # flagged rows stay flagged, NaN
    assert np.all(np.isnan(np.asarray(chunked.contact_time_s)[np.asarray(chunked.status) != 0]))


def test_simulate_inside_jit_is_one_staged_program():
    heights = np.linspace(0.1, 1.6, 20_000)  # two chunks outside jit
    staged = jax.jit(lambda: rbjax.simulate(heights).contact_time_s)()
    np.testing.assert_allclose(staged, rbjax.simulate(heights).contact_time_s, rtol=1e-14)


ZENER = rbjax.Model(damping=rbjax.Zener(0.3, 2e-3), blocked_force="momentum")
#: Chunks of 128 rows (``ALIGN``), so that a few hundred impacts split over two devices as a
#: batch of 10^5 does with the default chunks (the plan does not depend on the chunk size's
#: origin: ``test_plan_cuts_even_aligned_chunks_that_do_not_depend_on_the_devices``).
CHUNK = 128


def _cases():
    """Batches that each split over two devices: the quadrature (with deflection limits), the
    phase-angle path with rows it flags and the ODE solves again, the ODE, and evaluate's
    scalars and L_FE histories."""
    rng = np.random.default_rng(3)
    mixed = np.concatenate([rng.uniform(0.1, 1.6, 1000), rng.uniform(9.0, 12.0, 200)])
    return {  # name: (function, heights, model, path or lfe)
        "quadrature": ("simulate", np.linspace(0.05, 12.0, 1001), rbjax.Model(), "auto"),
        "angle+ode": ("simulate", mixed, ZENER, "auto"),
        "ode": ("simulate", rng.uniform(0.1, 1.6, 300), ZENER, "ode"),
        "evaluate": ("evaluate", rng.uniform(0.1, 1.6, 1000), rbjax.Model(), False),
        "evaluate-lfe": ("evaluate", rng.uniform(0.1, 1.6, 300), rbjax.Model(), True),
    }


def _run(name):
    kind, heights, model, option = _cases()[name]
    if kind == "simulate":
        r = rbjax.simulate(heights, model=model, path=option, parallel=Parallel(chunk_size=CHUNK))
        fields = ("contact_time_s", "peak_force_N", "peak_time_s", "restitution")
        fields += ("max_deflection_m", "status", "num_steps")
        out = {f: np.asarray(getattr(r, f)) for f in fields} | {"path": np.array(r.path)}
    else:
        youngs = np.linspace(1.3e6, 1.9e6, heights.size)
        samples = {"height_m": heights, "youngs_Pa": youngs}
        out = evaluate(samples, model=model, lfe=option, parallel=Parallel(chunk_size=CHUNK))
    return {f"{name}.{k}": v for k, v in out.items()}


SCRIPT = textwrap.dedent(
    """
    import sys
    import jax, numpy as np
    sys.path.insert(0, sys.argv[2])
    import test_devices as t
    from rbjax.solve.devices import cached_jit
    from rbjax.solve.path_runner import Rows, rows_program
    from rbjax.solve.inputs import as_arrays
    import rbjax

    assert jax.local_device_count() == int(sys.argv[3]), jax.devices()
    # which device ran each chunk: device_map's program for a chunk, wrapped to note the
    # device its output is on (a jitted call runs where its committed inputs are)
    import rbjax.solve.devices as engine
    compile_once, ran = engine.cached_jit, []

    def noting_the_device(fn):
        program = compile_once(fn)

        def call(rows, shared):
            result = program(rows, shared)
            (device,) = jax.tree_util.tree_leaves(result)[0].devices()
            ran.append(device.id)
            return result

        return call

    engine.cached_jit = noting_the_device
    out = {}
    for name in t._cases():
        ran.clear()
        out |= t._run(name)
        out[f"ran_on.{name}"] = np.array(ran)
    engine.cached_jit = compile_once
    # a per-device program holds no collective: nothing ties one device's loops to another's
    batch = Rows.of(*as_arrays((np.linspace(0.1, 1.6, 8), rbjax.JIS_RUBBER_BALL, t.ZENER)))
    rows = jax.device_put(batch.rows, jax.devices()[-1])
    fn = cached_jit(rows_program("ode", batch.spec, rbjax.Solver()))
    hlo = fn.lower(rows, batch.shared).compile().as_text()
    collectives = ("all-reduce", "all-gather", "all-to-all", "collective-permute")
    out["collectives"] = np.array(sum(hlo.count(op) for op in collectives))
    out["while_loops"] = np.array(hlo.count(" while("))
    np.savez(sys.argv[1], **out)
    """
)


def test_two_cpu_devices_equal_one_device_bit_for_bit(tmp_path):
    for _, heights, _, _ in _cases().values():  # each case splits over both devices
        assert plan(heights.size, 2, CHUNK)[0] == 2
    # this process has one CPU device (unless a command run in it earlier gave JAX one per
    # core): the subprocess gets two (or one)
    count = 2 if jax.local_device_count() == 1 else 1
    script = tmp_path / "two_devices.py"
    script.write_text(SCRIPT)
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    env |= {"JAX_NUM_CPU_DEVICES": str(count), "JAX_PLATFORMS": "cpu"}
    proc = subprocess.run(
        [
            sys.executable,
            str(script),
            str(tmp_path / "two.npz"),
            os.path.dirname(__file__),
            str(count),
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    two = dict(np.load(tmp_path / "two.npz"))
    assert int(two.pop("collectives")) == 0 and int(two.pop("while_loops")) > 0
    # the split reached every device: each case's chunks (the device of each) ran on both
    ran_on = {k: two.pop(k) for k in sorted(two) if k.startswith("ran_on.")}
    assert len(ran_on) == len(_cases())
    for name, ids in ran_on.items():
        assert sorted(set(ids.tolist())) == list(range(count)), (name, ids)
    one = {}
    for name in _cases():
        one |= _run(name)
    assert sorted(one) == sorted(two)
    for key in one:
        np.testing.assert_array_equal(two[key], one[key], err_msg=key)  # NaN where NaN
    assert str(one["angle+ode.path"]) == "angle+ode"
    status = one["angle+ode.status"]
    assert np.any(status == rbjax.STATUS_CODES["deflection_limit"]) and np.any(status == 0)
    assert np.all(np.isnan(one["angle+ode.contact_time_s"][status != 0]))

"""Lever: both CPU cores. XLA:CPU runs a vmapped solve on about one core; splitting the batch
over two host devices (``--xla_force_host_platform_device_count=2``) runs the halves in parallel.

Two ways of splitting:

* ``jax.jit`` with a NamedSharding of the batch axis (one partitioned program; a vmapped while
  loop's condition becomes an all-reduce, so the devices step together): scalar outputs at
  batch 10 000 (quick: 1000, the default quadrature only), one device vs two.
* ``rbjax.simulate``'s engine (``rbjax.solve.devices``): chunks sized for a CPU, round-robin
  over the devices, each running its own program. Elastic (quadrature) 10⁶, Zener (phase angle,
  momentum) 2×10⁵ and the Zener ODE 4096 impacts (quick: 10⁴ elastic only): one call of the
  whole batch (``simulate`` before the engine), chunks on one device, chunks on two devices.
  ``contact_rel_err`` of these rows: the largest relative difference to the one call (0: bit for
  bit); ``bitwise_1_device``: equal to the chunks on one device bit for bit.

The XLA flag must be set before JAX starts, so this script sets it itself; run it on its own:
``.venv/bin/python benchmarks/multicore.py [--quick]`` (run_all.py does).
"""

from __future__ import annotations

import os

os.environ["XLA_FLAGS"] = (
    os.environ.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=2"
).strip()

import time  # noqa: E402

import jax  # noqa: E402
import numpy as np  # noqa: E402
from jax.sharding import Mesh, NamedSharding  # noqa: E402
from jax.sharding import PartitionSpec as P  # noqa: E402

import rbjax  # noqa: E402
from rbjax import Model  # noqa: E402
from rbjax.solve import (
    impact_batch,  # noqa: E402
    impact_quadrature,  # noqa: E402
)

from _common import (
    broadcast_inputs,  # noqa: E402
    finish_machine_info,
    impact_one,
    machine_info,
    quadrature_reference,
    time_call,
    write_json,
)

RECOMMENDED = rbjax.Solver(scheme="tsit5", rtol=1e-7, atol=1e-10)


def timing_row(variant: str, devices: str, n: int, t: dict, err: float) -> dict:
    """One row of the table: throughput of ``n`` impacts timed as ``t`` (``time_call``)."""
    return {
        "variant": variant,
        "devices": devices,
        "batch": n,
        "impacts_per_s": n / t["median_s"],
        "best_impacts_per_s": n / t["min_s"],
        "first_s": t["first_s"],
        "median_s": t["median_s"],
        "min_s": t["min_s"],
        "contact_rel_err": err,
    }


def main(quick: bool = False) -> None:
    info = machine_info()
    t0 = time.perf_counter()
    n = 1000 if quick else 10_000
    model = Model()
    heights = np.linspace(0.1, 1.6, n)
    _, h, b, _ = broadcast_inputs(heights, rbjax.JIS_RUBBER_BALL, model)
    ref = quadrature_reference(heights)["contact_time_s"]
    devices = jax.devices()
    mesh = Mesh(np.array(devices[:2]), ("batch",))
    rows = []
    variants = (
        (
            "ode, recommended tsit5 1e-7/1e-10",
            lambda hh, bb: impact_one(hh, bb, model, RECOMMENDED).contact_time_s,
        ),
        (
            "quadrature, n_nodes=10",
            lambda hh, bb: impact_quadrature(hh, bb, model, n_nodes=10).contact_time_s,
        ),
        (
            "quadrature, n_nodes=12 (default)",
            lambda hh, bb: impact_quadrature(hh, bb, model).contact_time_s,
        ),
    )
    for name, one in variants[-1:] if quick else variants:
        batched = jax.vmap(one)
        single = jax.jit(batched)
        # as rbjax.studies.sweep sharded before rbjax.solve.devices (and still does over several
        # hosts): jit with the batch axis split over the mesh (GSPMD partitions the vmapped
        # solve; shard_map trips over the event root finder's lineax solve)
        spec = NamedSharding(mesh, P("batch"))
        sharded = jax.jit(batched, in_shardings=(spec, spec), out_shardings=spec)
        hs, bs = jax.device_put(h, spec), jax.device_put(b, spec)
        for label, fn, args_ in (
            ("1 device", single, (h, b)),
            ("2 devices (jit, NamedSharding)", sharded, (hs, bs)),
        ):
            t = time_call(lambda: fn(*args_), min_repeats=5)
            err = float(np.max(np.abs(np.asarray(t["out"]) / ref - 1)))
            rows.append(timing_row(name, label, n, t, err))
            print(
                f"{name:36s} {label:22s} {n / t['median_s']:10.0f} /s (best "
                f"{n / t['min_s']:.0f}/s)  first {t['first_s']:.1f} s  err {err:.1e}",
                flush=True,
            )
    rows += engine_rows(quick, devices[:2])
    write_json(
        "multicore" + ("_quick" if quick else ""),
        {
            "machine": finish_machine_info(info),
            "devices": [str(d) for d in devices],
            "rows": rows,
            "wall_s": time.perf_counter() - t0,
        },
    )


ZENER = Model(
    damping=rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3), blocked_force="momentum"
)


def engine_rows(quick: bool, devices) -> list[dict]:
    """``simulate``'s engine: one call of the whole batch, chunks on one device, on two."""
    from rbjax.solve import EvaluationSpec, evaluate, impact_angle, impact_quadrature_batch

    rows = []
    cases = (
        ("simulate elastic (quadrature)", "quadrature", Model(), 1_000_000),
        ("simulate zener (phase angle)", "angle", ZENER, 200_000),
        ("simulate zener (ode)", "ode", ZENER, 4096),
    )
    for name, path, model, n in cases[:1] if quick else cases:
        n = n // 100 if quick else n
        heights = np.linspace(0.1, 1.6, n)
        _, h, b, m = broadcast_inputs(heights, rbjax.JIS_RUBBER_BALL, model)
        if path == "ode":
            whole = lambda: impact_batch(h, b, m, rbjax.Solver()).contact_time_s  # noqa: E731
        elif path == "quadrature":
            whole = lambda: impact_quadrature_batch(h, b, m).contact_time_s  # noqa: E731
        else:
            one_call = jax.jit(jax.vmap(impact_angle))
            whole = lambda: one_call(h, b, m).contact_time_s  # noqa: E731

        def chunks(devs, path=path, heights=heights, model=model):
            spec, where = EvaluationSpec(path=path), rbjax.Parallel(devices=devs)
            out = evaluate({"height_m": heights}, model=model, evaluation=spec, parallel=where)
            return out["contact_time_s"]

        variants = {
            "1 device, one call (before)": whole,
            "1 device, chunks": lambda: chunks(devices[:1]),
            f"{len(devices)} devices, chunks": lambda: chunks(devices),
        }
        results = {}
        for label, fn in variants.items():
            t = time_call(fn, min_repeats=3, max_repeats=7)
            out = t["out"]
            results[label] = np.asarray(getattr(out, "contact_time_s", out))
            one = results["1 device, one call (before)"]
            ok = np.isfinite(one)
            err = float(np.max(np.abs(results[label][ok] / one[ok] - 1))) if ok.any() else 0.0
            chunked = results.get("1 device, chunks")
            rows.append(
                timing_row(name, label, n, t, err)
                | {
                    "bitwise_1_device": None
                    if chunked is None
                    else bool(np.array_equal(results[label], chunked, equal_nan=True)),
                }
            )
            print(
                f"{name:36s} {label:28s} {n / t['median_s']:12,.0f} /s (best "
                f"{n / t['min_s']:,.0f}/s)  first {t['first_s']:.1f} s  "
                f"vs one call {err:.1e}  bitwise {rows[-1]['bitwise_1_device']}",
                flush=True,
            )
    return rows

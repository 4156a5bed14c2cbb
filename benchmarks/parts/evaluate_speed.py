"""``rbjax.solve.batch.evaluate`` at its defaults against ``rbjax.simulate`` on the same impacts,
one device: the bar is evaluate ≥ 0.9× simulate (elastic 10⁶ and Zener 2×10⁵ impacts).

``evaluate`` is the engine of sweeps and sensitivities: N samples of named parameters (here
the drop height, 0.1–1.6 m, and Young's modulus, 1.3–1.9 MPa: two varied columns), the other
parameters at their nominal values. ``simulate`` gets the same heights and a ball whose
``youngs_Pa`` is the same array. Both return the scalar outputs of every impact (quadrature for
the elastic model, the phase-angle path for Zener with the momentum blocked force); the
outputs are checked to agree (rtol 1e-12). Timings: the best of repeats after a first
(compiling) call, run alternately (the 2-core machine is shared; its load average is recorded).

Run: ``.venv/bin/python benchmarks/evaluate_speed.py [--quick]`` (quick: 100× fewer impacts);
writes ``results/evaluate_speed.json`` and prints a table.
"""

from __future__ import annotations

import os
import time

# one device (a caller's XLA_FLAGS or JAX_NUM_CPU_DEVICES would split both over several)
os.environ.pop("JAX_NUM_CPU_DEVICES", None)
os.environ["XLA_FLAGS"] = " ".join(
    f
    for f in os.environ.get("XLA_FLAGS", "").split()
    if "xla_force_host_platform_device_count" not in f
)

import jax  # noqa: E402
import numpy as np  # noqa: E402

import rbjax  # noqa: E402
from rbjax.solve import evaluate  # noqa: E402

from _common import (  # noqa: E402
    finish_machine_info,
    fmt,
    machine_info,
    table,
    write_json,
)

MODELS = {
    "elastic": (rbjax.Model(), 1_000_000),
    "zener (momentum)": (
        rbjax.Model(
            damping=rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3),
            blocked_force="momentum",
        ),
        200_000,
    ),
}
BAR = 0.9
REPEATS = 5


def _best(fns: dict) -> dict:
    """First call of each, then the best of ``REPEATS`` calls, run alternately."""
    first, times = {}, {k: [] for k in fns}
    for k, fn in fns.items():
        t0 = time.perf_counter()
        fn()
        first[k] = time.perf_counter() - t0
    for _ in range(REPEATS):
        for k, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
    return {
        k: {"first_s": first[k], "best_s": min(v), "median_s": float(np.median(v))}
        for k, v in times.items()
    }


def main(quick: bool = False) -> None:
    info = machine_info()
    assert jax.local_device_count() == 1, jax.devices()
    t0 = time.perf_counter()
    rows = []
    for name, (model, n) in MODELS.items():
        n = n // 100 if quick else n
        heights = np.linspace(0.1, 1.6, n)
        youngs = np.linspace(1.3e6, 1.9e6, n)
        ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=youngs)
        out = {}

        def sim():
            r = rbjax.simulate(heights, ball, model)
            out["simulate"] = {k: np.asarray(getattr(r, k)) for k in ("contact_time_s", "status")}

        def ev():
            out["evaluate"] = evaluate({"height_m": heights, "youngs_Pa": youngs}, model=model)

        timing = _best({"simulate": sim, "evaluate": ev})
        s, e = out["simulate"], out["evaluate"]
        assert np.array_equal(s["status"], e["status"])
        np.testing.assert_allclose(e["contact_time_s"], s["contact_time_s"], rtol=1e-12)
        ratio = timing["simulate"]["best_s"] / timing["evaluate"]["best_s"]
        row = {
            "model": name,
            "impacts": n,
            "simulate_per_s": n / timing["simulate"]["best_s"],
            "evaluate_per_s": n / timing["evaluate"]["best_s"],
            "ratio": ratio,
            "bar": BAR,
            "met": ratio >= BAR,
            "timing": timing,
        }
        rows.append(row)
        print(
            f"{name:18s} {n:>9,d}  simulate {row['simulate_per_s']:>11,.0f}/s  "
            f"evaluate {row['evaluate_per_s']:>11,.0f}/s  ratio {ratio:.2f}",
            flush=True,
        )
    print()
    print(
        table(
            [
                "model",
                "impacts",
                "simulate (impacts/s)",
                "evaluate (impacts/s)",
                "evaluate / simulate",
                "bar",
            ],
            [
                [
                    r["model"],
                    f"{r['impacts']:,}",
                    fmt(r["simulate_per_s"], ",.0f"),
                    fmt(r["evaluate_per_s"], ",.0f"),
                    fmt(r["ratio"], ".2f"),
                    f"≥ {BAR} " + ("met" if r["met"] else "**missed**"),
                ]
                for r in rows
            ],
        )
    )
    write_json(
        "evaluate_speed" + ("_quick" if quick else ""),
        {
            "machine": finish_machine_info(info),
            "devices": [str(d) for d in jax.devices()],
            "rows": rows,
            "wall_s": time.perf_counter() - t0,
        },
    )

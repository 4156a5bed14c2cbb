"""Shared helpers of the benchmark scripts: machine record, timing, references, output files.

Every script writes ``benchmarks/results/<name>.json`` (and PNG charts beside it) and prints a
table. Timings are wall-clock medians of repeated calls after a first (compiling) call, with
``jax.block_until_ready`` on the outputs; the first call's excess over the median is reported as
the compile time. The machine is shared: each record carries the load average before and after.
"""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

import rbjax  # noqa: F401  (float64 on before anything else touches JAX)

# isort: split
import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp

from rbjax import Solver

FIXED_STEP_METHODS = ("euler", "heun", "midpoint")  # diffrax's fixed-step methods (Solver.step_s)

HERE = Path(__file__).resolve().parent
RESULTS_DIR = Path(os.environ.get("RBJAX_BENCH_RESULTS") or HERE / "results")
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tests"))  # the independent scipy reference lives with the tests

G = 9.80665


# ------------------------------------------------------------------------------------------------
# machine record


def machine_info() -> dict:
    """nproc, CPU model, load average, library versions and the date (recorded in every JSON)."""
    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import diffrax
    import equinox
    import jaxlib
    import scipy

    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "nproc": len(os.sched_getaffinity(0)),
        "cpu_model": model,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "jax": jax.__version__,
        "jaxlib": jaxlib.__version__,
        "diffrax": diffrax.__version__,
        "equinox": equinox.__version__,
        "scipy": scipy.__version__,
        "numpy": np.__version__,
        "jax_backend": jax.default_backend(),
        "loadavg_start": list(os.getloadavg()),
    }


def finish_machine_info(info: dict) -> dict:
    info["loadavg_end"] = list(os.getloadavg())
    return info


# ------------------------------------------------------------------------------------------------
# timing


def block(x):
    return jax.block_until_ready(x)


def time_call(
    fn,
    *,
    min_repeats: int = 3,
    min_time_s: float = 0.3,
    max_repeats: int = 15,
    max_time_s: float = 20.0,
) -> dict:
    """First call (compile + run) and the median of later calls, in seconds.

    Repeats at least ``min_repeats`` times and until ``min_time_s`` of repeats have run (at most
    ``max_repeats`` or ``max_time_s``). ``compile_s`` = first call − median (≥ 0).
    """
    t0 = time.perf_counter()
    out = block(fn())
    first = time.perf_counter() - t0
    times: list[float] = []
    while len(times) < min_repeats or (sum(times) < min_time_s and len(times) < max_repeats):
        if times and sum(times) > max_time_s:
            break
        t0 = time.perf_counter()
        block(fn())
        times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    return {
        "first_s": first,
        "median_s": med,
        "min_s": min(times),
        "compile_s": max(first - med, 0.0),
        "repeats": len(times),
        "out": out,
    }


# ------------------------------------------------------------------------------------------------
# a Solver whose tolerances are traced (one compile per method for a whole tolerance sweep)


class SweepSolver(Solver):
    """``rbjax.Solver`` with rtol, atol and the fixed step as traced arrays.

    ``Solver``'s own rtol/atol/step_s are static (each value is a new compile). Here the same
    PID controller / constant step receive arrays, so one compiled function serves the whole
    sweep; the arithmetic is the library's (its vector field, events, phases and root finder).
    """

    rtol_array: jax.Array | None = None
    atol_array: jax.Array | None = None
    step_array: jax.Array | None = None

    def controller(self):
        if self.scheme in FIXED_STEP_METHODS:
            return dfx.ConstantStepSize()
        return dfx.PIDController(rtol=self.rtol_array, atol=self.atol_array)

    def dt0(self):
        return self.step_array if self.scheme in FIXED_STEP_METHODS else None


def sweep_solver(
    method: str, *, rtol=1e-9, atol=1e-12, step_s=1e-5, max_steps=4096, adjoint="reverse"
) -> SweepSolver:
    fixed = method in FIXED_STEP_METHODS
    return SweepSolver(
        scheme=method,
        step_s=1e-5 if fixed else None,
        max_steps=max_steps,
        adjoint=adjoint,
        rtol_array=jnp.asarray(rtol, dtype=jnp.float64),
        atol_array=jnp.asarray(atol, dtype=jnp.float64),
        step_array=jnp.asarray(step_s, dtype=jnp.float64),
    )


# ------------------------------------------------------------------------------------------------
# scipy baseline: the lean loop the throughput targets are measured against


def scipy_impact_lean(
    height_m: float, ball, *, rtol: float = 1e-10, atol: float = 1e-13, gas: bool = True
) -> float:
    """Contact time of one elastic impact by scipy DOP853: two phases with one terminal event
    each (δ̇ = 0, then δ = 0), nothing else saved (no dense output, no extra events).

    The physics of paper Eq. 7 as in ``tests/scipy_reference.py``, written compactly; used as the
    per-impact cost of "a Python loop over scipy" (and checked against that reference).
    """
    from scipy.integrate import solve_ivp

    r, h, m, e, nu = (
        float(getattr(ball, f)) for f in ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")
    )
    k = 4.0 * e * h**2 / (r * math.sqrt(3.0 * (1.0 - nu**2)))
    pa, gamma = 101_325.0, 1.4
    flux = m / (2.0 * r)

    def force(d):
        f = k * d
        if gas:
            ratio = 1.0 - (3.0 - d / r) * (d / (2.0 * r)) ** 2
            f += pa * (ratio ** (-gamma) - 1.0) * math.pi * d * (2.0 * r - d)
        return f

    def compression(t, y):
        return [y[1], -force(y[0]) / (m * (1.0 - y[0] / (2.0 * r)))]

    def restitution(t, y):
        return [y[1], -(force(y[0]) - flux * y[1] ** 2) / (m * (1.0 - y[0] / (2.0 * r)))]

    def vel(t, y):
        return y[1]

    def defl(t, y):
        return y[0]

    vel.terminal, vel.direction = True, -1.0
    defl.terminal, defl.direction = True, -1.0
    v0 = math.sqrt(2.0 * G * height_m)
    t_span = 100.0 * math.sqrt(m / k)
    s1 = solve_ivp(
        compression, (0.0, t_span), [0.0, v0], method="DOP853", rtol=rtol, atol=atol, events=vel
    )
    t_max = s1.t_events[0][0]
    y_max = [s1.y_events[0][0][0], 0.0]
    s2 = solve_ivp(
        restitution,
        (t_max, t_max + t_span),
        y_max,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        events=defl,
    )
    return float(s2.t_events[0][0])


# ------------------------------------------------------------------------------------------------
# batch inputs of the solve cores (``rbjax.solve.impact_batch``, ``impact_quadrature_batch``)


def broadcast_inputs(height_m, ball, model):
    """Flatten height, ball and model parameters to one batch axis, as ``rbjax.simulate`` does
    before it calls a solve core (returns the shape, the heights, the ball and the model)."""
    height = jnp.asarray(height_m, dtype=jnp.float64)
    ball = ball.as_arrays()
    arrays, static = eqx.partition(model, eqx.is_array_like)
    arrays = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype=jnp.float64), arrays)
    leaves = [height, *jax.tree_util.tree_leaves(ball), *jax.tree_util.tree_leaves(arrays)]
    shape = jnp.broadcast_shapes(*(x.shape for x in leaves))

    def flat(x):
        return jnp.broadcast_to(x, shape).reshape(-1)

    height = flat(height)
    ball = jax.tree_util.tree_map(flat, ball)
    model = eqx.combine(jax.tree_util.tree_map(flat, arrays), static)
    return shape, height, ball, model


def impact_one(height_m, ball, model, solver):
    """One impact on the ODE path (``rbjax.solve.impact_batch`` on a batch of one), traceable
    under ``jax.vmap`` and ``jax.jacfwd``."""
    from rbjax.solve import impact_batch

    _, h, b, m = broadcast_inputs(height_m, ball, model)
    return jax.tree_util.tree_map(lambda x: x[0], impact_batch(h, b, m, solver))


# ------------------------------------------------------------------------------------------------
# references for the elastic JIS ball


def quadrature_reference(heights_m, ball=None, *, gas="adiabatic", n_nodes: int = 64):
    """Scalar outputs of the elastic model by the quadrature path at a high node count (an
    independent integration of Eq. 7 in δ, exponentially convergent; see rbjax.solve.quadrature)."""
    from rbjax import Model
    from rbjax.solve import impact_quadrature_batch

    ball = rbjax.JIS_RUBBER_BALL if ball is None else ball
    _, h, b, m = broadcast_inputs(np.asarray(heights_m, dtype=float), ball, Model(gas=gas))
    out = impact_quadrature_batch(h, b, m, n_nodes)
    return {
        k: np.asarray(getattr(out, k))
        for k in ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m", "status")
    }


# ------------------------------------------------------------------------------------------------
# fit helpers, from public names only


def held_out_rows(result, heights) -> list[SimpleNamespace]:
    """Held-out errors at ``heights`` of a ``FitResult`` or a ``Prediction``: the history's rms
    error in % of the mean peak, and the per-height errors the result reports."""
    rows = []
    for h in heights:
        k = np.isclose(result.heights_m, h, atol=5e-4)
        row = next(r for r in result.per_height if abs(r["height_m"] - h) < 5e-4)
        rms = float(np.sqrt(np.mean((result.predicted_N[k] - result.measured_N[k]) ** 2)))
        peak = float(np.mean(np.max(result.measured_N[k], axis=1)))
        rows.append(
            SimpleNamespace(
                height_m=float(h),
                history_error_pct=100.0 * rms / peak,
                contact_time_pct=row["error"]["contact_time_pct"],
                peak_force_pct=row["error"]["peak_force_pct"],
                lfe_octave_dB=tuple(float(x) for x in row["error"]["lfe_octave_dB"]),
                converged=result.converged,
            )
        )
    return rows


def shared_structure(names, gas: str = "adiabatic"):
    """One model holding the terms of every candidate named (``rbjax.terms.structure_model``):
    the structure of the one compiled fit program all candidates run through."""
    from rbjax import Model
    from rbjax.fit import parse_model_terms
    from rbjax.terms import structure_model

    laws, stiff, mode, series = [], False, False, False
    for name in names:
        terms = parse_model_terms(name)
        laws += [t for t in terms.laws if t not in laws]
        stiff = stiff or terms.stiffening
        mode = mode or terms.ball_mode
        series = series or terms.series
    return structure_model(Model(gas=gas), laws, stiffening=stiff, ball_mode=mode, series=series)


def usable_cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


# ------------------------------------------------------------------------------------------------
# output


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items() if k != "out"}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.ndarray, jax.Array)):
        return _jsonable(np.asarray(x).tolist())
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def write_json(name: str, data: dict) -> Path:
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    path = RESULTS_DIR / f"{name}.json"
    path.write_text(json.dumps(_jsonable(data), indent=1) + "\n")
    return path


def read_json(name: str) -> dict | None:
    path = RESULTS_DIR / f"{name}.json"
    return json.loads(path.read_text()) if path.exists() else None


def fmt(x, spec=".3g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "—"
    return format(x, spec)


def table(headers: list[str], rows: list[list]) -> str:
    """A GitHub-markdown table."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def parse_args(description: str):
    import argparse

    p = argparse.ArgumentParser(description=description)
    p.add_argument(
        "--quick", action="store_true", help="a smoke run: fewer points, small batches (minutes)"
    )
    return p.parse_args()

"""Throughput: impacts per second against batch size, compile time, and the scipy baseline.

The JIS ball (paper §4), elastic model of Eq. 7 with the adiabatic gas force unless stated; drop
heights spread over 0.1–1.6 m. For each workload and batch size B the first call (trace + XLA
compile + run) and the median of later calls are timed (``block_until_ready``); compile time =
first − median. Workloads:

(a) scalar outputs (contact time, peak force, restitution): ``rbjax.solve.impact_batch`` after
    ``rbjax.solve.simulate.broadcast_inputs`` (the core of ``rbjax.simulate``), with the library's
    default ``Solver()`` and with the recommended one; the quadrature path
    ``impact_quadrature_batch`` (default 12 interpolation points, and 10 and 16); a batch of mixed
    difficulty with and without bucketing; and the scipy loop (DOP853, rtol 1e-10, one terminal
    event per phase).
(b) the 44.1 kHz force history over the contact window (``rbjax.trajectory``) and the octave-band
    L_FE of the 1 s record (``rbjax.spectrum.lfe_octave_dB`` on the zero-padded record, paper §2.4),
    and the same L_FE from only the DFT bins the octave bands use (a matrix product on the window).
(c) value and Jacobian of (contact time, peak force, restitution) with respect to (E, ν, c) for the
    Kelvin–Voigt model by ``jax.jacfwd`` with ``Solver(adjoint="forward")``, and with respect to
    (E, ν) for the elastic model through the quadrature path; the ratio to the value-only cost.

Accuracy: every ODE and quadrature variant's contact time is compared with the quadrature path at
64 nodes (the forward-model tests require 1e-6 relative). A compile breakdown (tracing vs XLA,
HLO size) and the cost of one vector-field evaluation (the arithmetic floor per step) are recorded.

Run: ``.venv/bin/python benchmarks/throughput.py [--quick]``.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import rbjax
from rbjax import Model
from rbjax.solve import impact_batch, impact_quadrature, impact_quadrature_batch
from rbjax.spectrum import OCTAVE_BANDS, band_edges_Hz, lfe_dB, lfe_octave_dB

from _common import (
    RESULTS_DIR,
    broadcast_inputs,
    finish_machine_info,
    fmt,
    impact_one,
    machine_info,
    quadrature_reference,
    scipy_impact_lean,
    time_call,
    write_json,
)

RATE_HZ = 44_100.0
N_RECORD = 44_100  # the paper's 1 s record (§2.4)
BALL = rbjax.JIS_RUBBER_BALL
DEFAULT = rbjax.Solver()
#: The recommended default (see RESULTS.md, work–precision): tsit5 at rtol 1e-7, atol 1e-10.
RECOMMENDED = rbjax.Solver(scheme="tsit5", rtol=1e-7, atol=1e-10)
RECOMMENDED_FWD = rbjax.Solver(scheme="tsit5", rtol=1e-7, atol=1e-10, adjoint="forward")
#: Other node counts of the quadrature's interpolant (default 12, ≤ 1e-12): 10 still ≤ 1e-10 for
#: the JIS ball over 0.1–1.6 m, 16 to round-off (fewer are flagged solver_failed by its estimate).
QUAD_FAST_NODES = (10, 16)
TARGET_REL = 1e-6


def heights(n):
    return np.linspace(0.1, 1.6, n) if n > 1 else np.array([1.0])


def flat(n, model=None, **ball_changes):
    model = Model() if model is None else model
    ball = BALL.replace(**ball_changes) if ball_changes else BALL
    _, h, b, m = broadcast_inputs(heights(n), ball, model)
    return h, b, m


def record(rows, workload, variant, n, timing, **extra):
    row = {
        "workload": workload,
        "variant": variant,
        "batch": n,
        "first_s": timing["first_s"],
        "median_s": timing["median_s"],
        "min_s": timing["min_s"],
        "compile_s": timing["compile_s"],
        "repeats": timing["repeats"],
        "impacts_per_s": n / timing["median_s"],
        "per_impact_s": timing["median_s"] / n,
        **extra,
    }
    rows.append(row)
    print(
        f"{workload:10s} {variant:44s} B={n:<7d} {row['impacts_per_s']:12.0f} /s   first "
        f"{timing['first_s']:6.2f} s  compile {timing['compile_s']:6.2f} s  median "
        f"{timing['median_s'] * 1e3:9.2f} ms  "
        + " ".join(
            f"{k}={fmt(v, '.3g')}" for k, v in extra.items() if not isinstance(v, (dict, list))
        ),
        flush=True,
    )
    return row


def timed(fn, n):
    big = n >= 10_000
    return time_call(
        fn, min_repeats=1 if n >= 100_000 else 2 if big else 3, min_time_s=0.3, max_repeats=10
    )


def contact_error(out, n):
    """Max relative contact-time error against the quadrature reference (64 nodes)."""
    ref = quadrature_reference(heights(n), n_nodes=64)["contact_time_s"]
    return float(np.max(np.abs(np.asarray(out.contact_time_s) / ref - 1)))


# ------------------------------------------------------------------------------------------------
# (a) scalar outputs


def scalar_workload(rows, sizes, quick):
    default_sizes = [sizes[0], sizes[-2], sizes[-1]] if len(sizes) > 3 else sizes
    for n in sizes:
        h, b, m = flat(n)
        check = n <= 10_000
        variants = [("ode, recommended tsit5 1e-7/1e-10", RECOMMENDED)]
        if n in default_sizes and not quick:
            variants.insert(0, ("ode, default Solver()", DEFAULT))
        for name, solver in variants:
            t = timed(lambda: impact_batch(h, b, m, solver), n)
            out = t["out"]
            record(
                rows,
                "scalar",
                name,
                n,
                t,
                mean_steps=float(np.mean(np.asarray(out.num_steps))),
                max_steps=int(np.max(np.asarray(out.num_steps))),
                contact_rel_err=contact_error(out, n) if check else None,
            )
        for nodes in (12,) if quick else (12, *QUAD_FAST_NODES):
            t = timed(lambda: impact_quadrature_batch(h, b, m, nodes), n)
            record(
                rows,
                "scalar",
                f"quadrature, n_nodes={nodes}",
                n,
                t,
                contact_rel_err=contact_error(t["out"], n) if check else None,
            )
    if quick:
        return
    # adjoint lever at one size: the same tolerance, forward-mode adjoint
    n = sizes[-2] if len(sizes) > 1 else sizes[-1]
    h, b, m = flat(n)
    for name, solver in (
        ("ode, default tol, adjoint=forward", rbjax.Solver(adjoint="forward")),
        ("ode, recommended tol, adjoint=forward", RECOMMENDED_FWD),
    ):
        t = timed(lambda: impact_batch(h, b, m, solver), n)
        record(
            rows,
            "scalar",
            name,
            n,
            t,
            mean_steps=float(np.mean(np.asarray(t["out"].num_steps))),
            contact_rel_err=contact_error(t["out"], n),
        )


def bucketing_workload(rows, quick):
    """A batch of mixed difficulty: vmap runs every element for as many steps as the slowest one,
    so grouping similar impacts (sorted by a cheap difficulty predictor) saves work. ``quick``:
    the elastic model, whose chunks of 100 reuse the scalar workload's program."""
    rng = np.random.default_rng(0)
    n, chunk = (200, 100) if quick else (20_000, 1000)
    height = 10.0 ** rng.uniform(-3, 1, n)
    youngs = 10.0 ** rng.uniform(5, 8, n)
    c = 10.0 ** rng.uniform(
        0, 3.5, n
    )  # Kelvin–Voigt c up to ~3× critical (~700 N s/m for the JIS ball)
    solver = RECOMMENDED

    def run(order):
        outs = []
        for i in range(0, n, chunk):
            idx = order[i : i + chunk]
            _, hh, bb, mm = broadcast_inputs(
                height[idx],
                BALL.replace(youngs_Pa=youngs[idx]),
                Model() if quick else Model(damping=rbjax.KelvinVoigt(c[idx])),
            )
            outs.append(impact_batch(hh, bb, mm, solver))
        return outs

    # predictor: deflection of the undamped linear shell relative to the wall, and the damping ratio
    k = 4 * youngs * BALL.wall_m**2 / (BALL.radius_m * math.sqrt(3 * (1 - BALL.poisson**2)))
    zeta = c / (2 * np.sqrt(k * BALL.mass_kg))
    defl = np.sqrt(2 * 9.80665 * height) * np.sqrt(BALL.mass_kg / k) / BALL.wall_m
    predictor = np.lexsort((defl, np.round(np.log10(zeta) * 2)))
    unsorted = np.arange(n)
    t_un = time_call(lambda: run(unsorted), min_repeats=2, min_time_s=0.0)
    steps = np.concatenate([np.asarray(o.num_steps) for o in t_un["out"]])
    oracle = np.argsort(steps)
    t_pred = time_call(lambda: run(predictor), min_repeats=2, min_time_s=0.0)
    t_orc = time_call(lambda: run(oracle), min_repeats=2, min_time_s=0.0)

    def chunk_max(order):
        return float(np.mean([steps[order[i : i + chunk]].max() for i in range(0, n, chunk)]))

    for name, t, order in (
        ("mixed batch, chunks unsorted", t_un, unsorted),
        ("mixed batch, chunks sorted by predictor", t_pred, predictor),
        ("mixed batch, chunks sorted by step count (oracle)", t_orc, oracle),
    ):
        record(
            rows,
            "bucketing",
            name,
            n,
            t,
            chunk=chunk,
            mean_steps=float(steps.mean()),
            mean_chunk_max_steps=chunk_max(order),
        )


def scipy_workload(rows, quick):
    n = 20 if quick else 100
    hs = heights(n)
    scipy_impact_lean(1.0, BALL)
    t0 = time.perf_counter()
    tc = [scipy_impact_lean(h, BALL) for h in hs]
    wall = time.perf_counter() - t0
    ref = quadrature_reference(hs, n_nodes=64)["contact_time_s"]
    timing = {"first_s": wall, "median_s": wall, "min_s": wall, "compile_s": 0.0, "repeats": 1}
    return record(
        rows,
        "scalar",
        "scipy solve_ivp DOP853 rtol 1e-10 (Python loop)",
        n,
        timing,
        contact_rel_err=float(np.max(np.abs(np.asarray(tc) / ref - 1))),
    )


# ------------------------------------------------------------------------------------------------
# (b) force history at 44.1 kHz and octave L_FE


def _bin_matrix():
    """cos/sin of the 1 s record's rfft bins inside the octave bands (22.4 Hz–1.41 kHz)."""
    lower, upper = band_edges_Hz(1, float(OCTAVE_BANDS[0]), float(OCTAVE_BANDS[-1]))
    k = np.arange(N_RECORD // 2 + 1)
    f = k * RATE_HZ / N_RECORD
    used = (f >= lower[0]) & (f < upper[-1])
    band = np.array(
        [np.flatnonzero((f[used] >= lo) & (f[used] < hi)) for lo, hi in zip(lower, upper)],
        dtype=object,
    )
    mask = np.zeros((len(lower), used.sum()))
    for i, idx in enumerate(band):
        mask[i, idx] = 1.0
    return k[used], mask


def lfe_octave_from_window(force_window):
    """The octave L_FE of the 1 s record from its contact window alone: the rfft bins of the
    zero-padded record that the bands use, as one matrix product (equal to lfe_octave_dB on the
    padded record up to round-off; the weight 2 of the one-sided spectrum, none of DC/Nyquist
    used)."""
    bins, mask = _bin_matrix()
    n_w = force_window.shape[-1]
    phase = 2.0 * np.pi * np.outer(np.arange(n_w), bins) / N_RECORD
    cos, sin = jnp.asarray(np.cos(phase)), jnp.asarray(np.sin(phase))
    re, im = force_window @ cos, force_window @ sin
    energy = 2.0 * (re**2 + im**2) / RATE_HZ**2 * (RATE_HZ / N_RECORD)  # E_k Δf, N² s
    return lfe_dB(energy @ jnp.asarray(mask).T)


def history_workload(rows, sizes, quick=False):
    model = Model()
    t_c = float(
        quadrature_reference([0.1])["contact_time_s"][0]
    )  # the longest contact of 0.1–1.6 m
    n_w = int(math.ceil(t_c * RATE_HZ)) + 2
    times = jnp.arange(n_w) / RATE_HZ

    def padded(solver):
        @jax.jit
        def f(h):
            force = rbjax.trajectory(h, times, BALL, model, solver).force_N
            chunks = force.reshape(
                (-1, min(force.shape[0], 250), n_w)
            )  # rfft of 1 s records, 250 at a time

            def lfe(x):
                return lfe_octave_dB(jnp.pad(x, ((0, 0), (0, N_RECORD - n_w))), RATE_HZ)

            return jax.lax.map(lfe, chunks).reshape((-1, len(OCTAVE_BANDS)))

        return f

    def windowed(solver):
        return jax.jit(
            lambda h: lfe_octave_from_window(
                rbjax.trajectory(h, times, BALL, model, solver).force_N
            )
        )

    # rbjax.trajectory keeps each phase's dense interpolant for max_steps steps: ~16 floats per step
    # and phase (tsit5), 1 MB per impact at max_steps = 4096; a batch of 10 000 needs ~10 GB (the
    # first full run was killed there). Batches ≥ 10 000 run only with max_steps = 256.
    small = rbjax.Solver(scheme="tsit5", rtol=1e-7, atol=1e-10, max_steps=256)
    upto_1000 = [n for n in sizes if n <= 1000]
    variants = [
        (
            "trajectory + octave bins only (DFT matmul), recommended",
            windowed(RECOMMENDED),
            upto_1000,
        ),
        ("trajectory + lfe_octave_dB (1 s rfft), recommended", padded(RECOMMENDED), upto_1000[-1:]),
        ("trajectory + octave bins only, default Solver()", windowed(DEFAULT), upto_1000[-1:]),
        ("trajectory + octave bins only, recommended, max_steps=256", windowed(small), sizes),
        (
            "trajectory + lfe_octave_dB (1 s rfft), recommended, max_steps=256",
            padded(small),
            sizes[-1:],
        ),
    ]
    ref_fn = windowed(rbjax.Solver(scheme="dopri8", rtol=1e-12, atol=1e-15, max_steps=256))
    if quick:  # one variant, one size, itself as the reference: the code path, one compile
        variants = variants[3:4]
        ref_fn = variants[0][1]
    refs = {}
    for name, fn, ns in variants:
        for n in ns:
            h = jnp.asarray(heights(n))
            if n not in refs:
                refs[n] = np.asarray(ref_fn(h))
            t = timed(lambda: fn(h), n)
            record(
                rows,
                "history",
                name,
                n,
                t,
                samples=n_w,
                lfe_max_abs_err_dB=float(np.max(np.abs(np.asarray(t["out"]) - refs[n]))),
            )


# ------------------------------------------------------------------------------------------------
# (c) value and Jacobian


def jacobian_workload(rows, sizes, quick=False):
    model0 = Model(damping=rbjax.KelvinVoigt(damping_Ns_per_m=100.0))

    def one_ode(theta, h, solver):
        ball = BALL.replace(youngs_Pa=theta[0], poisson=theta[1])
        model = eqx.tree_at(lambda m: m.damping[0].damping_Ns_per_m, model0, theta[2])
        out = impact_one(h, ball, model, solver)
        return jnp.stack([out.contact_time_s, out.peak_force_N, out.restitution])

    def one_quad(theta, h):
        out = impact_quadrature(h, BALL.replace(youngs_Pa=theta[0], poisson=theta[1]), Model())
        return jnp.stack([out.contact_time_s, out.peak_force_N, out.restitution])

    def value_and_jac(f):
        return jax.jacfwd(lambda th, h: (f(th, h), f(th, h)), has_aux=True)

    solver = RECOMMENDED_FWD
    ode_value = jax.jit(jax.vmap(lambda th, h: one_ode(th, h, solver)))
    ode_value_rev = jax.jit(jax.vmap(lambda th, h: one_ode(th, h, RECOMMENDED)))
    ode_jac = jax.jit(jax.vmap(value_and_jac(lambda th, h: one_ode(th, h, solver))))
    quad_value = jax.jit(jax.vmap(one_quad))
    quad_jac = jax.jit(jax.vmap(value_and_jac(one_quad)))
    for n in sizes:
        h = jnp.asarray(heights(n))
        # the ODE Jacobian compiles for minutes: one size, none with quick
        ode = not quick and (n == sizes[-2] if len(sizes) > 1 else True)
        theta3 = jnp.tile(jnp.array([1.6e6, 0.45, 100.0]), (n, 1))
        theta2 = jnp.tile(jnp.array([1.6e6, 0.45]), (n, 1))
        base = {}
        for name, fn, th in (
            ("KV: value only (adjoint=forward)", ode_value, theta3),
            ("KV: value only (adjoint=reverse)", ode_value_rev, theta3),
            ("KV: value + jacfwd (E, nu, c)", ode_jac, theta3),
            ("quadrature: value only", quad_value, theta2),
            ("quadrature: value + jacfwd (E, nu)", quad_jac, theta2),
        ):
            kind = name.split(":")[0]
            if kind == "KV" and not ode:
                continue
            t = timed(lambda: fn(th, h), n)
            if "jacfwd" in name:
                ratio = t["median_s"] / base[kind]
                row = record(rows, "jacobian", name, n, t, ratio_to_value=ratio)
                jac = np.asarray(t["out"][0])
                row["jacobian_finite"] = bool(np.all(np.isfinite(jac)))
            else:
                base.setdefault(kind, t["median_s"])
                record(rows, "jacobian", name, n, t)


# ------------------------------------------------------------------------------------------------
# compile breakdown and the arithmetic floor


def compile_breakdown(n=1000, quick=False):
    """Tracing (Python → jaxpr → StableHLO) and XLA compile time, HLO size, per variant."""
    out = {}
    h, b, m = flat(n)
    variants = (("default Solver()", DEFAULT), ("recommended, adjoint=forward", RECOMMENDED_FWD))
    for name, solver in () if quick else variants:  # quick: the quadrature's below only
        fn = jax.jit(jax.vmap(lambda hh, bb: impact_one(hh, bb, Model(), solver)))
        t0 = time.perf_counter()
        lowered = fn.lower(h, b)
        t1 = time.perf_counter()
        compiled = lowered.compile()
        t2 = time.perf_counter()
        hlo = compiled.as_text() or ""
        out[name] = {
            "trace_lower_s": t1 - t0,
            "xla_compile_s": t2 - t1,
            "hlo_lines_optimized": hlo.count("\n"),
            "stablehlo_lines": lowered.as_text().count("\n"),
            "while_loops": hlo.count(" while("),
        }
    fn = jax.jit(jax.vmap(lambda hh, bb: impact_quadrature(hh, bb, Model())))
    t0 = time.perf_counter()
    lowered = fn.lower(h, b)
    t1 = time.perf_counter()
    compiled = lowered.compile()
    t2 = time.perf_counter()
    out["quadrature n_nodes=12"] = {
        "trace_lower_s": t1 - t0,
        "xla_compile_s": t2 - t1,
        "hlo_lines_optimized": (compiled.as_text() or "").count("\n"),
        "stablehlo_lines": lowered.as_text().count("\n"),
    }
    for k, v in out.items():
        print(
            f"compile  {k:32s} trace+lower {v['trace_lower_s']:6.2f} s  XLA "
            f"{v['xla_compile_s']:6.2f} s  HLO lines {v['hlo_lines_optimized']}"
        )
    return out


def persistent_cache_probe(quick):
    """First-call time of rbjax.simulate in a fresh process with an empty, then a warm, JAX
    persistent compilation cache (the warm run still traces; it skips XLA)."""
    import tempfile

    code = (
        "import time,sys; t=time.perf_counter(); import jax; "
        "jax.config.update('jax_compilation_cache_dir', sys.argv[1]);"
        "jax.config.update('jax_persistent_cache_min_compile_time_secs', 0.0); "
        "import rbjax, numpy as np;"
        "t1=time.perf_counter(); r=rbjax.simulate(np.linspace(0.1,1.6,1000)); "
        "jax.block_until_ready(r.contact_time_s);"
        "print(time.perf_counter()-t1)"
    )
    out = {}
    with tempfile.TemporaryDirectory() as d:
        for label in ("cold cache", "warm cache"):
            res = subprocess.run(
                [sys.executable, "-c", code, d],
                capture_output=True,
                text=True,
                cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
            )
            try:
                out[label] = float(res.stdout.strip().splitlines()[-1])
            except (ValueError, IndexError):
                out[label] = None
                print(res.stderr[-2000:])
    print(f"persistent cache: first rbjax.simulate call {out}")
    return out


# ------------------------------------------------------------------------------------------------


def main(quick: bool = False) -> None:
    info = machine_info()
    t_start = time.perf_counter()
    rows: list[dict] = []
    # quick: one size and one variant per workload (each ODE variant compiles for seconds)
    sizes_a = [100] if quick else [1, 10, 100, 1000, 10_000, 100_000]
    sizes_b = [10] if quick else [1, 100, 1000, 10_000]
    sizes_c = [10] if quick else [1, 1000, 10_000]

    breakdown = compile_breakdown(100 if quick else 1000, quick)
    scipy_row = scipy_workload(rows, quick)
    scalar_workload(rows, sizes_a, quick)
    bucketing_workload(rows, quick)
    history_workload(rows, sizes_b, quick)
    jacobian_workload(rows, sizes_c, quick)
    cache = {} if quick else persistent_cache_probe(quick)

    for r in rows:
        if r["workload"] == "scalar" and r is not scipy_row:
            r["speedup_vs_scipy"] = scipy_row["per_impact_s"] / r["per_impact_s"]
    data = {
        "machine": finish_machine_info(info),
        "quick": quick,
        "rows": rows,
        "compile_breakdown": breakdown,
        "persistent_cache_first_call_s": cache,
        "scipy_per_impact_s": scipy_row["per_impact_s"],
        "recommended_solver": repr(RECOMMENDED),
        "wall_s": time.perf_counter() - t_start,
    }
    write_json("throughput" + ("_quick" if quick else ""), data)
    plot(rows, scipy_row, quick)
    print(f"total {data['wall_s']:.0f} s")


def plot(rows, scipy_row, quick):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(17, 5.2))
    for ax, workload, title in zip(
        axes,
        ("scalar", "history", "jacobian"),
        ("(a) scalar outputs", "(b) 44.1 kHz history + octave L_FE", "(c) value + Jacobian"),
    ):
        variants = []
        for r in rows:
            if r["workload"] == workload and r["variant"] not in variants and r is not scipy_row:
                variants.append(r["variant"])
        for v in variants:
            pts = sorted(
                (r["batch"], r["impacts_per_s"])
                for r in rows
                if r["workload"] == workload and r["variant"] == v
            )
            if len(pts) == 1:
                ax.loglog(*zip(*pts), "*", ms=10, label=v)
            else:
                ax.loglog(*zip(*pts), marker="o", label=v)
        if workload == "scalar":
            ax.axhline(1 / scipy_row["per_impact_s"], color="grey", ls=":", label="scipy loop")
            ax.axhline(5e5, color="k", ls="--", lw=0.8, label="target 500 000/s")
        if workload == "history":
            ax.axhline(2e4, color="k", ls="--", lw=0.8, label="target 20 000/s")
        ax.set_xlabel("batch size")
        ax.set_ylabel("impacts per second (median, after compile)")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    RESULTS_DIR.mkdir(exist_ok=True)
    fig.savefig(RESULTS_DIR / ("throughput" + ("_quick" if quick else "") + ".png"), dpi=110)
    plt.close(fig)

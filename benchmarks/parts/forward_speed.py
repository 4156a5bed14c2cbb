"""Forward speed of ``rbjax.simulate`` at its defaults, side by side with the scipy loop.

The targets (the project's "forward speed" goal), each measured here in one run:

* default ``rbjax.simulate`` (``path="auto"``: the quadrature for the elastic model), elastic
  model with the gas force, batch 10 000, scalar outputs: ≥ 1 000 000 impacts/s and ≥ 3000× the
  scipy ``solve_ivp`` loop (DOP853, rtol 1e-10, one terminal event per phase, one Python call per
  impact);
* first-call compile of the default ``simulate`` ≤ 5 s (a fresh process, no persistent cache);
* value + Jacobian (``jax.vmap(jax.jacfwd(...))`` of contact time, peak force, restitution) ≤ 3×
  the forward, at batch 1, 1000 and 10 000, of the default paths: the quadrature (elastic) w.r.t.
  (E, ν), the phase-angle path (Zener) w.r.t. (E, ν, relaxation time);
* the damped models (Zener, Hunt–Crossley; ``simulate`` default: the phase-angle path
  ``rbjax.solve.angle``) at batch 10 000: ≥ 300 000 impacts/s; histories (44.1 kHz × 1 s force
  record: its contact samples, ``history(pad=False)``, the rest being zero, and its octave-band
  L_FE with ``n_record=44 100``) ≥ 20 000/s.

Accuracy rides along: the scalar outputs of every timed variant are compared with the independent
scipy reference (``tests/scipy_reference.py``, DOP853 at rtol 1e-12) at 16 heights of the batch.
Heights 0.1–1.6 m, the JIS ball (paper §4). Timings: median of repeats after a first (compiling)
call, ``jax.block_until_ready`` on every output; the machine's load average is recorded at start
and end (the 2-core machine is shared).

Run: ``.venv/bin/python benchmarks/forward_speed.py [--quick]``; writes
``results/forward_speed.json`` and prints the targets table.
"""

from __future__ import annotations

import subprocess
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

import rbjax
from rbjax.spectrum import lfe_octave_dB

from _common import (
    HERE,
    REPO,
    finish_machine_info,
    fmt,
    machine_info,
    scipy_impact_lean,
    table,
    time_call,
    write_json,
)
from scipy_reference import reference_impact  # noqa: E402  (tests/ is on sys.path via _common)

BALL = rbjax.JIS_RUBBER_BALL
RATE_HZ = 44_100.0
SCALARS = ("contact_time_s", "peak_force_N", "restitution")
DAMPED = {
    "zener": (rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3), "momentum"),
    "hunt-crossley": (rbjax.HuntCrossley(alpha_s_per_m=0.3), "paper"),
}
CHECK_POINTS = 16
#: Block size of the chunked value + Jacobian variant.
CHUNK = 1000


def heights(n):
    return np.linspace(0.1, 1.6, n) if n > 1 else np.array([1.0])


def blocked(res):
    return jax.block_until_ready([getattr(res, k) for k in (*SCALARS, "status")])


def row(rows, workload, variant, n, timing, **extra):
    r = {
        "workload": workload,
        "variant": variant,
        "batch": n,
        "first_s": timing["first_s"],
        "median_s": timing["median_s"],
        "min_s": timing["min_s"],
        "compile_s": timing["compile_s"],
        "impacts_per_s": n / timing["median_s"],
        **extra,
    }
    rows.append(r)
    notes = " ".join(
        f"{k}={fmt(v, '.3g') if isinstance(v, float) else v}"
        for k, v in extra.items()
        if not isinstance(v, (dict, list))
    )
    print(
        f"{workload:9s} {variant:58s} B={n:<6d} {r['impacts_per_s']:12,.0f}/s  first "
        f"{timing['first_s']:6.2f} s  median {timing['median_s'] * 1e3:9.3f} ms  {notes}",
        flush=True,
    )
    return r


def reference_error(res, n, **options):
    """Largest relative error of the scalar outputs at CHECK_POINTS heights of the batch."""
    h = heights(n)
    idx = np.unique(np.linspace(0, n - 1, min(n, CHECK_POINTS)).astype(int))
    worst = {}
    for i in idx:
        ref = reference_impact(h[i], BALL, **options)
        for k in SCALARS:
            err = abs(float(np.asarray(getattr(res, k)).reshape(-1)[i]) / getattr(ref, k) - 1.0)
            worst[k] = max(worst.get(k, 0.0), err)
    return worst


# ------------------------------------------------------------------------------------------------


def scipy_loop(rows, quick):
    n = 20 if quick else 100
    hs = heights(n)
    scipy_impact_lean(1.0, BALL)
    t0 = time.perf_counter()
    for h in hs:
        scipy_impact_lean(h, BALL)
    wall = time.perf_counter() - t0
    timing = {"first_s": wall, "median_s": wall, "min_s": wall, "compile_s": 0.0}
    return row(
        rows, "scalar", "scipy solve_ivp DOP853 rtol 1e-10 (Python loop, elastic)", n, timing
    )


def elastic_scalars(rows, sizes, scipy_per_impact):
    for n in sizes:
        h = heights(n)
        for path in ("auto",) if n < 1000 else ("auto", "ode"):  # quick (n 100): no ODE
            if path == "ode" and n > 10_000:
                continue
            t = time_call(
                lambda: blocked(rbjax.simulate(h, path=path)),
                min_repeats=3 if n >= 10_000 else 5,
                min_time_s=0.5,
            )
            res = rbjax.simulate(h, path=path)
            r = row(
                rows,
                "scalar",
                f"simulate(path={path!r}) elastic, gas",
                n,
                t,
                path=res.path,
                max_rel_err_vs_scipy=reference_error(res, n),
                speedup_vs_scipy=scipy_per_impact / (t["median_s"] / n),
            )
            r["statuses_ok"] = bool(np.all(np.asarray(res.status) == 0))


def damped_scalars(rows, sizes, quick=False):
    for name, (law, bf) in list(DAMPED.items())[:1] if quick else DAMPED.items():
        for n in sizes:
            h = heights(n)
            t = time_call(
                lambda: blocked(rbjax.simulate(h, damping=law, blocked_force=bf)),
                min_repeats=2,
                min_time_s=0.3,
            )
            res = rbjax.simulate(h, damping=law, blocked_force=bf)
            row(
                rows,
                "damped",
                f"simulate() {name} (auto)",
                n,
                t,
                path=res.path,
                max_rel_err_vs_scipy=reference_error(res, n, damping=law, blocked_force=bf),
                mean_steps=float(np.mean(np.asarray(res.num_steps))),
            )


def histories(rows, sizes, quick=False):
    """The 44.1 kHz × 1 s force record and its octave-band L_FE through the public API: the
    record's contact samples (``res.history(pad=False)``: every non-zero sample) and
    ``lfe_octave_dB(..., n_record=44 100)`` (exact for the zero-padded record)."""
    n_record = int(RATE_HZ)
    for model_name, kwargs in (
        ("elastic", {}),
        ("zener", {"damping": DAMPED["zener"][0], "blocked_force": "momentum"}),
    )[: 1 if quick else 2]:
        for n in sizes:
            h = heights(n)

            def run():
                force = rbjax.simulate(h, **kwargs).history(pad=False).force_N
                return force, lfe_octave_dB(force, RATE_HZ, n_record=n_record)

            t = time_call(run, min_repeats=2, min_time_s=0.3, max_repeats=5)
            ref = reference_impact(
                h[-1],
                BALL,
                **(
                    {}
                    if not kwargs
                    else {"damping": kwargs["damping"], "blocked_force": "momentum"}
                ),
            )
            ref_lfe = np.asarray(lfe_octave_dB(ref.force_N(np.arange(n_record) / RATE_HZ), RATE_HZ))
            err = float(np.max(np.abs(np.asarray(t["out"][1])[-1] - ref_lfe)))
            samples = int(np.shape(t["out"][0])[-1])
            row(
                rows,
                "history",
                f"simulate(...).history(pad=False) + lfe_octave_dB(n_record), {model_name}",
                n,
                t,
                lfe_max_abs_err_dB_vs_scipy=err,
                contact_samples=samples,
            )


def jacobians(rows, sizes, quick=False):
    zener0 = DAMPED["zener"][0]

    def quad(th, h):
        r = rbjax.simulate(h, BALL.replace(youngs_Pa=th[0], poisson=th[1]))
        return jnp.stack([getattr(r, k) for k in SCALARS])

    def angle(th, h):
        zener = rbjax.Zener(stiffness_ratio=zener0.stiffness_ratio, relaxation_time_s=th[2])
        r = rbjax.simulate(
            h, BALL.replace(youngs_Pa=th[0], poisson=th[1]), damping=zener, blocked_force="momentum"
        )
        assert r.path == "angle"
        return jnp.stack([getattr(r, k) for k in SCALARS])

    def value_and_jacobian(f):
        return jax.jacfwd(lambda th, h: (f(th, h), f(th, h)), has_aux=True)

    cases = (
        ("quadrature (elastic), d/d(E, ν)", quad, np.array([1.6e6, 0.45])),
        ("angle (zener), d/d(E, ν, τ)", angle, np.array([1.6e6, 0.45, 2e-3])),
    )
    for name, f, theta in cases[:1] if quick else cases:  # quick: the angle's jacfwd takes ~20 s
        forward = jax.jit(jax.vmap(f))
        both = jax.jit(jax.vmap(value_and_jacobian(f)))
        for n in sizes:
            h = jnp.asarray(heights(n))
            th = jnp.tile(jnp.asarray(theta), (n, 1))
            tf = time_call(lambda: forward(th, h), min_repeats=3, min_time_s=0.3)
            tj = time_call(lambda: both(th, h), min_repeats=3, min_time_s=0.3)
            jac = np.asarray(tj["out"][0])
            row(rows, "jacobian", f"{name}: forward", n, tf)
            row(
                rows,
                "jacobian",
                f"{name}: value + jacfwd",
                n,
                tj,
                ratio_to_forward=tj["median_s"] / tf["median_s"],
                jacobian_finite=bool(np.all(np.isfinite(jac))),
            )
            if n > CHUNK:
                # the same in blocks of CHUNK impacts (jax.lax.map over jax.vmap): the tangents of a
                # 10 000 batch outgrow the caches; a block's stay in them
                shape = (n // CHUNK, CHUNK)
                forward_c = jax.jit(
                    lambda th, h: jax.lax.map(
                        lambda a: jax.vmap(f)(*a), (th.reshape(*shape, -1), h.reshape(shape))
                    )
                )
                both_c = jax.jit(
                    lambda th, h: jax.lax.map(
                        lambda a: jax.vmap(value_and_jacobian(f))(*a),
                        (th.reshape(*shape, -1), h.reshape(shape)),
                    )
                )
                tf = time_call(lambda: forward_c(th, h), min_repeats=3, min_time_s=0.3)
                tj = time_call(lambda: both_c(th, h), min_repeats=3, min_time_s=0.3)
                row(rows, "jacobian", f"{name}: forward, blocks of {CHUNK}", n, tf)
                row(
                    rows,
                    "jacobian",
                    f"{name}: value + jacfwd, blocks of {CHUNK}",
                    n,
                    tj,
                    ratio_to_forward=tj["median_s"] / tf["median_s"],
                )


FIRST_CALL = """
import sys, time
t0 = time.perf_counter()
import numpy as np, jax, rbjax
kind, n = sys.argv[1], int(sys.argv[2])
kw = {} if kind == "elastic" else {"damping": rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3), "blocked_force": "momentum"}
h = np.linspace(0.1, 1.6, n)
t1 = time.perf_counter()
r = rbjax.simulate(h, **kw); jax.block_until_ready(r.contact_time_s)
t2 = time.perf_counter()
r = rbjax.simulate(h, **kw); jax.block_until_ready(r.contact_time_s)
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2, r.path)
"""  # noqa: E501


def first_calls(n, quick=False):
    """First ``simulate`` call in a fresh process (JAX's persistent cache is off unless asked for:
    the library never switches it on), minus the second call: trace + compile."""
    out = {}
    for kind in ("elastic",) if quick else ("elastic", "zener"):
        res = subprocess.run(
            [sys.executable, "-c", FIRST_CALL, kind, str(n)],
            capture_output=True,
            text=True,
            cwd=HERE,
            env={"PYTHONPATH": str(REPO / "src"), "PATH": "/usr/bin:/bin", "JAX_PLATFORMS": "cpu"},
        )
        try:
            imp, first, second, path = res.stdout.split()
            out[kind] = {
                "import_s": float(imp),
                "first_call_s": float(first),
                "second_call_s": float(second),
                "compile_s": float(first) - float(second),
                "path": path,
            }
        except ValueError:
            print(res.stderr[-2000:])
            out[kind] = None
        print(f"first call  {kind:8s} batch {n}: {out[kind]}", flush=True)
    return out


# ------------------------------------------------------------------------------------------------


def targets(data) -> list[list]:
    rows, compile_ = data["rows"], data["first_call"]
    scipy = data["scipy_per_impact_s"]

    def find(workload, prefix, n):
        return next(
            (
                r
                for r in rows
                if r["workload"] == workload and r["variant"].startswith(prefix) and r["batch"] == n
            ),
            None,
        )

    out = []

    def add(target, measured, met, how):
        out.append([target, measured, "met" if met else "**missed**", how])

    n = 10_000
    auto = find("scalar", "simulate(path='auto')", n)
    if auto:
        add(
            "default simulate, elastic + gas, batch 10 000, scalars: ≥ 1 000 000 impacts/s",
            f"{auto['impacts_per_s']:,.0f}/s",
            auto["impacts_per_s"] >= 1e6,
            f"path {auto['path']}; contact time within "
            f"{fmt(auto['max_rel_err_vs_scipy']['contact_time_s'], '.1e')} of scipy",
        )
        speedup = scipy / (auto["median_s"] / n)
        add(
            "… and ≥ 3000× the scipy solve_ivp loop",
            f"{speedup:,.0f}×",
            speedup >= 3000,
            f"scipy loop {1 / scipy:,.0f} impacts/s in the same run",
        )
    for kind in ("elastic", "zener"):
        c = compile_.get(kind)
        if c:
            add(
                f"first-call compile of the default simulate ≤ 5 s ({kind}, batch "
                f"{data['first_call_batch']})",
                f"{c['compile_s']:.1f} s",
                c["compile_s"] <= 5.0,
                f"path {c['path']}; fresh process, first − second call",
            )
    for r in rows:
        if r["workload"] == "jacobian" and "ratio_to_forward" in r:
            blocks = "blocks of" in r["variant"]
            add(
                f"value + Jacobian ≤ 3× forward: {r['variant'].split(':')[0]}, batch {r['batch']}"
                + (f" (blocks of {CHUNK})" if blocks else ""),
                f"{r['ratio_to_forward']:.2f}×",
                r["ratio_to_forward"] <= 3.0,
                f"jax.lax.map over jax.vmap(jax.jacfwd), {CHUNK} per block"
                if blocks
                else "jax.vmap(jax.jacfwd)",
            )
    for name in DAMPED:
        r = find("damped", f"simulate() {name}", n)
        if r:
            add(
                f"damped model ({name}), batch 10 000: ≥ 300 000 impacts/s",
                f"{r['impacts_per_s']:,.0f}/s",
                r["impacts_per_s"] >= 3e5,
                f"path {r['path']}, {r['mean_steps']:.0f} steps/impact; contact time within "
                f"{fmt(r['max_rel_err_vs_scipy']['contact_time_s'], '.1e')} of scipy",
            )
    best = max(
        (r for r in rows if r["workload"] == "history"),
        key=lambda r: r["impacts_per_s"],
        default=None,
    )
    if best:
        add(
            "histories (44.1 kHz × 1 s) + octave L_FE: ≥ 20 000/s",
            f"{best['impacts_per_s']:,.0f}/s",
            best["impacts_per_s"] >= 2e4,
            f"{best['variant']}, batch {best['batch']}",
        )
    return out


def render(data) -> str:
    m = data["machine"]
    head = (
        f"{m['date']}, {m['cpu_model']} ×{m['nproc']}, jax {m['jax']}; load average (1/5/15 min) "
        f"{'/'.join(f'{x:.1f}' for x in m['loadavg_start'])} at start, "
        f"{'/'.join(f'{x:.1f}' for x in m['loadavg_end'])} at end; {data['wall_s']:.0f} s"
    )
    lines = [head, "", table(["target", "measured", "", "how"], targets(data)), ""]
    body = []
    for r in data["rows"]:
        notes = []
        for k in (
            "path",
            "speedup_vs_scipy",
            "ratio_to_forward",
            "mean_steps",
            "lfe_max_abs_err_dB_vs_scipy",
            "contact_samples",
        ):
            if r.get(k) is not None:
                notes.append(f"{k} {fmt(r[k], '.3g') if isinstance(r[k], float) else r[k]}")
        if r.get("max_rel_err_vs_scipy"):
            notes.append(
                "max rel err vs scipy "
                + ", ".join(
                    f"{k.split('_')[0]} {v:.1e}" for k, v in r["max_rel_err_vs_scipy"].items()
                )
            )
        body.append(
            [
                r["workload"],
                r["variant"],
                r["batch"],
                fmt(r["impacts_per_s"], ",.0f"),
                fmt(r["first_s"], ".2f"),
                fmt(r["median_s"] * 1e3, ".3g"),
                "; ".join(notes),
            ]
        )
    lines += [
        table(
            ["workload", "variant", "batch", "impacts/s", "first call (s)", "median (ms)", "notes"],
            body,
        )
    ]
    return "\n".join(lines)


def main(quick: bool = False) -> None:
    info = machine_info()
    t_start = time.perf_counter()
    rows: list[dict] = []
    scipy_row = scipy_loop(rows, quick)
    scipy_per_impact = scipy_row["median_s"] / scipy_row["batch"]
    # quick: one size, one model per workload (each compiles for seconds)
    elastic_scalars(rows, [100] if quick else [1, 1000, 10_000, 100_000], scipy_per_impact)
    damped_scalars(rows, [100] if quick else [1000, 10_000], quick)
    histories(rows, [10] if quick else [100, 1000], quick)
    jacobians(rows, [10] if quick else [1, 1000, 10_000], quick)
    n_first = 100 if quick else 10_000
    first = first_calls(n_first, quick)
    data = {
        "machine": finish_machine_info(info),
        "quick": quick,
        "rows": rows,
        "scipy_per_impact_s": scipy_per_impact,
        "first_call": first,
        "first_call_batch": n_first,
        "wall_s": time.perf_counter() - t_start,
    }
    write_json("forward_speed" + ("_quick" if quick else ""), data)
    print()
    print(render(data))

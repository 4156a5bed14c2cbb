"""Work–precision of the forward model: error against wall time per solve, per diffrax method.

The JIS ball (paper §4: R = 89 mm, h = 32 mm, M = 2.5 kg, E = 1.6 MPa, ν = 0.5; elastic model of
Eq. 7 with the adiabatic gas force, paper blocked force) at drop heights 0.1, 1.0 and 1.6 m.

* Adaptive methods (bosh3, tsit5, dopri5, dopri8, kvaerno5): rtol 1e-3 … 1e-12, atol = 1e-3·rtol
  (the state is δ in m, ~0.03, and δ̇ in m/s, ~1–5; the library default pair 1e-9/1e-12 has the
  same ratio). Fixed-step methods (euler, heun, midpoint): step_s swept.
* Reference: the quadrature path (rbjax.solve.quadrature, Eq. 7 integrated in δ by
  Gauss–Legendre rules, 64 nodes) for the scalars and its force history (48 nodes); cross-checked
  against scipy DOP853 at rtol 1e-13 and diffrax Dopri8 at rtol 1e-13 (the reference floor,
  printed).
* Errors (maximum over the three heights): relative contact time, peak force and restitution; the
  force history on the 44.1 kHz grid over the contact (relative L2, paper §2.4); the octave-band
  force exposure level L_FE (paper Eq. 11) of the 1 s record, max |ΔL| over 31.5 Hz–1 kHz, dB.
* Cost: median wall time of ``rbjax.solve.impact_batch`` (the core of ``rbjax.simulate``) on a
  batch of heights (1000, from 0.1 to 1.6 m) divided by the batch size, after the compiling call.
  One compile per method: tolerances are traced (``_common.SweepSolver``).
* Levers on the same chart: tsit5 with the forward-mode adjoint (``Solver(adjoint="forward")``),
  and the quadrature path (``impact_quadrature_batch``) over its node count.

Run: ``.venv/bin/python benchmarks/work_precision.py [--quick]``.
"""

from __future__ import annotations

import math
import time

import jax.numpy as jnp
import numpy as np

import rbjax
from rbjax import Model
from rbjax.solve import (
    force_history_quadrature,
    impact_batch,
    impact_quadrature_batch,
    trajectory_batch,
)
from rbjax.spectrum import lfe_octave_dB

from _common import (
    RESULTS_DIR,
    block,
    broadcast_inputs,
    finish_machine_info,
    fmt,
    machine_info,
    quadrature_reference,
    sweep_solver,
    table,
    time_call,
    write_json,
)

HEIGHTS_M = (0.1, 1.0, 1.6)
RATE_HZ = 44_100.0
ADAPTIVE = ("bosh3", "tsit5", "dopri5", "dopri8", "kvaerno5")
FIXED = ("euler", "heun", "midpoint")
TARGET_REL = 1e-6  # the forward-model tests' tolerance on contact time, peak force, restitution
SCALARS = ("contact_time_s", "peak_force_N", "restitution")


def configs(quick: bool):
    rtols = [1e-7] if quick else [10.0**-k for k in range(3, 13)]
    steps = [1e-4] if quick else [1e-4, 3e-5, 1e-5, 3e-6, 1e-6]
    methods = ("tsit5", "heun") if quick else ADAPTIVE + FIXED  # quick: one adaptive, one fixed
    out = []
    for m in methods:
        if m in FIXED:
            out += [dict(method=m, adjoint="reverse", step_s=s) for s in steps]
        else:
            out += [dict(method=m, adjoint="reverse", rtol=r, atol=1e-3 * r) for r in rtols]
    if not quick:  # quick: no forward-adjoint series (another compile)
        out += [dict(method="tsit5", adjoint="forward", rtol=r, atol=1e-3 * r) for r in rtols]
    return out


def status_counts(status):
    from rbjax import STATUS_NAMES

    names, counts = np.unique(np.asarray(status), return_counts=True)
    return {STATUS_NAMES[int(k)]: int(c) for k, c in zip(names, counts)}


def series_name(c):
    if c.get("quadrature"):
        return "quadrature"
    return c["method"] + (" (forward adjoint)" if c["adjoint"] == "forward" else "")


def lfe_of(force_window):
    """Octave L_FE of the 1 s, 44.1 kHz record: the contact window zero-padded (paper §2.4)."""
    n = int(RATE_HZ)
    padded = jnp.pad(jnp.asarray(force_window), ((0, 0), (0, n - force_window.shape[-1])))
    return np.asarray(lfe_octave_dB(padded, RATE_HZ))


def main(quick: bool = False) -> None:
    info = machine_info()
    t_start = time.perf_counter()
    ball = rbjax.JIS_RUBBER_BALL
    model = Model()
    batch = 100 if quick else 1000
    heights = np.concatenate([HEIGHTS_M, np.linspace(0.1, 1.6, batch - len(HEIGHTS_M))])
    _, h_all, b_all, m_all = broadcast_inputs(heights, ball, model)
    _, h3, b3, m3 = broadcast_inputs(np.asarray(HEIGHTS_M), ball, model)

    # ---- references ---------------------------------------------------------------------------
    ref = quadrature_reference(HEIGHTS_M, n_nodes=64)
    n_t = int(math.ceil(ref["contact_time_s"].max() * RATE_HZ)) + 2
    times = jnp.arange(n_t) / RATE_HZ
    ref_force = np.stack(
        [
            np.asarray(force_history_quadrature(h, ball, model, times, n_nodes=48).force_N)
            for h in HEIGHTS_M
        ]
    )
    ref_lfe = lfe_of(ref_force)

    import scipy_reference as sr

    floor = {}
    sp = [sr.reference_impact(h, ball, rtol=1e-13) for h in HEIGHTS_M]
    floor["scipy DOP853 rtol 1e-13"] = {
        "contact_time_s": max(
            abs(s.contact_time_s / ref["contact_time_s"][i] - 1) for i, s in enumerate(sp)
        ),
        "peak_force_N": max(
            abs(s.peak_force_N / ref["peak_force_N"][i] - 1) for i, s in enumerate(sp)
        ),
        "restitution": max(
            abs(s.restitution / ref["restitution"][i] - 1) for i, s in enumerate(sp)
        ),
        "force_L2": max(
            np.linalg.norm(s.force_N(np.asarray(times)) - ref_force[i])
            / np.linalg.norm(ref_force[i])
            for i, s in enumerate(sp)
        ),
    }
    # quick: the diffrax reference reuses the sweep's tsit5 program (dopri8 compiles for seconds)
    d8 = (
        sweep_solver("tsit5", rtol=1e-7, atol=1e-10)
        if quick
        else sweep_solver("dopri8", rtol=1e-13, atol=1e-16)
    )
    o = impact_batch(h3, b3, m3, d8)
    f8 = np.asarray(trajectory_batch(h3, b3, m3, d8, times).force_N)
    floor["diffrax dopri8 rtol 1e-13"] = {
        **{k: float(np.max(np.abs(np.asarray(getattr(o, k)) / ref[k] - 1))) for k in SCALARS},
        "force_L2": float(
            np.max(np.linalg.norm(f8 - ref_force, axis=-1) / np.linalg.norm(ref_force, axis=-1))
        ),
        "lfe_dB": float(np.max(np.abs(lfe_of(f8) - ref_lfe))),
    }

    # ---- the sweep -----------------------------------------------------------------------------
    rows = []
    for c in configs(quick):
        fixed = "step_s" in c
        solver = sweep_solver(
            c["method"],
            rtol=c.get("rtol", 1e-9),
            atol=c.get("atol", 1e-12),
            step_s=c.get("step_s", 1e-5),
            max_steps=16384 if fixed else 4096,
            adjoint=c["adjoint"],
        )
        timing = time_call(
            lambda: impact_batch(h_all, b_all, m_all, solver), min_repeats=2 if quick else 3
        )
        out = timing["out"]
        status = np.asarray(out.status)
        err = {
            k: float(np.max(np.abs(np.asarray(getattr(out, k))[:3] / ref[k] - 1))) for k in SCALARS
        }
        traj = block(trajectory_batch(h3, b3, m3, solver, times))
        force = np.asarray(traj.force_N)
        err["force_L2"] = float(
            np.max(np.linalg.norm(force - ref_force, axis=-1) / np.linalg.norm(ref_force, axis=-1))
        )
        err["lfe_dB"] = float(np.max(np.abs(lfe_of(force) - ref_lfe)))
        row = {
            **c,
            "series": series_name(c),
            "per_solve_s": timing["median_s"] / batch,
            "first_call_s": timing["first_s"],
            "mean_steps": float(np.mean(np.asarray(out.num_steps))),
            "max_steps_taken": int(np.max(np.asarray(out.num_steps))),
            "ok_fraction": float(np.mean(status == 0)),
            "status_counts": status_counts(status),
            "errors": err,
        }
        rows.append(row)
        print(
            f"{row['series']:26s} {c.get('rtol', c.get('step_s')):8.0e}  "
            f"{row['per_solve_s'] * 1e6:9.2f} µs/solve  steps {row['mean_steps']:7.1f}  ok "
            f"{row['ok_fraction']:.2f}  tc {err['contact_time_s']:.1e}  F "
            f"{err['peak_force_N']:.1e}  e {err['restitution']:.1e}  L2 {err['force_L2']:.1e}  "
            f"LFE {err['lfe_dB']:.1e} dB  (first call {timing['first_s']:.1f} s) "
            f"{row['status_counts']}",
            flush=True,
        )

    # quadrature path, over its node count (static: one compile each)
    for n in [12] if quick else [4, 6, 8, 10, 12, 16, 24, 32]:
        timing = time_call(
            lambda: impact_quadrature_batch(h_all, b_all, m_all, n), min_repeats=2 if quick else 3
        )
        out = timing["out"]
        err = {
            k: float(np.max(np.abs(np.asarray(getattr(out, k))[:3] / ref[k] - 1))) for k in SCALARS
        }
        row = {
            "quadrature": True,
            "n_nodes": n,
            "series": "quadrature",
            "per_solve_s": timing["median_s"] / batch,
            "first_call_s": timing["first_s"],
            "ok_fraction": float(np.mean(np.asarray(out.status) == 0)),
            "errors": err,
        }
        rows.append(row)
        print(
            f"{'quadrature':26s} n={n:<6d}  {row['per_solve_s'] * 1e6:9.2f} µs/solve  tc "
            f"{err['contact_time_s']:.1e}  F {err['peak_force_N']:.1e}  e {err['restitution']:.1e}",
            flush=True,
        )

    damped = damped_models(quick)
    knees = pick_knees(rows)
    data = {
        "machine": finish_machine_info(info),
        "quick": quick,
        "heights_m": HEIGHTS_M,
        "timing_batch": batch,
        "atol_over_rtol": 1e-3,
        "reference": (
            "rbjax.solve.quadrature n_nodes=64 (scalars), force_history_quadrature n_nodes=48 "
            "(history)"
        ),
        "reference_floor": floor,
        "target_rel": TARGET_REL,
        "rows": rows,
        "knees": knees,
        "damped_models": damped,
        "wall_s": time.perf_counter() - t_start,
    }
    write_json("work_precision" + ("_quick" if quick else ""), data)
    plot(rows, floor, quick)
    print()
    print("reference floor:", floor)
    print(knee_table(knees))
    print(f"total {data['wall_s']:.0f} s")


DAMPED = {
    # the damped configurations of tests/test_impact_reference.py (moderate damping)
    "kelvin-voigt c=100": dict(damping=rbjax.KelvinVoigt(100.0)),
    "hunt-crossley a=0.5": dict(damping=rbjax.HuntCrossley(0.5)),
    "zener r=0.3 tau=1ms, momentum": dict(damping=rbjax.Zener(0.3, 1e-3), blocked_force="momentum"),
    "kelvin-voigt 3x critical": dict(
        damping=rbjax.KelvinVoigt(
            3.0 * 2.0 * math.sqrt(float(rbjax.JIS_RUBBER_BALL.stiffness_N_per_m) * 2.5)
        )
    ),
}


def damped_models(quick):
    """Scalar errors of tsit5 against the scipy reference for the damped models, per rtol
    (atol = 1e-3·rtol): does the recommended tolerance hold beyond the elastic model?"""
    import scipy_reference as sr

    ball = rbjax.JIS_RUBBER_BALL
    rtols = [1e-7] if quick else [1e-5, 1e-6, 1e-7, 1e-8, 1e-9]
    out = {}
    for name, options in list(DAMPED.items())[:1] if quick else DAMPED.items():
        refs = [sr.reference_impact(h, ball, **options) for h in HEIGHTS_M]
        _, h, b, m = broadcast_inputs(np.asarray(HEIGHTS_M), ball, Model(**options))
        out[name] = {}
        for rtol in rtols:
            res = impact_batch(h, b, m, sweep_solver("tsit5", rtol=rtol, atol=1e-3 * rtol))
            err = {
                k: float(
                    np.max(
                        np.abs(
                            np.asarray(getattr(res, k)) / np.array([getattr(r, k) for r in refs])
                            - 1
                        )
                    )
                )
                for k in SCALARS
            }
            out[name][f"{rtol:.0e}"] = {
                "errors": err,
                "mean_steps": float(np.mean(np.asarray(res.num_steps))),
            }
            print(
                f"damped  {name:32s} tsit5 rtol {rtol:.0e}: "
                + "  ".join(f"{k} {v:.1e}" for k, v in err.items())
                + f"  steps {out[name][f'{rtol:.0e}']['mean_steps']:.0f}",
                flush=True,
            )
    return out


def pick_knees(rows):
    """Per series: the cheapest setting whose scalar errors are all ≤ TARGET_REL, and the cheapest
    with a 100× margin (≤ 1e-8), the margin that covers other parameters and models."""
    knees = {}
    for name in sorted({r["series"] for r in rows}):
        mine = sorted((r for r in rows if r["series"] == name), key=lambda r: r["per_solve_s"])
        for label, tol in (("target", TARGET_REL), ("margin_100x", TARGET_REL / 100)):
            ok = [
                r
                for r in mine
                if r["ok_fraction"] == 1.0 and all(r["errors"][k] <= tol for k in SCALARS)
            ]
            if ok:
                r = ok[0]
                knees.setdefault(name, {})[label] = {
                    k: r.get(k)
                    for k in ("rtol", "atol", "step_s", "n_nodes", "per_solve_s", "mean_steps")
                } | {"errors": r["errors"]}
    return knees


def knee_table(knees):
    rows = []
    for name, k in knees.items():
        for label, r in k.items():
            setting = (
                f"rtol {r['rtol']:.0e}"
                if r.get("rtol")
                else f"step {r['step_s']:.0e} s"
                if r.get("step_s")
                else f"n={r['n_nodes']}"
            )
            e = r["errors"]
            rows.append(
                [
                    name,
                    label,
                    setting,
                    fmt(r["per_solve_s"] * 1e6),
                    fmt(r.get("mean_steps")),
                    fmt(e["contact_time_s"], ".1e"),
                    fmt(e["peak_force_N"], ".1e"),
                    fmt(e["restitution"], ".1e"),
                    fmt(e.get("force_L2"), ".1e"),
                    fmt(e.get("lfe_dB"), ".1e"),
                ]
            )
    return table(
        [
            "series",
            "criterion",
            "setting",
            "µs/solve",
            "steps",
            "tc err",
            "F err",
            "e err",
            "history L2",
            "L_FE dB",
        ],
        rows,
    )


def plot(rows, floor, quick):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [
        ("contact_time_s", "contact time, relative error"),
        ("peak_force_N", "peak force, relative error"),
        ("restitution", "restitution, relative error"),
        ("force_L2", "force history (44.1 kHz), relative L2"),
        ("lfe_dB", "octave L_FE, max |ΔL| (dB)"),
    ]
    fig, axes = plt.subplots(2, 3, figsize=(16, 9.5))
    names = sorted({r["series"] for r in rows}, key=lambda s: (s == "quadrature", s))
    cmap = plt.get_cmap("tab10")
    for ax, (key, title) in zip(axes.flat, panels):
        for i, name in enumerate(names):
            pts = [
                (r["per_solve_s"], r["errors"].get(key))
                for r in rows
                if r["series"] == name and r["errors"].get(key) is not None
            ]
            pts = [(t, max(e, 1e-17)) for t, e in pts if math.isfinite(e)]
            if not pts:
                continue
            t, e = zip(*pts)
            style = "--" if "forward" in name else ":" if name == "quadrature" else "-"
            ax.loglog(
                np.asarray(t) * 1e6, e, style, marker="o", ms=3, color=cmap(i % 10), label=name
            )
            bad = [
                (r["per_solve_s"] * 1e6, r["errors"][key])
                for r in rows
                if r["series"] == name
                and r["ok_fraction"] < 1.0
                and r["errors"].get(key) is not None
                and math.isfinite(r["errors"][key])
            ]
            if bad:  # a status other than ok in the batch (the history itself carries no status)
                ax.loglog(*zip(*bad), "x", ms=9, mew=2, color="red")
        if key != "lfe_dB":
            ax.axhline(TARGET_REL, color="k", lw=0.8, ls="--")
        floor_val = (
            floor["scipy DOP853 rtol 1e-13"].get(key)
            if key in floor["scipy DOP853 rtol 1e-13"]
            else None
        )
        if floor_val:
            ax.axhline(floor_val, color="grey", lw=0.8, ls=":")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("wall time per solve (µs, batch of 1000, after compile)")
        ax.grid(True, which="both", alpha=0.3)
    axes.flat[0].legend(fontsize=7)
    ax = axes.flat[5]
    for i, name in enumerate(names):
        pts = [
            (r["per_solve_s"], r["mean_steps"])
            for r in rows
            if r["series"] == name and r.get("mean_steps")
        ]
        if pts:
            t, s = zip(*pts)
            ax.loglog(s, np.asarray(t) * 1e6, marker="o", ms=3, color=cmap(i % 10), label=name)
    ax.set_xlabel("accepted + rejected steps per impact (all phases)")
    ax.set_ylabel("µs per solve")
    ax.set_title("cost per step", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(
        "Work–precision, JIS ball at 0.1, 1.0, 1.6 m (max error over heights); dashed: 1e-6 "
        "target; dotted grey: scipy 1e-13 vs reference; red x: step_limit / solver_failed in the "
        "batch"
    )
    fig.tight_layout()
    RESULTS_DIR.mkdir(exist_ok=True)
    fig.savefig(RESULTS_DIR / ("work_precision" + ("_quick" if quick else "") + ".png"), dpi=110)
    plt.close(fig)

"""Where methods fail: success, flagged, step limit, wrong answer or NaN over the parameter space.

For every diffrax method (adaptive ones at the library default tolerance rtol 1e-9, atol 1e-12,
fixed-step ones at step_s = 10 µs; max_steps 4096 per phase; tsit5 also at the recommended
rtol 1e-7, atol 1e-10) over three slices of the parameter space of paper Eq. 7:

A. stiffness × drop height: E 10 kPa–1 GPa, h_D 1 mm–10 m; elastic model with the gas force.
B. damping × drop height: Kelvin–Voigt c from 0 to 5× critical, ζ = c / (2√(kM)), E = 1.6 MPa.
C. towards the mass singularity δ → 2R (the dynamic mass M(1 − δ/2R) of Eq. 6 vanishes):
   gas="none", max_deflection_ratio = 100 (so that only the singularity flags), E 10 kPa–10 MPa.

Each point is classified against an independent reference: the quadrature path at 64 nodes for the
elastic slices (A, C), scipy DOP853 at rtol 1e-12 (tests/scipy_reference.py) for the damped slice B.

* correct: status ok and contact time, peak force, restitution within 1e-6 relative;
* WRONG: status ok but an error above 1e-6 (silently wrong);
* flagged: deflection_limit or mass_singularity (the reference agrees the point is out of range);
* false flag: flagged although the reference finds a valid impact;
* step_limit; solver_failed; NaN: status ok with a non-finite output.

Run: ``.venv/bin/python benchmarks/accuracy.py --only stability_map [--quick]`` (quick: a 3 × 3
grid on slices A and B, Heun and Tsit5 only).
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

import rbjax
from rbjax import Model
from rbjax.solve import impact_batch, impact_quadrature_batch

from _common import (
    RESULTS_DIR,
    broadcast_inputs,
    finish_machine_info,
    machine_info,
    sweep_solver,
    table,
    write_json,
)

BALL = rbjax.JIS_RUBBER_BALL
TOL = 1e-6
SCALARS = ("contact_time_s", "peak_force_N", "restitution")
CLASSES = ("correct", "WRONG", "flagged", "false flag", "step_limit", "solver_failed", "NaN")
METHODS = (
    ("euler", {}),
    ("heun", {}),
    ("midpoint", {}),
    ("bosh3", {}),
    ("tsit5", {}),
    ("tsit5", {"rtol": 1e-7, "atol": 1e-10}),
    ("dopri5", {}),
    ("dopri8", {}),
    ("kvaerno5", {}),
)
FIXED_STEP_S = 1e-5
MAX_DEFLECTION_RATIO_C = 100.0


def critical_damping(youngs_Pa):
    ball = BALL.replace(youngs_Pa=youngs_Pa)
    return 2.0 * math.sqrt(float(ball.stiffness_N_per_m) * BALL.mass_kg)


def grids(n):
    heights = np.logspace(-3, 1, n)
    slices = {
        "A": {
            "title": "A: E × height (elastic, gas)",
            "x": heights,
            "y": np.logspace(4, 9, n),
            "ylabel": "E (Pa)",
        },
        "B": {
            "title": "B: Kelvin–Voigt ζ × height",
            "x": heights,
            "y": np.concatenate([[0.0], np.logspace(-2, math.log10(5.0), n - 1)]),
            "ylabel": "ζ = c / 2√(kM)",
        },
        "C": {
            "title": "C: E × height, gas none (δ → 2R)",
            "x": heights,
            "y": np.logspace(4, 7, n),
            "ylabel": "E (Pa)",
        },
    }
    return slices


def inputs(key, s):
    hh, yy = np.meshgrid(s["x"], s["y"])  # rows: y, columns: height
    if key == "A":
        return hh, BALL.replace(youngs_Pa=yy), Model()
    if key == "B":
        c = yy * critical_damping(BALL.youngs_Pa)
        return hh, BALL, Model(damping=rbjax.KelvinVoigt(damping_Ns_per_m=c))
    return (
        hh,
        BALL.replace(youngs_Pa=yy),
        Model(gas="none", max_deflection_ratio=MAX_DEFLECTION_RATIO_C),
    )


def reference(key, s):
    """Reference scalars and the expected flag (None: valid impact) on the slice's grid."""
    hh, ball, model = inputs(key, s)
    shape = hh.shape
    import scipy_reference as sr

    if key in ("A", "C"):
        _, h, b, m = broadcast_inputs(hh, ball, model)
        out = impact_quadrature_batch(h, b, m, 64)
        ref = {k: np.array(getattr(out, k)).reshape(shape) for k in SCALARS + ("max_deflection_m",)}
        ref["status"] = np.array(out.status).reshape(shape)
        # where 64 nodes are too few (δ_max within a few ‰ of 2R) the scipy ODE is the reference
        todo = ref["status"] == 4
        youngs = np.broadcast_to(np.asarray(ball.youngs_Pa), shape)
        options = {"gas": model.gas}
    else:
        ref = {k: np.full(shape, np.nan) for k in SCALARS + ("max_deflection_m",)}
        ref["status"] = np.zeros(shape, dtype=int)
        todo = np.ones(shape, dtype=bool)
        youngs = np.full(shape, float(BALL.youngs_Pa))
        c = np.broadcast_to(np.asarray(model.damping[0].damping_Ns_per_m), shape)
    for i, j in zip(*np.nonzero(todo)):
        if key == "B":
            options = {"damping": ("kv", float(c[i, j]))}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                r = sr.reference_impact(
                    hh[i, j], BALL.replace(youngs_Pa=float(youngs[i, j])), **options
                )
            except Exception:  # noqa: BLE001  (a reference that cannot solve the point)
                ref["status"][i, j] = -1
                continue
        for k in SCALARS + ("max_deflection_m",):
            ref[k][i, j] = getattr(r, k)
        ref["status"][i, j] = 0
        if r.max_deflection_m > model.max_deflection_ratio * BALL.wall_m:
            ref["status"][i, j] = 3
        elif r.max_deflection_m >= 0.999 * 2 * BALL.radius_m:
            ref["status"][i, j] = 2
    return ref


def classify(out, ref):
    status = np.asarray(out.status)
    err = np.max(
        np.stack([np.abs(np.asarray(getattr(out, k)) / ref[k] - 1) for k in SCALARS]), axis=0
    )
    finite = np.all(np.stack([np.isfinite(np.asarray(getattr(out, k))) for k in SCALARS]), axis=0)
    cls = np.full(status.shape, -1)
    ok = status == 0
    ref_valid = ref["status"] == 0
    cls[ok & finite & ref_valid & (err <= TOL)] = 0
    cls[ok & finite & ref_valid & (err > TOL)] = 1
    cls[ok & ~finite] = 6
    flagged = (status == 2) | (status == 3)
    cls[flagged & ~ref_valid] = 2
    cls[flagged & ref_valid] = 3
    cls[status == 1] = 4
    cls[status == 4] = 5
    cls[ok & finite & ~ref_valid] = 1  # ok although the reference finds the point out of range
    cls[ref["status"] == -1] = -1  # no reference
    return cls, np.where(ok & ref_valid, err, np.nan)


def main(quick: bool = False) -> None:
    info = machine_info()
    t0 = time.perf_counter()
    n = 3 if quick else 16
    slices = grids(n)
    if quick:  # slice C's reference near δ → 2R is scipy's, slow at its corners
        slices = {k: slices[k] for k in ("A", "B")}
    refs = {}
    for key, s in slices.items():
        t = time.perf_counter()
        refs[key] = reference(key, s)
        print(f"reference {key}: {time.perf_counter() - t:.1f} s", flush=True)
    methods = (
        METHODS if not quick else (("heun", {}), ("tsit5", {}))  # one fixed-step, one adaptive
    )
    results = []
    for method, tol in methods:
        label = method + (
            f" rtol {tol['rtol']:.0e}"
            if tol
            else (" step 10 µs" if method in ("euler", "heun", "midpoint") else " rtol 1e-09")
        )
        solver = sweep_solver(
            method, rtol=tol.get("rtol", 1e-9), atol=tol.get("atol", 1e-12), step_s=FIXED_STEP_S
        )
        entry = {"label": label, "method": method, "slices": {}}
        for key, s in slices.items():
            hh, ball, model = inputs(key, s)
            shape, h, b, m = broadcast_inputs(hh, ball, model)
            t = time.perf_counter()
            out = impact_batch(h, b, m, solver)
            out = type(out)(
                **{f: np.asarray(getattr(out, f)).reshape(shape) for f in out.__dataclass_fields__}
            )
            wall = time.perf_counter() - t
            cls, err = classify(out, refs[key])
            counts = {CLASSES[c]: int(np.sum(cls == c)) for c in range(len(CLASSES))}
            counts["no reference"] = int(np.sum(cls == -1))
            entry["slices"][key] = {
                "class": cls,
                "error": err,
                "status": out.status,
                "num_steps": out.num_steps,
                "counts": counts,
                "wall_s": wall,
            }
            print(
                f"{label:22s} {key}  {counts}  max steps {int(np.max(out.num_steps))}  "
                f"({wall:.1f} s)",
                flush=True,
            )
        results.append(entry)

    data = {
        "machine": finish_machine_info(info),
        "quick": quick,
        "tolerance_rel": TOL,
        "fixed_step_s": FIXED_STEP_S,
        "classes": CLASSES,
        "slices": {
            k: {
                "title": s["title"],
                "height_m": s["x"],
                "y": s["y"],
                "ylabel": s["ylabel"],
                "reference_status": refs[k]["status"],
            }
            for k, s in slices.items()
        },
        "results": results,
        "wall_s": time.perf_counter() - t0,
    }
    write_json("stability_map" + ("_quick" if quick else ""), data)
    plot(results, slices, quick)
    rows = [
        [e["label"]]
        + [
            " / ".join(
                str(e["slices"][k]["counts"][c])
                for c in (
                    "correct",
                    "WRONG",
                    "flagged",
                    "step_limit",
                    "solver_failed",
                    "NaN",
                    "false flag",
                )
            )
            for k in slices
        ]
        for e in results
    ]
    print(
        table(
            [
                "method",
                *(
                    f"{k}: correct / WRONG / flagged / step_limit / failed / NaN / false flag"
                    for k in slices
                ),
            ],
            rows,
        )
    )
    print(f"total {data['wall_s']:.0f} s")


def plot(results, slices, quick):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    colours = [
        "white",
        "#2ca02c",
        "#d62728",
        "#1f77b4",
        "#17becf",
        "#ff7f0e",
        "#9467bd",
        "black",
    ]  # -1 … 6
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(-1.5, 7.5), cmap.N)
    nrows = len(results)
    fig, axes = plt.subplots(nrows, 3, figsize=(13, 2.6 * nrows + 0.8), squeeze=False)
    for r, entry in enumerate(results):
        for c, (key, s) in enumerate(slices.items()):
            ax = axes[r, c]
            cls = entry["slices"][key]["class"]
            x, y = s["x"], s["y"]
            ax.pcolormesh(np.arange(len(x) + 1), np.arange(len(y) + 1), cls, cmap=cmap, norm=norm)
            xt = np.arange(0, len(x), max(1, len(x) // 4))
            ax.set_xticks(xt + 0.5, [f"{x[i]:.0e}" for i in xt], fontsize=7)
            ax.set_yticks(
                xt[xt < len(y)] + 0.5,
                [f"{y[i]:.1e}" if y[i] else "0" for i in xt if i < len(y)],
                fontsize=7,
            )
            if r == 0:
                ax.set_title(s["title"], fontsize=9)
            if r == nrows - 1:
                ax.set_xlabel("drop height (m)", fontsize=8)
            if c == 0:
                ax.set_ylabel(f"{entry['label']}\n{s['ylabel']}", fontsize=8)
            else:
                ax.set_ylabel(s["ylabel"], fontsize=7)
    handles = [Patch(color=colours[i + 1], label=name) for i, name in enumerate(CLASSES)] + [
        Patch(facecolor="white", edgecolor="k", label="no reference")
    ]
    fig.legend(handles=handles, loc="lower center", ncol=8, fontsize=8)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    RESULTS_DIR.mkdir(exist_ok=True)
    fig.savefig(RESULTS_DIR / ("stability_map" + ("_quick" if quick else "") + ".png"), dpi=90)
    plt.close(fig)

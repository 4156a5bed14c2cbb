"""Regenerate every benchmark result and the generated tables of benchmarks/RESULTS.md.

    .venv/bin/python benchmarks/run_all.py            # full run (~15 min on the 2-core CI box)
    .venv/bin/python benchmarks/run_all.py --quick    # smoke run (writes *_quick.json / .png)
    .venv/bin/python benchmarks/run_all.py --render   # only re-render RESULTS.md from the JSON

Runs work_precision.py, throughput.py, stability_map.py, multicore.py and forward_speed.py one
after the other (each in its own process, so compile caches do not leak between them), then
replaces the text between the
``<!-- generated:NAME -->`` and ``<!-- /generated:NAME -->`` markers of RESULTS.md (the prose
around them is written by hand and states the conclusions).
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

SCRIPTS = (
    "work_precision.py",
    "throughput.py",
    "stability_map.py",
    "multicore.py",
    "forward_speed.py",
)


def run(quick: bool, only=None) -> dict:
    walls = {}
    for script in only or SCRIPTS:
        t0 = time.perf_counter()
        cmd = [sys.executable, str(HERE / script)] + (["--quick"] if quick else [])
        print(f"== {' '.join(cmd)}", flush=True)
        subprocess.run(cmd, check=True, cwd=HERE)
        walls[script] = time.perf_counter() - t0
    return walls


# ------------------------------------------------------------------------------------------------
# rendering


def _machine(data):
    m = data["machine"]
    return (
        f"{m['date']}, {m['cpu_model']} ×{m['nproc']} (nproc), {m['platform']}, Python "
        f"{m['python']}, jax {m['jax']} / jaxlib {m['jaxlib']}, diffrax {m['diffrax']}, equinox "
        f"{m['equinox']}, scipy {m['scipy']}; load average (1/5/15 min) "
        f"{'/'.join(f'{x:.1f}' for x in m['loadavg_start'])} at start, "
        f"{'/'.join(f'{x:.1f}' for x in m['loadavg_end'])} at end; {data['wall_s']:.0f} s"
    )


def render_machine(wp, tp, sm):
    lines = []
    for name, d in (("work_precision", wp), ("throughput", tp), ("stability_map", sm)):
        if d:
            lines.append(f"- `{name}`: {_machine(d)}")
    return "\n".join(lines)


def render_work_precision(wp):
    from _common import fmt, table
    from work_precision import knee_table

    out = [knee_table(wp["knees"]), ""]
    floor = wp["reference_floor"]
    rows = [
        [k]
        + [
            fmt(v.get(f), ".1e")
            for f in ("contact_time_s", "peak_force_N", "restitution", "force_L2", "lfe_dB")
        ]
        for k, v in floor.items()
    ]
    out += [
        "Reference floor (disagreement with the quadrature reference):",
        "",
        table(["solution", "tc", "F", "e", "history L2", "L_FE dB"], rows),
        "",
    ]
    # every point
    rows = []
    for r in wp["rows"]:
        setting = (
            f"rtol {r['rtol']:.0e}"
            if r.get("rtol")
            else f"step {r['step_s']:.0e} s"
            if r.get("step_s")
            else f"n={r['n_nodes']}"
        )
        e = r["errors"]
        bad = {k: v for k, v in r.get("status_counts", {}).items() if k != "ok"}
        rows.append(
            [
                r["series"],
                setting,
                fmt(r["per_solve_s"] * 1e6),
                fmt(r.get("mean_steps"), ".4g"),
                *(
                    fmt(e.get(k), ".1e")
                    for k in ("contact_time_s", "peak_force_N", "restitution", "force_L2", "lfe_dB")
                ),
                ", ".join(f"{k} {v}" for k, v in bad.items()) or "all ok",
            ]
        )
    out += [
        "<details><summary>All work–precision points</summary>",
        "",
        table(
            [
                "series",
                "setting",
                "µs/solve",
                "steps",
                "tc",
                "F",
                "e",
                "history L2",
                "L_FE dB",
                "status (batch)",
            ],
            rows,
        ),
        "",
        "</details>",
        "",
    ]
    rows = []
    for name, per in wp.get("damped_models", {}).items():
        for rtol, v in per.items():
            e = v["errors"]
            rows.append(
                [
                    name,
                    rtol,
                    fmt(v["mean_steps"], ".3g"),
                    *(fmt(e[k], ".1e") for k in ("contact_time_s", "peak_force_N", "restitution")),
                ]
            )
    out += [
        "Damped models, tsit5 (atol = 1e-3·rtol) against the scipy reference at 0.1, 1.0, 1.6 m:",
        "",
        table(["model", "rtol", "steps", "tc", "F", "e"], rows),
    ]
    return "\n".join(out)


def render_throughput(tp):
    from _common import fmt, table

    out = []
    for workload in ("scalar", "bucketing", "history", "jacobian"):
        rows = []
        for r in tp["rows"]:
            if r["workload"] != workload:
                continue
            extra = []
            for k in (
                "mean_steps",
                "contact_rel_err",
                "lfe_max_abs_err_dB",
                "ratio_to_value",
                "speedup_vs_scipy",
                "mean_chunk_max_steps",
            ):
                if r.get(k) is not None:
                    extra.append(f"{k} {fmt(r[k], '.3g')}")
            rows.append(
                [
                    r["variant"],
                    r["batch"],
                    fmt(r["impacts_per_s"], ",.0f"),
                    fmt(r["first_s"], ".2f"),
                    fmt(r["compile_s"], ".2f"),
                    fmt(r["median_s"] * 1e3, ".3g"),
                    fmt(r["min_s"] * 1e3, ".3g"),
                    "; ".join(extra),
                ]
            )
        out += [
            f"**{workload}**",
            "",
            table(
                [
                    "variant",
                    "batch",
                    "impacts/s",
                    "first call (s)",
                    "compile (s)",
                    "median (ms)",
                    "min (ms)",
                    "notes",
                ],
                rows,
            ),
            "",
        ]
    cb = tp["compile_breakdown"]
    rows = [
        [
            k,
            fmt(v["trace_lower_s"], ".2f"),
            fmt(v["xla_compile_s"], ".2f"),
            v.get("stablehlo_lines"),
            v["hlo_lines_optimized"],
            v.get("while_loops", ""),
        ]
        for k, v in cb.items()
    ]
    out += [
        "**compile breakdown** (batch 1000): tracing + lowering to StableHLO vs XLA compile",
        "",
        table(
            [
                "variant",
                "trace+lower (s)",
                "XLA compile (s)",
                "StableHLO lines",
                "optimized HLO lines",
                "while loops",
            ],
            rows,
        ),
        "",
    ]
    c = tp["persistent_cache_first_call_s"]
    vf = tp["vector_field_eval_s_per_impact"]
    vf = vf if isinstance(vf, dict) else {"adiabatic": vf, "none": float("nan")}
    out.append(
        "First `rbjax.simulate(linspace(0.1, 1.6, 1000))` call in a fresh process: "
        f"{fmt(c.get('cold cache'), '.1f')} s with an empty JAX persistent compilation cache, "
        f"{fmt(c.get('warm cache'), '.1f')} s with it warm. One vector-field evaluation of Eq. 7, "
        f"vmapped over 10 000 impacts (min of repeats): {vf['adiabatic'] * 1e9:.1f} ns per impact "
        f"with the gas force, {vf['none'] * 1e9:.1f} ns without. scipy loop: "
        f"{tp['scipy_per_impact_s'] * 1e3:.2f} ms per impact."
    )
    return "\n".join(out)


def render_multicore(mc):
    from _common import fmt, table

    rows = [
        [
            r["variant"],
            r["devices"],
            r["batch"],
            fmt(r["impacts_per_s"], ",.0f"),
            fmt(r["best_impacts_per_s"], ",.0f"),
            fmt(r["first_s"], ".1f"),
            fmt(r["contact_rel_err"], ".1e"),
        ]
        for r in mc["rows"]
    ]
    return f"- `multicore`: {_machine(mc)}\n\n" + table(
        [
            "variant",
            "devices",
            "batch",
            "impacts/s (median)",
            "impacts/s (best)",
            "first call (s)",
            "contact time rel. err",
        ],
        rows,
    )


def render_targets(tp):
    from _common import table

    rows = tp["rows"]
    scipy = tp["scipy_per_impact_s"]
    acc = {}
    for r in rows:  # a variant's accuracy, measured at the sizes where the reference was computed
        if r.get("contact_rel_err") is not None:
            acc[r["variant"]] = max(acc.get(r["variant"], 0.0), r["contact_rel_err"])
    big = [
        r
        for r in rows
        if r["workload"] == "scalar" and r["batch"] >= 10_000 and acc.get(r["variant"], 1.0) <= 1e-6
    ]
    best = max(big, key=lambda r: r["impacts_per_s"]) if big else None
    ode = [r for r in big if r["variant"].startswith("ode")]
    best_ode = max(ode, key=lambda r: r["impacts_per_s"]) if ode else None
    hist = [r for r in rows if r["workload"] == "history"]
    best_hist = max(hist, key=lambda r: r["impacts_per_s"]) if hist else None
    jac = [r for r in rows if r["workload"] == "jacobian" and r.get("ratio_to_value") is not None]
    comp = [
        r
        for r in rows
        if r["workload"] == "scalar" and r["variant"].startswith("ode") and r["batch"] >= 1000
    ]
    t = []

    def line(target, value, met, how):
        t.append([target, value, "met" if met else "**missed**", how])

    if best:
        line(
            "scalar outputs, batch ≥ 10 000: ≥ 500 000 impacts/s",
            f"{best['impacts_per_s']:,.0f}/s",
            best["impacts_per_s"] >= 5e5,
            f"{best['variant']}, batch {best['batch']}",
        )
        line(
            "… and ≥ 2000× the scipy loop",
            f"{scipy / best['per_impact_s']:,.0f}×",
            scipy / best["per_impact_s"] >= 2000,
            best["variant"],
        )
    if best_ode:
        line(
            "(ODE path only) ≥ 500 000 impacts/s",
            f"{best_ode['impacts_per_s']:,.0f}/s",
            best_ode["impacts_per_s"] >= 5e5,
            f"{best_ode['variant']}, batch {best_ode['batch']}; "
            f"{scipy / best_ode['per_impact_s']:,.0f}× scipy",
        )
    if best_hist:
        line(
            "44.1 kHz history + octave L_FE: ≥ 20 000 impacts/s",
            f"{best_hist['impacts_per_s']:,.0f}/s",
            best_hist["impacts_per_s"] >= 2e4,
            f"{best_hist['variant']}, batch {best_hist['batch']}",
        )
    for r in jac:
        line(
            f"value + Jacobian ≤ 3× forward ({r['variant']}, batch {r['batch']})",
            f"{r['ratio_to_value']:.2f}×",
            r["ratio_to_value"] <= 3.0,
            "jax.jacfwd",
        )
    for r in comp:
        line(
            f"first-call compile of the batched forward ≤ 5 s ({r['variant']}, batch {r['batch']})",
            f"{r['compile_s']:.1f} s",
            r["compile_s"] <= 5.0,
            "first call − median",
        )
    return table(["target", "measured", "", "how"], t)


def render_stability(sm):
    from _common import table

    keys = list(sm["slices"])
    rows = []
    for e in sm["results"]:
        row = [e["label"]]
        for k in keys:
            c = e["slices"][k]["counts"]
            row.append(
                " / ".join(
                    str(c[n])
                    for n in (
                        "correct",
                        "WRONG",
                        "flagged",
                        "false flag",
                        "step_limit",
                        "solver_failed",
                        "NaN",
                    )
                )
            )
        rows.append(row)
    head = ["method"] + [f"{sm['slices'][k]['title']}" for k in keys]
    return (
        "Counts per slice: correct / WRONG / flagged (deflection_limit or mass_singularity, "
        "agreeing with the reference) / false flag / step_limit / solver_failed / NaN (of "
        + str(len(sm["slices"][keys[0]]["height_m"]) ** 2)
        + " points).\n\n"
        + table(head, rows)
    )


def render(quick: bool):
    from _common import read_json

    suffix = "_quick" if quick else ""
    wp, tp, sm, mc = (
        read_json(n + suffix)
        for n in ("work_precision", "throughput", "stability_map", "multicore")
    )
    path = HERE / ("RESULTS.md" if not quick else "RESULTS_quick.md")
    text = path.read_text() if path.exists() else (HERE / "RESULTS.md").read_text()
    parts = {"machine": render_machine(wp, tp, sm)}
    if wp:
        parts["work_precision"] = render_work_precision(wp)
    if tp:
        parts["throughput"] = render_throughput(tp)
        parts["targets"] = render_targets(tp)
    if sm:
        parts["stability"] = render_stability(sm)
    if mc:
        parts["multicore"] = render_multicore(mc)
    fs = read_json("forward_speed" + suffix)
    if fs:
        from forward_speed import render as render_forward_speed

        parts["forward_speed"] = render_forward_speed(fs)
    for name, body in parts.items():
        pattern = re.compile(rf"(<!-- generated:{name} -->\n).*?(<!-- /generated:{name} -->)", re.S)
        text, n = pattern.subn(lambda m: m.group(1) + body + "\n" + m.group(2), text)
        if n == 0:
            print(f"RESULTS.md has no marker for {name}")
    if quick:
        text = (
            text.replace("results/work_precision.png", "results/work_precision_quick.png")
            .replace("results/throughput.png", "results/throughput_quick.png")
            .replace("results/stability_map.png", "results/stability_map_quick.png")
        )
    path.write_text(text)
    print(f"wrote {path}")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="smoke run with small grids and batches")
    p.add_argument(
        "--render", action="store_true", help="only re-render RESULTS.md from the existing JSON"
    )
    p.add_argument(
        "--only", nargs="+", choices=SCRIPTS, help="run only these scripts (then render everything)"
    )
    args = p.parse_args()
    if not args.render:
        walls = run(args.quick, args.only)
        print(
            "wall time per script:",
            {k: f"{v:.0f} s" for k, v in walls.items()},
            f"total {sum(walls.values()):.0f} s",
        )
    render(args.quick)


if __name__ == "__main__":
    main()

"""Cost per impact of each optional term (ODE path, batch 1000): a term that is off is absent
from the compiled program, so the models without it run as before; a term that is on costs
what this table says.

Prints a table and writes ``results/term_cost.json``.
"""

from __future__ import annotations

import numpy as np

import rbjax
from rbjax.terms import floor_preset

from _common import finish_machine_info, machine_info, table, time_call, write_json

HEIGHTS = np.linspace(0.05, 2.0, 1000)
#: Values of the fitted hunt-crossley+ball-mode/momentum model (benchmarks/RESULTS.md, "Ball mode").
MODE = rbjax.BallMode(0.93, 59.0, 1.67)
HC = rbjax.HuntCrossley(0.033)

CASES = {
    "elastic (ode)": {},
    "elastic + ball mode": {"ball_mode": MODE},
    "hunt-crossley": {"damping": HC},
    "hunt-crossley + ball mode": {"damping": HC, "ball_mode": MODE},
    "zener": {"damping": rbjax.Zener(0.3, 2e-3)},
    "elastic on osb-15mm (infinite plate)": {"floor": floor_preset("osb-15mm")},
    "elastic on a 2-mode floating floor": {
        "floor": rbjax.ModalFloor([12.0, 4000.0], [50.0, 60.0], [0.1, 0.02])
    },
}


def main(quick: bool = False) -> None:
    info = machine_info()
    rows, out = [], {}
    heights = HEIGHTS[::10] if quick else HEIGHTS
    # quick: the elastic model and a damping law, 100 impacts (the coupled terms compile for long;
    # floors.py's quick run has a moving floor)
    cases = {k: CASES[k] for k in ("elastic (ode)", "hunt-crossley")} if quick else CASES
    for name, options in cases.items():

        def run(options=options):
            return rbjax.simulate(
                heights, blocked_force="momentum", path="ode", **options
            ).contact_time_s

        t = time_call(run)
        res = rbjax.simulate(heights, blocked_force="momentum", path="ode", **options)
        steps = float(np.mean(np.asarray(res.num_steps)))
        us = 1e6 * t["median_s"] / heights.size
        out[name] = {
            "per_impact_us": us,
            "compile_s": t["compile_s"],
            "mean_steps": steps,
            "ok": int(np.sum(np.asarray(res.status) == 0)),
        }
        rows.append(
            [
                name,
                f"{us:.1f}",
                f"{1e6 / us:,.0f}",
                f"{steps:.0f}",
                f"{t['compile_s']:.1f}",
                out[name]["ok"],
            ]
        )
        print(rows[-1], flush=True)
    print(
        table(
            [
                f"model (momentum, ODE path, batch {heights.size})",
                "µs/impact",
                "impacts/s",
                "steps",
                "first call (s)",
                "ok",
            ],
            rows,
        )
    )
    out["machine"] = finish_machine_info(info)
    print(f"wrote {write_json('term_cost' + ('_quick' if quick else ''), out)}")

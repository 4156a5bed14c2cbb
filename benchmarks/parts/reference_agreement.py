"""Agreement of rbjax's default settings with the independent scipy reference.

    .venv/bin/python benchmarks/reference_agreement.py          # prints a table, writes JSON

For the JIS ball at the paper's drop heights 10–160 cm, every model configuration of
issue #2 (gas adiabatic/none × blocked force paper/momentum) and the three damping
extensions, rbjax.simulate with its default Solver() against tests/scipy_reference.py
(DOP853, rtol 1e-12, terminal events; written from the physics, calls nothing of rbjax):
the largest relative error over the heights of the contact time, peak force, restitution
and of the 44.1 kHz force history (max |ΔF| over the peak force).
"""

from __future__ import annotations

import numpy as np

import rbjax

from _common import write_json
from scipy_reference import reference_impact  # tests/ is on sys.path via _common

HEIGHTS_M = np.round(np.arange(1, 17) * 0.1, 1)
RATE_Hz = 44_100.0
CONFIGS = [
    ("paper", "adiabatic", "paper", None),
    ("paper", "adiabatic", "momentum", None),
    ("paper", "none", "paper", None),
    ("paper", "none", "momentum", None),
    ("kelvin-voigt c=100 N·s/m", "adiabatic", "paper", rbjax.KelvinVoigt(damping_Ns_per_m=100.0)),
    ("hunt-crossley α=0.3 s/m", "adiabatic", "paper", rbjax.HuntCrossley(alpha_s_per_m=0.3)),
    (
        "zener r=0.3, τ=2 ms",
        "adiabatic",
        "momentum",
        rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3),
    ),
]


def measure(quick: bool = False) -> list[dict]:
    """``quick``: the paper's model and the Zener model (the quadrature and the phase-angle paths)
    at two heights."""
    rows = []
    ball = rbjax.JIS_RUBBER_BALL
    heights = HEIGHTS_M[[0, -1]] if quick else HEIGHTS_M
    for name, gas, bf, damping in [CONFIGS[0], CONFIGS[-1]] if quick else CONFIGS:
        res = rbjax.simulate(heights, ball, gas=gas, blocked_force=bf, damping=damping)
        res.raise_for_status()
        n = int(np.ceil(float(np.max(res.contact_time_s)) * RATE_Hz)) + 2
        times = np.arange(n) / RATE_Hz
        model = rbjax.Model(gas=gas, blocked_force=bf, damping=damping)
        hist = np.asarray(rbjax.trajectory(heights, times, ball, model).force_N)
        err = {"contact_time_s": [], "peak_force_N": [], "restitution": [], "history": []}
        for i, h in enumerate(heights):
            ref = reference_impact(float(h), ball, gas=gas, blocked_force=bf, damping=damping)
            for q in ("contact_time_s", "peak_force_N", "restitution"):
                err[q].append(abs(float(getattr(res, q)[i]) / getattr(ref, q) - 1.0))
            err["history"].append(
                float(np.max(np.abs(hist[i] - ref.force_N(times))) / ref.peak_force_N)
            )
        rows.append(
            {"model": name, "gas": gas, "blocked_force": bf, **{q: max(v) for q, v in err.items()}}
        )
    return rows


def main(quick: bool = False) -> None:
    rows = measure(quick)
    print(
        "| model | gas | blocked force | contact time | peak force | restitution | history (of "
        "peak) |"
    )
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['model']} | {r['gas']} | {r['blocked_force']} | {r['contact_time_s']:.1e} | "
            f"{r['peak_force_N']:.1e} | {r['restitution']:.1e} | {r['history']:.1e} |"
        )
    name = "reference_agreement" + ("_quick" if quick else "")
    heights = HEIGHTS_M[[0, -1]] if quick else HEIGHTS_M
    print(f"wrote {write_json(name, {'heights_m': heights.tolist(), 'rows': rows})}")

"""Arrest laws over their parameters: does every impact solve, and is its peak the largest floor
force?

An arrest law (``rbjax.WaveLimitedArrest``) passes its share of the wall column's flux to the
floor; where the share is steep (large n) the floor force falls within a fraction of a
millisecond as δ̇ passes v_a, and can peak narrowly inside one step of the motion. Over a grid of
laws (Young's modulus, v_a, n, Hunt–Crossley α, the contact layer) and heights 0.05–2 m, each
impact is solved by ``rbjax.simulate(path="ode")`` with the default ``Solver()``, and its force
history sampled at 400 kHz: the section counts the impacts not solved (status other than ok) and
the largest excess of a sample over the reported peak (relative; the peak is the largest floor
force, so a sample above it by more than the sampling's interpolation means a missed maximum).

    python benchmarks/accuracy.py --only arrest_peaks   # 192 laws × 40 heights (minutes)

``--quick``: two laws at four heights. The figures: docs/guides/ball-across-heights.md.
"""

from __future__ import annotations

import itertools
import time

import numpy as np

import rbjax

from _common import finish_machine_info, machine_info, table, write_json

RATE_Hz = 400_000.0
DURATION_S = 0.03


def laws(quick: bool):
    """(E, v_a, n, α, (y_ref, p)) of every law of the grid."""
    if quick:
        return [(1.95e6, 3.4, 35.0, 0.064, (1.2e-3, 3.5)), (1.6e6, 2.0, 100.0, 0.2, (0.3e-3, 1.5))]
    return list(
        itertools.product(
            [1.6e6, 1.95e6],
            [2.0, 3.0, 3.4, 4.5],
            [6.0, 20.0, 35.0, 100.0],
            [0.02, 0.064, 0.2],
            [(1.2e-3, 3.5), (0.3e-3, 1.5)],
        )
    )


def main(quick: bool = False) -> dict:
    info = machine_info()
    heights = np.linspace(0.05, 2.0, 4 if quick else 40)
    rows, t0 = [], time.perf_counter()
    for E, v_a, n, alpha, (y_ref, p) in laws(quick):
        model = rbjax.Model(
            damping=rbjax.HuntCrossley(alpha),
            layer=rbjax.ContactLayer(y_ref, p),
            arrest=rbjax.WaveLimitedArrest(v_a, n),
        )
        ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=E)
        res = rbjax.simulate(
            heights, ball, model, path="ode", rate_Hz=RATE_Hz, duration_s=DURATION_S
        )
        ok = np.asarray(res.status) == 0
        peak = np.asarray(res.peak_force_N)
        sampled = np.nanmax(np.asarray(res.force_N), axis=-1)
        excess = np.where(ok, sampled / peak - 1.0, -np.inf)
        rows.append(
            dict(
                youngs_Pa=E,
                arrest_speed_m_per_s=v_a,
                arrest_exponent=n,
                alpha_s_per_m=alpha,
                layer_deflection_m=y_ref,
                layer_exponent=p,
                not_solved=int((~ok).sum()),
                largest_excess=float(np.max(excess)),
            )
        )
    seconds = time.perf_counter() - t0
    worst = max(rows, key=lambda r: r["largest_excess"])
    summary = dict(
        laws=len(rows),
        heights=len(heights),
        not_solved=sum(r["not_solved"] for r in rows),
        largest_excess=worst["largest_excess"],
        worst_law=worst,
        seconds=seconds,
    )
    print(
        table(
            ["laws", "heights", "not solved", "largest sample above the peak (rel.)", "time (s)"],
            [
                [
                    summary["laws"],
                    summary["heights"],
                    summary["not_solved"],
                    f"{summary['largest_excess']:.2g}",
                    f"{seconds:.0f}",
                ]
            ],
        )
    )
    record = dict(
        machine=finish_machine_info(info),
        quick=quick,
        rate_Hz=RATE_Hz,
        heights_m=heights,
        summary=summary,
        laws=rows,
    )
    print("wrote", write_json("arrest_peaks" + ("_quick" if quick else ""), record))
    return record


if __name__ == "__main__":
    main()

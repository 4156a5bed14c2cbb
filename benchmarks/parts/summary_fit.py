"""Summary fits (``rbjax.fit.fit_summary``): recovery of a known model from figures simulated with
the paper's noise, and the warm time of a fit on 5 heights.

The truth is simulated by ``rbjax.simulate`` (contact time, peak force, restitution) and
``ImpactResult.lfe_octave_dB`` (octave bands 31.5–500 Hz), at 0.1, 0.2, 0.4, 0.8 and 1.6 m;
noise at the paper's level (0.1 ms; 1 % of the force; 0.01 on the restitution; 0.2 dB) is
added, ``--draws`` times with different seeds, and the model is fitted to each. Bars: every
parameter within its reported 2σ (the fraction of draws is printed: ~95 % expected); a fit on
5 heights ≤ 5 s warm (median of the draws after the first, which compiles).
Writes ``results/summary_fit.json``. ``--quick``: the paper's model, two draws (Kelvin–Voigt's first
fit compiles for a minute).

The benchmark calls ``rbjax.fit.fit_summary`` (what ``rbjax fit --summary`` runs) to time the fit
itself, without a process and a file around it.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

import rbjax
from rbjax.fit import fit_summary, model_from_name, summary_table

from _common import finish_machine_info, machine_info, write_json

HEIGHTS = (0.1, 0.2, 0.4, 0.8, 1.6)
BANDS = ("31.5", "63", "125", "250", "500")
CASES = {
    "paper": {"youngs_Pa": 1.9e6},
    "kelvin-voigt": {"youngs_Pa": 1.9e6, "damping_Ns_per_m": 40.0},
}


def truth_rows(name, truth, rng):
    ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=truth["youngs_Pa"])
    model = model_from_name(name, values=truth)
    res = rbjax.simulate(np.array(HEIGHTS), ball, model)
    lfe = np.asarray(res.lfe_octave_dB())
    rows = []
    for i, h in enumerate(HEIGHTS):
        row = {
            "height_m": h,
            "contact_time_s": float(res.contact_time_s[i]) + 1e-4 * rng.standard_normal(),
            "contact_time_s_sd": 1e-4,
        }
        peak = float(res.peak_force_N[i])
        row.update(
            peak_force_N=peak * (1 + 0.01 * rng.standard_normal()), peak_force_N_sd=0.01 * peak
        )
        row.update(
            restitution=float(res.restitution[i]) + 0.01 * rng.standard_normal(),
            restitution_sd=0.01,
        )
        for j, b in enumerate(BANDS):
            row[f"lfe_{b}_dB"] = float(lfe[i, j]) + 0.2 * rng.standard_normal()
            row[f"lfe_{b}_dB_sd"] = 0.2
        rows.append(row)
    return rows


def main(quick: bool = False) -> None:
    draws = 2 if quick else 10
    info = machine_info()
    out = {}
    print(
        f"{'model':<14} {'parameter':<18} {'truth':>10} {'within 2σ':>10} {'median |z|':>10}  "
        "first fit   warm fit (median)"
    )
    for name, truth in list(CASES.items())[:1] if quick else CASES.items():
        z = {k: [] for k in truth}
        times = []
        for seed in range(draws):
            rng = np.random.default_rng(seed)
            table = summary_table(truth_rows(name, truth, rng), source=f"{name} truth, seed {seed}")
            t0 = time.perf_counter()
            fit = fit_summary(table, name)
            times.append(time.perf_counter() - t0)
            for k, v in truth.items():
                p = fit.parameters[k]
                z[k].append((p.value - v) / p.std)
        warm = statistics.median(times[1:]) if len(times) > 1 else float("nan")
        row = {
            "truth": truth,
            "heights_m": HEIGHTS,
            "n_figures": len(HEIGHTS) * (3 + len(BANDS)),
            "first_s": times[0],
            "warm_median_s": warm,
            "within_2sigma": {k: float(np.mean(np.abs(v) <= 2)) for k, v in z.items()},
            "z": z,
        }
        out[name] = row
        for k, v in truth.items():
            print(
                f"{name:<14} {k:<18} {v:>10.4g} {row['within_2sigma'][k]:>10.0%} "
                f"{np.median(np.abs(z[k])):>10.2f}  {times[0]:8.1f} s  {warm:8.2f} s"
            )
    path = write_json(
        "summary_fit" + ("_quick" if quick else ""),
        {"machine": finish_machine_info(info), "draws": draws, "cases": out},
    )
    print(f"wrote {path}")

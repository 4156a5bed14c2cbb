"""The default fit against the accuracy bars of issue 25, and the sampled path against the ODE.

1. ``select_model`` with the default candidates and both blocked forces on all six bundled
   heights (what ``rbjax fit`` without ``--model`` does): the recommended model.
2. That model fitted to 0.1, 0.4, 1.0, 1.6 m, predicting 0.2 and 0.8 m (heights it never saw):
   contact time (bar 1 %), peak force (bar 1.5 %), L_FE at 31.5–250 Hz (bar 0.5 dB).
3. That model fitted on all heights on the sampled path (the default) and on the diffrax ODE
   path (``path="ode"``, the reference): every fitted parameter of the first within its
   reported 2σ of the second.

Prints tables and writes ``results/default_fit.json``. ``--quick``: parts 1 and 2 with
one candidate (hunt-crossley/momentum; the default selection takes minutes), no part 3 (the fit on
the ODE path compiles for minutes).
"""

from __future__ import annotations

import time

import numpy as np

from rbjax.data import examples_dir
from rbjax.fit import FitOptions, fit, prepare_data
from rbjax.spectrum import OCTAVE_BANDS
from rbjax.studies import select_model

from _common import finish_machine_info, held_out_rows, machine_info, write_json

FIT_HEIGHTS = (0.1, 0.4, 1.0, 1.6)
QUICK = {"candidates": ["hunt-crossley"], "blocked_forces": ("momentum",)}
PREDICT_HEIGHTS = (0.2, 0.8)
BARS = {"contact_time_pct": 1.0, "peak_force_pct": 1.5, "lfe_31.5-250_dB": 0.5}


def main(quick: bool = False) -> None:
    info = machine_info()
    data = prepare_data(examples_dir())
    t0 = time.perf_counter()
    selection = select_model(data, progress=False, **(QUICK if quick else {}))
    rec = selection.recommended
    print(selection.table())
    print(f"recommended: {rec.label} ({time.perf_counter() - t0:.1f} s)")

    held = fit(
        data,
        rec.model_name,
        blocked_force=rec.blocked_force,
        options=FitOptions(fit_heights=FIT_HEIGHTS),
        progress=False,
    )
    rows = []
    print(f"\n{rec.label} fitted to {FIT_HEIGHTS} m ({held.message}):")
    print("h (m) | Δt_c (%) | Δpeak (%) | " + " | ".join(f"ΔL {b}" for b in OCTAVE_BANDS) + " (dB)")
    for r in held_out_rows(held, PREDICT_HEIGHTS):
        lfe = np.asarray(r.lfe_octave_dB)
        met = {
            "contact_time": abs(r.contact_time_pct) <= BARS["contact_time_pct"],
            "peak_force": abs(r.peak_force_pct) <= BARS["peak_force_pct"],
            "lfe_31.5-250": bool(np.all(np.abs(lfe[:4]) <= BARS["lfe_31.5-250_dB"])),
        }
        rows.append({**vars(r), "bars_met": met})
        print(
            f"{r.height_m:.1f} | {r.contact_time_pct:+.2f} | {r.peak_force_pct:+.2f} | "
            + " | ".join(f"{x:+.2f}" for x in lfe)
            + f"   met: {met}"
        )

    compare, times, rms, messages = {}, [], [], []
    if not quick:
        compare, times, rms, messages = sampled_against_ode(data, rec)
    write_json(
        "default_fit" + ("_quick" if quick else ""),
        {
            "machine": finish_machine_info(info),
            "recommended": rec.label,
            "selection_s": selection.elapsed_s,
            "held_out": {"fit_heights_m": FIT_HEIGHTS, "rows": rows, "message": held.message},
            "sampled_vs_ode": {
                "parameters": compare,
                "rms_N": rms,
                "time_s": times,
                "messages": messages,
            },
        },
    )


def sampled_against_ode(data, rec):
    """Part 3: the recommended model on all heights, on the sampled path and on the ODE."""
    t1 = time.perf_counter()
    sampled = fit(data, rec.model_name, blocked_force=rec.blocked_force, progress=False)
    t_sampled = time.perf_counter() - t1
    t1 = time.perf_counter()
    ode = fit(
        data,
        rec.model_name,
        blocked_force=rec.blocked_force,
        options=FitOptions(path="ode"),
        progress=False,
    )
    t_ode = time.perf_counter() - t1
    compare = {}
    print(
        f"\nall heights, sampled path ({t_sampled:.1f} s, rms {sampled.residual_rms_N:.3f} N) vs "
        f"ODE path ({t_ode:.1f} s, rms {ode.residual_rms_N:.3f} N):"
    )
    for name, est in sampled.parameters.items():
        if est.fixed:
            continue
        other = ode.parameters[name].value
        within = abs(est.value - other) <= 2 * est.std
        compare[name] = {
            "samples": est.value,
            "std": est.std,
            "ode": other,
            "difference_in_sigma": abs(est.value - other) / est.std if est.std else None,
            "within_2_sigma": within,
        }
        print(
            f"  {name:22s} {est.value:.6g} ± {est.std:.2g} | ODE {other:.6g} | "
            f"{abs(est.value - other) / est.std:.3f} σ {'ok' if within else 'MISSED'}"
        )
    return (
        compare,
        [t_sampled, t_ode],
        [sampled.residual_rms_N, ode.residual_rms_N],
        [sampled.message, ode.message],
    )

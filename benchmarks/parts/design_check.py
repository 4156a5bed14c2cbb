"""``rbjax design`` checked: the margins it reports against ``rbjax simulate`` + the tolerance
check at the designed parameters, and against a 32-start run (no start may beat the reported
smallest margin by more than 0.05 of a tolerance half-width: 0.1 dB in a ±2 dB band).

Cases: the elastic model (paper) and Kelvin–Voigt on the JIS geometry, Kelvin–Voigt on the ISO
informative geometry. Writes ``results/design_check.json``. ``--quick``: the elastic model on
the JIS geometry, 2 starts of 20 steps checked against 2 other starts (the code path, not the bar).

The check calls ``rbjax.studies.design`` (what ``rbjax design`` runs): it compares the optimiser's
own margins with the tolerance check's, which the command's output does not carry.
"""

from __future__ import annotations

import time

from rbjax.studies import DesignSearch, design

from _common import finish_machine_info, machine_info, write_json

CASES = (("paper", "jis"), ("kelvin-voigt", "jis"), ("kelvin-voigt", "iso"))
#: The 32-start check's tolerance, in tolerance half-widths (0.1 dB of a ±2 dB band).
CHECK = 0.05


def main(quick: bool = False) -> None:
    info = machine_info()
    rows = []
    print(
        f"{'model':<14} {'geom':<5} {'smallest':>9} {'blocking':<16} {'|opt − check|':>13} "
        f"{'32-start best':>13} {'bar':>5}  parameters   time (8 / 32 starts)"
    )
    narrow, broad = (
        (DesignSearch(n_starts=2, steps=20), DesignSearch(n_starts=2, steps=20, seed=1))
        if quick
        else (DesignSearch(n_starts=8), DesignSearch(n_starts=32, seed=1))
    )
    for model, geometry in CASES[:1] if quick else CASES:
        t0 = time.perf_counter()
        result = design(model, geometry, search=narrow)
        t8 = time.perf_counter() - t0
        t0 = time.perf_counter()
        wide = design(model, geometry, search=broad)
        t32 = time.perf_counter() - t0
        agreement = max(
            abs(result.optimiser_margins[k] - result.normalised_margins[k])
            for k in result.normalised_margins
        )
        best32 = max(wide.start_margins)
        ok = best32 <= result.smallest_margin + CHECK and agreement < 1e-6
        rows.append(
            {
                "model": model,
                "geometry": geometry,
                "result": result.to_dict(),
                "optimiser_vs_check": agreement,
                "best_of_32_starts": best32,
                "bar_met": ok,
                "time_8_starts_s": t8,
                "time_32_starts_s": t32,
            }
        )
        params = ", ".join(f"{k}={v:.4g}" for k, v in result.parameters.items())
        print(
            f"{model:<14} {geometry:<5} {result.smallest_margin:>+9.3f} {result.blocking:<16} "
            f"{agreement:>13.1e} {best32:>+13.3f} {'met' if ok else 'MISS':>5}  {params}   "
            f"{t8:.0f} / {t32:.0f} s"
        )
        print(f"    {result.verdict()}")
    path = write_json(
        "design_check" + ("_quick" if quick else ""),
        {"machine": finish_machine_info(info), "check_half_widths": CHECK, "cases": rows},
    )
    print(f"wrote {path}")

"""The fit on faulty recordings and at other sample rates against the fit on the clean set
(issue 21).

The six simulated 1 s drops of ``tests/synthetic_records.py`` (Kelvin–Voigt, momentum blocked
force, E = 1.9 MPa, c = 40 N s/m, 0.8 N noise through the 1250 Hz chain) are fitted:

* clean, at 44.1 kHz (the reference);
* as the faulty set of ``tests/fit/test_fit_faults.py`` (integer WAV 16/24/32 bit, MAT, UFF,
  TDMS; offset, drift, 50/60 Hz hum, inverted sign, a rebound, a clipped file excluded);
* the same drops recorded at 48 kHz and at 25.6 kHz (noise of the same density).

Bars: E within 1 % and the damping within 2σ (σ of the clean fit). A record at another rate
holds other noise samples, so its fit differs from the clean one by about √2σ even when
right; its damping against the truth, in its own σ, is printed beside. Prints a table and writes
``results/loader_faults.json``. ``--quick``: the clean and the faulty set at 44.1 kHz (another
rate compiles the fit again).
"""

from __future__ import annotations

import sys
import tempfile
import time
import warnings
from pathlib import Path

from rbjax import data as D
from rbjax.fit import fit, load_data, prepare_data

from _common import REPO, finish_machine_info, machine_info, table, write_json

sys.path.insert(0, str(REPO / "tests" / "fit"))  # the faulty set is the fit test's

# isort: split
from synthetic_records import CUTOFF_HZ, FAULT_DAMPING_NS_PER_M, RATE_HZ, long_records  # noqa: E402
from test_fit_faults import MODEL, recordings, write_faulty_set  # noqa: E402


def main(quick: bool = False) -> None:
    info = machine_info()
    sets = {"clean 44.1 kHz": prepare_data(recordings(long_records()[1], RATE_HZ))}
    with tempfile.TemporaryDirectory() as folder, warnings.catch_warnings():
        warnings.simplefilter("ignore", D.DataWarning)
        write_faulty_set(Path(folder), *long_records())
        sets["faulty files 44.1 kHz"] = prepare_data(load_data(folder, lowpass_Hz=CUTOFF_HZ))
    for rate in () if quick else (48_000.0, 25_600.0):
        sets[f"clean {rate / 1e3:g} kHz"] = prepare_data(recordings(long_records(rate)[1], rate))
    rows, out = [], {}
    ref = None
    for label, data in sets.items():
        t0 = time.perf_counter()
        res = fit(data, **MODEL)
        wall = time.perf_counter() - t0
        e, c = res.parameters["youngs_Pa"], res.parameters["damping_Ns_per_m"]
        ref = ref or (e, c)
        de = (e.value - ref[0].value) / ref[0].value * 100
        dc = (c.value - ref[1].value) / ref[1].std
        met = abs(de) <= 1.0 and abs(dc) <= 2.0
        dt = (c.value - FAULT_DAMPING_NS_PER_M) / c.std  # from the truth, in the fit's own σ
        out[label] = {
            "youngs_Pa": e.value,
            "youngs_std_Pa": e.std,
            "damping_Ns_per_m": c.value,
            "damping_std": c.std,
            "dE_pct": de,
            "dc_sigma": dc,
            "dc_truth_sigma": dt,
            "bars_met": met,
            "wall_s": wall,
            "excluded": list(data.excluded),
        }
        rows.append(
            [
                label,
                f"{e.value:.1f}",
                f"{de:+.4f}",
                f"{c.value:.4f}",
                f"{dc:+.2f}",
                "yes" if met else "NO",
                f"{dt:+.2f}",
                f"{wall:.1f}",
            ]
        )
    print(
        table(
            [
                "set",
                "E (Pa)",
                "ΔE (%)",
                "c (N s/m)",
                "Δc (σ)",
                "bars met",
                "c − truth (own σ)",
                "fit (s)",
            ],
            rows,
        )
    )
    write_json(
        "loader_faults" + ("_quick" if quick else ""),
        {"machine": finish_machine_info(info), "fits": out},
    )

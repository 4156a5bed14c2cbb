"""Speed and accuracy of the impact on moving floors (``rbjax.terms.floors.kinds``).

    .venv/bin/python benchmarks/floors.py [--quick]   # prints a table, writes results/floors.json

Per floor: impacts/s of the scalar path (``simulate``, the ODE with its default ``Solver()``;
for the rigid floor also the default quadrature path) at a batch of 1000 drop heights
(0.1–1.6 m), median of repeated calls after the compiling one; and the largest relative error
over the heights 0.1, 0.5, 1.0, 1.6 m of the contact time, peak force and restitution against
the independent scipy references (``tests/scipy_floor_reference.py`` for moving floors,
``tests/scipy_reference.py`` for the rigid floor; DOP853, rtol 1e-12).

Floors: rigid; dashpots Z = 500, 2000, 1e5 N·s/m; infinite plates of 15 mm OSB
(E 4.9 GPa, ρ 600 kg/m³, ν 0.3) and 150 mm concrete (E 30 GPa, ρ 2300 kg/m³, ν 0.2); the
first five drive-point modes of a simply supported 4 m × 5 m, 140 mm concrete slab
(``rbjax.terms.simply_supported_plate_modes``, η 0.02).
"""

from __future__ import annotations

import numpy as np

import rbjax
from rbjax.terms import simply_supported_plate_modes

from _common import finish_machine_info, fmt, machine_info, table, time_call, write_json
from scipy_floor_reference import reference_floor_impact
from scipy_reference import reference_impact

# (the scipy references live in tests/, which _common puts on sys.path)
BALL = rbjax.JIS_RUBBER_BALL
CHECK_HEIGHTS = (0.1, 0.5, 1.0, 1.6)
QUANTITIES = ("contact_time_s", "peak_force_N", "restitution")


def five_mode_slab() -> rbjax.ModalFloor:
    plate = simply_supported_plate_modes(
        4.0,
        5.0,
        0.14,
        30e9,
        2300.0,
        0.2,
        0.02,
        drive_x_m=1.7,
        drive_y_m=2.3,
        max_frequency_Hz=400.0,
    )
    return rbjax.ModalFloor(plate.mass_kg[:5], plate.frequency_Hz[:5], plate.loss_factor[:5])


def floors() -> list[tuple[str, object]]:
    return [
        ("rigid", rbjax.Rigid()),
        ("dashpot Z=500", rbjax.Dashpot(500.0)),
        ("dashpot Z=2000", rbjax.Dashpot(2000.0)),
        ("dashpot Z=1e5", rbjax.Dashpot(1e5)),
        ("infinite plate OSB 15 mm", rbjax.InfinitePlate(0.015, 4.9e9, 600.0, 0.3)),
        ("infinite plate concrete 150 mm", rbjax.InfinitePlate(0.15, 30e9, 2300.0, 0.2)),
        ("5-mode slab (4×5 m, 140 mm)", five_mode_slab()),
    ]


def describe(floor) -> dict:
    if isinstance(floor, rbjax.ModalFloor):
        return {
            "mass_kg": list(floor.mass_kg),
            "frequency_Hz": list(floor.frequency_Hz),
            "loss_factor": list(floor.loss_factor),
        }
    if isinstance(floor, (rbjax.Dashpot, rbjax.InfinitePlate)):
        return {"impedance_Ns_per_m": float(floor.impedance_Ns_per_m)}
    return {}


def agreement(floor) -> dict:
    res = rbjax.simulate(np.array(CHECK_HEIGHTS), BALL, floor=floor, path="ode")
    res.raise_for_status()
    err = {q: 0.0 for q in QUANTITIES}
    for i, h in enumerate(CHECK_HEIGHTS):
        ref = reference_impact(h, BALL) if floor.rigid else reference_floor_impact(h, BALL, floor)
        for q in QUANTITIES:
            err[q] = max(err[q], abs(float(getattr(res, q)[i]) / getattr(ref, q) - 1.0))
    return err


def throughput(floor, batch: int, method: str) -> dict:
    heights = np.linspace(0.1, 1.6, batch)
    t = time_call(
        lambda: rbjax.simulate(heights, BALL, floor=floor, path=method).contact_time_s,
        min_repeats=3,
        max_time_s=20.0,
    )
    ok = bool(np.all(np.isfinite(np.asarray(t["out"]))))
    return {
        "impacts_per_s": batch / t["median_s"],
        "median_s": t["median_s"],
        "compile_s": t["compile_s"],
        "repeats": t["repeats"],
        "all_ok": ok,
    }


def main(quick: bool = False) -> None:
    batch = len(CHECK_HEIGHTS) if quick else 1000  # quick: the agreement's batch, one compile
    info = machine_info()
    rows = []
    # quick: one moving floor (an infinite plate)
    chosen = floors()
    for name, floor in chosen[4:5] if quick else chosen:
        methods = ["ode", "auto"] if floor.rigid else ["ode"]
        for method in methods:
            speed = throughput(floor, batch, method)
            err = agreement(floor) if method == "ode" else {}
            path = "quadrature" if method == "auto" else "ode"
            rows.append(
                {
                    "floor": name,
                    "path": path,
                    "batch": batch,
                    **speed,
                    **{f"rel_err_{q}": v for q, v in err.items()},
                    **describe(floor),
                }
            )
            print(f"{name} ({path}): {speed['impacts_per_s']:.0f} impacts/s", flush=True)
    headers = [
        "floor",
        "path",
        f"impacts/s (batch {batch})",
        "compile (s)",
        "contact time",
        "peak force",
        "restitution",
    ]
    print(
        table(
            headers,
            [
                [
                    r["floor"],
                    r["path"],
                    fmt(r["impacts_per_s"], ".0f"),
                    fmt(r["compile_s"], ".1f"),
                    fmt(r.get("rel_err_contact_time_s"), ".1e"),
                    fmt(r.get("rel_err_peak_force_N"), ".1e"),
                    fmt(r.get("rel_err_restitution"), ".1e"),
                ]
                for r in rows
            ],
        )
    )
    path = write_json(
        "floors" + ("_quick" if quick else ""),
        {
            "machine": finish_machine_info(info),
            "batch": batch,
            "check_heights_m": list(CHECK_HEIGHTS),
            "rows": rows,
        },
    )
    print(f"wrote {path}")

"""Force histories: the ODE path (diffrax, dense interpolant at the sample times) against the
histories sampled inside a fixed-step solve (``rbjax.solve.sampled_history``, RK4, one step per
sample), the default of ``force_history`` for the rigid-floor models since this change.

Records per second at batch 100 and 1000 (heights 0.1–1.6 m, 44.1 kHz), for the force samples of
the contact only (⌈t_c·rate⌉ + 2 samples) and for the whole 1 s record zero-padded by
``force_history`` (what ``ImpactResult.force_N`` returns), with the contact times given (as
``ImpactResult.history`` passes them; the scalar solve is not timed). And the largest sample
error relative to the peak force against the scipy reference (DOP853, rtol 1e-12) at 0.1, 0.8
and 1.6 m, with one and with two RK4 steps per sample.

Prints a table and writes ``results/history_speed.json``. ``--quick``: the elastic model at
batch 100.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

import rbjax
from rbjax import Model
from rbjax.solve import force_history, sampled_history, trajectory

from _common import finish_machine_info, machine_info, table, time_call, write_json
from scipy_reference import reference_impact

# (the scipy reference lives in tests/, which _common puts on sys.path)

BALL = rbjax.JIS_RUBBER_BALL
RATE_Hz = 44_100.0
SOLVER = rbjax.Solver()
ERROR_HEIGHTS = np.array([0.1, 0.8, 1.6])
#: ``force_history``'s rule for its sub-steps: at least this many RK4 steps over the shortest
#: contact (rbjax.solve.sampled's MIN_STEPS_PER_CONTACT)
MIN_STEPS_PER_CONTACT = 400
MODELS = {
    "elastic": {},
    "zener (momentum)": dict(
        damping=rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3), blocked_force="momentum"
    ),
}


def _max_error(history, refs) -> float:
    t = np.arange(np.shape(history.force_N)[-1]) / RATE_Hz
    return max(
        float(np.max(np.abs(np.asarray(history.force_N[i]) - r.force_N(t))) / r.peak_force_N)
        for i, r in enumerate(refs)
    )


def _errors(model, options) -> dict:
    refs = [reference_impact(h, BALL, **options) for h in ERROR_HEIGHTS]
    contact = np.array([r.contact_time_s for r in refs])
    n = int(math.ceil(contact.max() * RATE_Hz)) + 2
    return {
        "ode": _max_error(
            force_history(ERROR_HEIGHTS, BALL, model, SOLVER, contact_time_s=contact, path="ode"),
            refs,
        ),
        "sampled": _max_error(
            force_history(ERROR_HEIGHTS, BALL, model, SOLVER, contact_time_s=contact), refs
        ),
        "sampled, 2 steps per sample": _max_error(sampled(ERROR_HEIGHTS, model, n, 2), refs),
    }


def sampled(heights, model, n, substeps):
    return sampled_history(heights, BALL, model, num_samples=n, rate_Hz=RATE_Hz, substeps=substeps)


def _paths(heights, model, contact):
    n = int(math.ceil(np.max(contact) * RATE_Hz)) + 2
    substeps = max(1, math.ceil(MIN_STEPS_PER_CONTACT / (float(np.min(contact)) * RATE_Hz)))
    times = jnp.arange(n) / RATE_Hz
    return (
        n,
        substeps,
        {
            ("ode", "contact"): lambda: trajectory(heights, times, BALL, model, SOLVER).force_N,
            ("ode", "record"): lambda: (
                force_history(
                    heights, BALL, model, SOLVER, contact_time_s=contact, path="ode"
                ).force_N
            ),
            ("sampled", "contact"): lambda: sampled(heights, model, n, substeps).force_N,
            ("sampled", "record"): lambda: (
                force_history(heights, BALL, model, SOLVER, contact_time_s=contact).force_N
            ),
            ("sampled, 2 steps per sample", "contact"): lambda: (
                sampled(heights, model, n, 2).force_N
            ),
        },
    )


def main(quick: bool = False) -> None:
    info = machine_info()
    batches = (100,) if quick else (100, 1000)
    out: dict = {"rate_Hz": RATE_Hz, "error_heights_m": ERROR_HEIGHTS, "models": {}}
    rows = []
    for name, options in list(MODELS.items())[:1] if quick else MODELS.items():
        model = Model(**options)
        errors = _errors(model, options)
        entry: dict = {"max_rel_error": errors, "batches": {}}
        for batch in batches:
            heights = np.linspace(0.1, 1.6, batch)
            contact = np.asarray(rbjax.simulate(heights, **options).contact_time_s)
            n, substeps, paths = _paths(heights, model, contact)
            timings = {}
            for (path, part), fn in paths.items():
                t = time_call(fn, max_repeats=7)
                timings[f"{path}, {part}"] = {
                    "records_per_s": batch / t["median_s"],
                    "median_s": t["median_s"],
                    "compile_s": t["compile_s"],
                }
                rows.append(
                    [
                        name,
                        batch,
                        path,
                        part,
                        f"{batch / t['median_s']:,.0f}",
                        f"{t['compile_s']:.1f}",
                        f"{errors[path]:.1e}",
                    ]
                )
                print(rows[-1], flush=True)
            entry["batches"][str(batch)] = {"samples": n, "substeps": substeps, "timings": timings}
        out["models"][name] = entry
    print(
        table(
            [
                "model",
                "batch",
                "path",
                "output",
                "records/s",
                "first call − median (s)",
                "max rel. error (3 heights)",
            ],
            rows,
        )
    )
    out["machine"] = finish_machine_info(info)
    print(f"wrote {write_json('history_speed' + ('_quick' if quick else ''), out)}")

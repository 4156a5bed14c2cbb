"""The default fit, raced (issue 42): the wall time of ``rbjax fit DIR`` (the model selection
races) cold and warm beside ``--exhaustive``, and the race against the exhaustive selection on
every data set the tests hold.

1. ``rbjax fit src/rbjax/examples/emulated-rubber-ball --quiet --json`` in subprocesses sharing
   one fresh ``RBJAX_CACHE_DIR``: cold (every program traced and compiled), then warm (best of
   2), and ``--exhaustive`` warm, every usable core; ``rbjax select`` warm with the default
   candidates and with two more (zener+ball-mode, both blocked forces); the load average
   around each run.
2. ``select_model(data)`` (the race) against ``select_model(data, exhaustive=True)`` with the
   default candidates on: the bundled recordings (per-height averages, and every drop as its
   own record), three of their heights, the simulated drops of the tests (Kelvin–Voigt,
   Hunt–Crossley and Zener truths, the fault tests' 1 s drops and their faulty files). Bars:
   the same recommendation and the same candidates within the noise; the recommended model's
   held-out errors identical (every fold, bit for bit); every fold the race ran equal to the
   exhaustive run's. Also the bound the race uses: the smallest ratio of a fold's held-out
   error to its full fit's in-sample error at that height, over every fold of the exhaustive
   run (≥ 1 where the bound holds), and the folds run.
3. The race with ``Parallel(workers=2)`` against ``Parallel(workers=1)`` on the bundled
   recordings: the same selection, bit for bit.

Prints the tables and writes ``results/selection_race.json``. ``--quick``: part 2 on three
heights with four candidates, nothing else.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from rbjax import JIS_RUBBER_BALL, HuntCrossley, KelvinVoigt, Parallel, Zener
from rbjax.data import DataWarning, examples_dir
from rbjax.fit import load_data, prepare_data
from rbjax.studies import select_model

from _common import REPO, finish_machine_info, machine_info, write_json

sys.path[:0] = [str(REPO / "tests"), str(REPO / "tests" / "fit")]  # the tests' data sets

# isort: split
from synthetic_records import (  # noqa: E402
    CUTOFF_HZ,
    RATE_HZ,
    long_records,
    synthetic_data,
)
from test_fit_faults import recordings, write_faulty_set  # noqa: E402

QUICK_CANDIDATES = ["paper", "kelvin-voigt"]
#: the default candidates and one more model (two candidates: both blocked forces) of the same
#: shared structure (nothing more to compile)
MORE = (
    "paper,kelvin-voigt,hunt-crossley,zener,hunt-crossley+ball-mode,"
    "hunt-crossley+series-kelvin-voigt,zener+ball-mode"
)


def fit_command(argv, cache) -> tuple[float, dict, list]:
    env = dict(os.environ, RBJAX_CACHE_DIR=str(cache))
    load = list(os.getloadavg())
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "rbjax.cli", *argv], env=env, capture_output=True, text=True
    )
    elapsed = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"rbjax {' '.join(argv)} failed:\n{proc.stderr[-3000:]}")
    return elapsed, json.loads(proc.stdout), load + list(os.getloadavg())


def timings() -> list[dict]:
    data = str(examples_dir())
    rows = []
    with tempfile.TemporaryDirectory() as cache:
        for label, argv, runs in (
            ("race, cold", ["fit"], 1),
            ("race, warm", ["fit"], 2),
            ("--exhaustive, warm", ["fit", "--exhaustive"], 1),
            ("select, warm", ["select"], 2),
            ("select, two more candidates, warm", ["select", "--candidates", MORE], 2),
        ):
            best = None
            for _ in range(runs):
                elapsed, out, load = fit_command([*argv, data, "--quiet", "--json"], cache)
                if best is None or elapsed < best[0]:
                    best = (elapsed, out, load)
            assert best is not None
            elapsed, out, load = best
            race = out["selection"].get("race")
            rows.append(
                {
                    "run": label,
                    "wall_s": elapsed,
                    "recommended": out["selection"]["recommended"],
                    "folds_run": race["folds_run"] if race else None,
                    "loadavg_before_after": load,
                }
            )
            print(f"rbjax fit DIR ({label}): {elapsed:.1f} s, load {load}", flush=True)
    return rows


def data_sets(quick: bool) -> dict:
    bundled = examples_dir()
    three = [bundled / f"h{h:03d}_d1.csv" for h in (10, 40, 100)]
    sets = {"bundled, three heights": lambda: prepare_data(load_data(three))}
    if quick:
        return sets
    t, forces = long_records()

    def faulty():
        folder = tempfile.mkdtemp()
        write_faulty_set(Path(folder), t, forces)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DataWarning)
            return prepare_data(load_data(folder, lowpass_Hz=CUTOFF_HZ))

    def ball(e):
        return JIS_RUBBER_BALL.replace(youngs_Pa=e)

    sets.update(
        {
            "bundled (per-height averages)": lambda: prepare_data(load_data(bundled)),
            "bundled, every drop a record": lambda: prepare_data(load_data(bundled), average=False),
            "simulated Kelvin–Voigt, 1 s drops": lambda: prepare_data(recordings(forces, RATE_HZ)),
            "simulated Kelvin–Voigt, faulty files": faulty,
            "simulated Hunt–Crossley": lambda: synthetic_data(
                JIS_RUBBER_BALL, HuntCrossley(0.05), "momentum", 7
            ),
            "simulated Zener": lambda: synthetic_data(
                ball(1.5e6), Zener(0.7, 1.7e-3), "momentum", 2
            ),
            "simulated Kelvin–Voigt, paper force": lambda: synthetic_data(
                ball(1.9e6), KelvinVoigt(40.0), "paper", 5
            ),
        }
    )
    return sets


def in_sample(candidate, heights) -> np.ndarray:
    """The full fit's history error (% of peak) at each height, as the held-out one is read."""
    fit = candidate.fit
    out = []
    for h in heights:
        k = np.isclose(fit.heights_m, h, atol=5e-4)
        rms = np.sqrt(np.mean((fit.predicted_N[k] - fit.measured_N[k]) ** 2))
        out.append(100.0 * rms / np.mean(np.max(fit.measured_N[k], axis=1)))
    return np.array(out)


def compare(race, full) -> dict:
    by_label = {c.label: c for c in full.candidates}
    same_folds = True
    for c in race.candidates:
        ref = by_label[c.label]
        mine = {f.height_m: f.history_error_pct for f in c.folds}
        theirs = {f.height_m: f.history_error_pct for f in ref.folds}
        same_folds &= all(mine[h] == theirs[h] for h in mine)
    heights = [f.height_m for f in full.recommended.folds]
    ratios, one_start, below = [], [], []
    for c in full.candidates:
        if not c.fit.converged:
            continue
        r = np.array([f.history_error_pct for f in c.folds]) / in_sample(c, heights)
        ratios.append(r)
        if c.fit.n_starts == 1:
            one_start.append(r)
        below += [
            {"candidate": c.label, "height_m": h, "ratio": float(x), "starts": c.fit.n_starts}
            for h, x in zip(heights, r)
            if x < 1.0
        ]
    return {
        "recommended_race": race.recommended.label,
        "recommended_exhaustive": full.recommended.label,
        "same_recommendation": race.recommended.label == full.recommended.label,
        "same_within_noise": [c.label for c in race.within_noise]
        == [c.label for c in full.within_noise],
        "recommended_errors_identical": bool(
            np.array_equal(race.recommended.fold_errors_pct, full.recommended.fold_errors_pct)
        ),
        "every_raced_fold_identical": bool(same_folds),
        "folds_run": race.race.folds_run,
        "folds_total": race.race.folds_total,
        "dropped": {
            c.label: {"round": c.dropped.round, "folds_run": len(c.folds)}
            for c in race.candidates
            if c.dropped is not None
        },
        "smallest_held_out_over_in_sample": float(np.nanmin(np.concatenate(ratios))),
        "smallest_held_out_over_in_sample_one_start": float(np.nanmin(np.concatenate(one_start))),
        "folds_below_their_bound": below,
        "folds_of_fits_from_several_starts": int(
            sum(len(c.folds) for c in full.candidates if c.fit.converged and c.fit.n_starts > 1)
        ),
        "race_s": race.elapsed_s,
        "exhaustive_s": full.elapsed_s,
    }


def equality(quick: bool) -> dict:
    # BLAS on one thread here, as in the worker processes and as the command line sets it: the
    # fit's host-side linear algebra then gives the same bits wherever a task runs
    with threadpool_limits(limits=1):
        return _equality(quick)


def _equality(quick: bool) -> dict:
    out = {}
    for label, make in data_sets(quick).items():
        data = make()
        kwargs = {"progress": False}
        if quick:
            kwargs["candidates"] = QUICK_CANDIDATES
        race = select_model(data, **kwargs)
        full = select_model(data, exhaustive=True, **kwargs)
        out[label] = compare(race, full)
        r = out[label]
        print(
            f"{label}: race {r['recommended_race']} ({r['folds_run']} of {r['folds_total']} "
            f"folds, {r['race_s']:.1f} s) | exhaustive {r['recommended_exhaustive']} "
            f"({r['exhaustive_s']:.1f} s) | same: {r['same_recommendation']}, within noise "
            f"{r['same_within_noise']}, errors identical {r['recommended_errors_identical']}, "
            f"raced folds identical {r['every_raced_fold_identical']} | smallest held-out / "
            f"in-sample {r['smallest_held_out_over_in_sample']:.3f}",
            flush=True,
        )
    return out


def workers() -> dict:
    data = prepare_data(load_data(examples_dir()))
    with threadpool_limits(limits=1):
        one = select_model(data, parallel=Parallel(workers=1), progress=False)
        two = select_model(data, parallel=Parallel(workers=2), progress=False)
    same = _text(one) == _text(two)
    print(f"race, workers 2 against 1: identical selection {same}", flush=True)
    return {"identical": same, "one_s": one.elapsed_s, "two_s": two.elapsed_s}


def _text(selection) -> str:
    """The selection's JSON without its wall time (NaN written as NaN, so equal to itself)."""
    return json.dumps(selection.to_dict() | {"elapsed_s": None}, sort_keys=True)


def main(quick: bool = False) -> None:
    info = machine_info()
    out: dict = {"machine": info}
    if not quick:
        out["timings"] = timings()
    out["equality"] = equality(quick)
    if not quick:
        out["workers"] = workers()
    finish_machine_info(info)
    path = write_json("selection_race" + ("_quick" if quick else ""), out)
    print(f"wrote {path}")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)

"""The model selection as batched fits (:mod:`rbjax.fit.batching`): how much shorter
the chain of optimiser steps gets when every fit of a structure steps in one batch.

On an accelerator one Levenberg–Marquardt step costs about the same for 1 lane as for 64 (an
H100 measured ~110 ms a step, 64 lanes 1.2× 3 lanes: the sample loop's sequential depth), so
the selection's time there is set by the steps walked one after another, not by the work.
This script runs the full default selection on the bundled recordings on this machine's CPU
twice — one fit after another (each fit's starts in one call, as an accelerator runs
them without batching) and batched (``Parallel(batch_fits=True)``) — and
counts, from every call of the fit program:

* the **sequential depth**: the steps walked one after another (a call costs as many steps as
  its slowest lane; an evaluation counts as one step), sequential against lanes;
* the program calls, their lanes (mean, largest) and the padding;
* whether the two runs recommend the same model and how far their held-out errors differ.

The depth times a measured per-step cost estimates an accelerator's time; it is an estimate
(stated as such), not a measurement: only ``benchmarks/device_check.py`` on a machine with an
accelerator measures that. On the CPU the lanes run slower than one fit after another (the
lanes are compute-bound there); that time is reported too.

Prints a table and writes ``results/selection_lanes.json``. ``--quick``: one candidate
(hunt-crossley/momentum: its six folds as lanes).

It counts the calls of the fit program through the ``run`` hook of
:class:`rbjax.fit.batching.BatchedFitExecutor` and :func:`rbjax.fit.program.run_lanes`,
internals that no public name exposes: the count is the measurement.
"""

from __future__ import annotations

import time

import numpy as np

from rbjax import Parallel
from rbjax.data import examples_dir
from rbjax.fit import prepare_data
from rbjax.fit.batching import BatchedFitExecutor
from rbjax.fit.problem import STEPS_PER_ROUND
from rbjax.fit.program import run_lanes
from rbjax.studies import select_model

from _common import finish_machine_info, machine_info, table, write_json

QUICK = ["hunt-crossley"]
#: The per-step cost of the fit program on an H100 (issue measurements of `fc0325d`: ~110 ms a
#: step whatever the batch), for the estimate only.
H100_STEP_S = 0.110


class OneAtATime(BatchedFitExecutor):
    """A lane executor that runs one fit at a time (each returns before the next starts): the
    calls of one fit after another, as an accelerator would run them without lanes."""

    def submit(self, fn, /, *args, **kwargs):
        future = super().submit(fn, *args, **kwargs)
        future.exception()  # wait for it (an error stays in the future)
        return future


def calls_of(run_selection, executor_type=BatchedFitExecutor):
    """Run ``run_selection(parallel)`` with a lane executor recording every program call."""
    calls = []

    def recorded(key, lanes, data):
        out = run_lanes(key, lanes, data)
        calls.append({"lanes": int(len(out.steps)), "steps": [int(x) for x in out.steps]})
        return out

    executor = executor_type(run=recorded)
    result = run_selection(Parallel(executor=executor))
    for call, (asked, _) in zip(calls, executor.batcher.batches):
        call["asked"] = asked
    return result, calls


def depth(calls) -> int:
    """Steps walked one after another: each call as many as its slowest asked-for lane."""
    return sum(max(1, *c["steps"][: c["asked"]]) for c in calls)


def main(quick: bool = False) -> None:
    info = machine_info()
    data = prepare_data(examples_dir())
    kwargs = {"progress": False}
    if quick:
        kwargs["candidates"] = QUICK
        kwargs["blocked_forces"] = ("momentum",)

    def run(parallel):
        return select_model(data, parallel=parallel, **kwargs)

    t0 = time.perf_counter()
    seq, sequential_calls = calls_of(run, OneAtATime)
    seq_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    lanes, calls = calls_of(run)
    lanes_s = time.perf_counter() - t0
    seq_depth = depth(sequential_calls)
    lane_depth = depth(calls)
    differences = [
        float(np.max(np.abs(b.fold_errors_pct / a.fold_errors_pct - 1)))
        for a, b in zip(seq.candidates, lanes.candidates)
    ]
    per_candidate = {
        a.label: {
            "sequential_folds_pct": a.fold_errors_pct.tolist(),
            "lanes_folds_pct": b.fold_errors_pct.tolist(),
            "largest_relative_difference": d,
        }
        for a, b, d in zip(seq.candidates, lanes.candidates, differences)
    }
    report = {
        "candidates": len(seq.candidates),
        "steps_per_round": STEPS_PER_ROUND,
        "sequential": {
            "wall_s": seq_s,
            "recommended": seq.recommended.label,
            "program_calls": len(sequential_calls),
            "sequential_depth_steps": seq_depth,
        },
        "lanes": {
            "wall_s": lanes_s,
            "recommended": lanes.recommended.label,
            "program_calls": len(calls),
            "sequential_depth_steps": lane_depth,
            "mean_lanes_per_call": float(np.mean([c["asked"] for c in calls])),
            "largest_call_lanes": max(c["asked"] for c in calls),
            "padded_lanes": sum(c["lanes"] - c["asked"] for c in calls),
            "total_lane_steps": sum(sum(c["steps"][: c["asked"]]) for c in calls),
        },
        "largest_relative_difference_of_held_out_errors": max(differences),
        "per_candidate": per_candidate,
        "estimate_on_h100_s": {
            "sequential": seq_depth * H100_STEP_S,
            "lanes": lane_depth * H100_STEP_S,
        },
        "calls": calls,
    }
    rows = [
        [
            "one fit after another",
            f"{seq_s:.1f}",
            seq.recommended.label,
            str(len(sequential_calls)),
            f"{np.mean([c['asked'] for c in sequential_calls]):.1f}",
            str(seq_depth),
        ],
        [
            "lanes",
            f"{lanes_s:.1f}",
            lanes.recommended.label,
            str(len(calls)),
            f"{report['lanes']['mean_lanes_per_call']:.1f}",
            str(lane_depth),
        ],
    ]
    print(
        table(["run (this CPU)", "wall (s)", "recommended", "calls", "lanes/call", "depth"], rows)
    )
    worst = max(per_candidate, key=lambda k: per_candidate[k]["largest_relative_difference"])
    print(
        f"held-out errors, lanes vs sequential: largest relative difference {max(differences):.1e}"
        f" ({worst})"
    )
    print(
        f"estimate on an H100 at {H100_STEP_S * 1e3:.0f} ms a step: {seq_depth} → {lane_depth} "
        f"steps in sequence, ~{seq_depth * H100_STEP_S:.0f} s → ~{lane_depth * H100_STEP_S:.0f} s "
        "(an estimate, not a measurement)"
    )
    write_json(
        "selection_lanes" + ("_quick" if quick else ""),
        {"machine": finish_machine_info(info), **report},
    )

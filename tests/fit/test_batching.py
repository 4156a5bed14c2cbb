"""Batched fits (:mod:`rbjax.fit.batching`): the calls of fits running in threads are gathered
into one batch per program once every fit waits, padded to a few sizes, and split again;
each call gets back its own lanes' outputs, and an error reaches only the fits of its batch.

The reference is plain arithmetic on each call's own lanes (``run`` below is elementwise, so
stacking, padding and splitting must be invisible in the outputs). That the fit program gives
the same fits as lanes as alone is tested with the selection, in
``tests/studies/test_parallel_selection.py``.
"""

from __future__ import annotations

import concurrent.futures as cf
import threading
import time

import numpy as np
import pytest

from rbjax import Parallel
from rbjax.fit import batching as batching_module
from rbjax.fit.batching import BATCH_SIZES, BatchedFitExecutor, padded_size
from rbjax.studies.parallel.executors import Task, TaskError, run_tasks


def test_a_batch_runs_at_the_next_of_a_few_sizes():
    assert [padded_size(n) for n in (1, 2, 3, 5, 9, 33, 64)] == [1, 2, 4, 8, 16, 64, 64]
    assert padded_size(65) == 2 * BATCH_SIZES[-1] and padded_size(129) == 3 * BATCH_SIZES[-1]


def _executor():
    """A batched-fit executor whose 'program' is elementwise: lane x → 10·x + key, with the
    data."""
    seen = []

    def run(key, lanes, shared):
        seen.append((key, len(lanes["x"])))
        if key == "bad":
            raise ValueError("this program fails")
        return {"y": 10 * lanes["x"] + key + shared, "n": np.full(len(lanes["x"]), len(seen))}

    return BatchedFitExecutor(run), seen


def _fit(rounds, key, lanes0, started=None, *, batcher):
    """A toy fit: ``rounds`` calls, each of its lanes, each feeding the next (after every fit
    of ``started`` has started, if given: all have joined the batcher then), to the
    ``batcher`` the executor gives it."""
    if started is not None:
        started.wait(timeout=30)
    x = np.asarray(lanes0, dtype=float)
    for _ in range(rounds):
        out = batcher.call(key, {"x": x}, 0.5)
        x = out["y"]
    return x


def test_every_call_gets_its_own_lanes_back_through_shared_batches():
    executor, seen = _executor()
    plan = [(3, 1, [1.0, 2.0]), (1, 1, [3.0]), (2, 2, [4.0, 5.0, 6.0]), (0, 1, [7.0])]
    started = threading.Barrier(len(plan))
    futures = [executor.submit(_fit, *p, started) for p in plan]
    results = [f.result(timeout=30) for f in futures]
    executor.shutdown()
    for (rounds, key, x0), got in zip(plan, results):
        want = np.asarray(x0)
        for _ in range(rounds):
            want = 10 * want + key + 0.5
        np.testing.assert_array_equal(got, want)
    # every round is one batch a key: first both keys with every fit still running (3 lanes of
    # key 1 padded to 4, 3 of key 2 padded to 4; the fit of 0 rounds never calls), then the
    # fits still going, packed again (2 + 3 lanes, then 2)
    assert sorted(seen[:2]) == [(1, 4), (2, 4)]
    assert sorted(seen[2:4]) == [(1, 2), (2, 4)] and seen[4:] == [(1, 2)]
    assert sorted(executor.batcher.batches) == [(2, 2), (2, 2), (3, 4), (3, 4), (3, 4)]


def test_an_error_in_a_batch_reaches_only_the_fits_in_it():
    executor, _ = _executor()
    good = executor.submit(_fit, 2, 1, [1.0])
    bad = executor.submit(_fit, 1, "bad", [1.0])
    with pytest.raises(ValueError, match="this program fails"):
        bad.result(timeout=30)
    np.testing.assert_array_equal(good.result(timeout=30), [10 * (10 * 1 + 1.5) + 1.5])


def _gated_fit(gate, record, *, batcher):
    """A toy fit that does host work (waits for ``gate``) after its first call."""
    x = np.zeros(1)
    try:
        for i in range(3):
            x = batcher.call(1, {"x": x}, 0.5)["y"]
            if i == 0:
                gate.wait(timeout=30)
    except cf.CancelledError as err:
        record.append(err)
        raise
    record.append("finished")
    return x


def _toy_run(key, lanes, shared):
    if key == "bad":
        raise ValueError("this program fails")
    return {"y": 10 * lanes["x"] + key + shared}


def test_a_run_that_fails_stops_the_fits_still_running(monkeypatch):
    monkeypatch.setattr(batching_module, "run_lanes", _toy_run)
    gate, record = threading.Event(), []
    tasks = [
        Task("a failing fit", _fit, (1, "bad", [1.0])),
        Task("a long fit", _gated_fit, (gate, record)),
    ]
    with pytest.raises(TaskError, match="a failing fit failed: ValueError: this program fails"):
        run_tasks(Parallel(batch_fits=True), tasks)
    gate.set()  # the long fit's host work ends: its next call finds the executor closed
    for _ in range(300):
        if record:
            break
        time.sleep(0.01)
    assert len(record) == 1 and isinstance(record[0], cf.CancelledError)


def test_tasks_added_while_others_run_join_the_batches():
    executor, _ = _executor()
    tasks = [Task("fit a", _fit, (2, 1, [1.0])), Task("fit b", _fit, (1, 1, [2.0]))]

    def then(i, result):
        return [Task(f"fold of {i}", _fit, (1, 1, result))] if i < 2 else []

    out = run_tasks(Parallel(executor=executor), tasks, then=then, label="toy")
    assert [float(x[0]) for x in out[:2]] == [10 * (10 + 1.5) + 1.5, 21.5]
    assert len(out) == 4 and threading.active_count() < 50


def test_batched_fits_run_in_this_process_only():
    with pytest.raises(ValueError, match=r"batch_fits=True .* workers=2"):
        Parallel(batch_fits=True, workers=2)
    with pytest.raises(ValueError, match="batch_fits=True"):
        Parallel(batch_fits=True, scheduler="tcp://127.0.0.1:1")
    assert Parallel(batch_fits=True).batches_fits and not Parallel(batch_fits=True).in_process
    assert not Parallel(workers=2).batches_fits  # a worker count given: processes

"""A model selection in worker processes equals the one in this process, bit for bit, and ran
in more than one process (its record of the process of each fit); the executor under it reruns
the tasks of a worker that died and names a task that failed.

The reference is the same selection run one fit after another in this process
(``Parallel(workers=1)``, the code path every other test of the selection uses): the worker
processes must give the same held-out errors, fitted parameters and recommendation exactly
(same programs on the same inputs), not merely close ones.
"""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from rbjax import Parallel
from rbjax.data import examples_dir
from rbjax.fit import load_data, prepare_data
from rbjax.solve.parallel import usable_cores
from rbjax.studies import select_model
from rbjax.studies.parallel.executors import Task, TaskError, run_tasks

CANDIDATES = ["paper", "kelvin-voigt"]


@pytest.fixture(scope="module")
def data():
    # three heights, one drop each: three folds a candidate, cheap fits
    files = [examples_dir() / f"h{h:03d}_d1.csv" for h in (10, 40, 100)]
    return prepare_data(load_data(files))


@pytest.fixture(scope="module")
def in_process(data):
    one = Parallel(workers=1)
    return select_model(data, CANDIDATES, blocked_forces=("paper",), parallel=one, progress=False)


@pytest.fixture(scope="module")
def in_workers(data):
    two = Parallel(workers=2)
    return select_model(data, CANDIDATES, blocked_forces=("paper",), parallel=two, progress=False)


def test_worker_processes_give_the_in_process_selection_bit_for_bit(in_process, in_workers):
    assert [c.label for c in in_workers.candidates] == [c.label for c in in_process.candidates]
    assert in_workers.recommended.label == in_process.recommended.label
    for a, b in zip(in_process.candidates, in_workers.candidates):
        assert [f.height_m for f in b.folds] == [f.height_m for f in a.folds]
        np.testing.assert_array_equal(b.fold_errors_pct, a.fold_errors_pct)
        np.testing.assert_array_equal(b.fit.theta, a.fit.theta)
        np.testing.assert_array_equal(b.fit.predicted_N, a.fit.predicted_N)
        assert b.fit.iterations == a.fit.iterations
    base_a = [r.history_error_pct for r in in_process.baseline]
    assert [r.history_error_pct for r in in_workers.baseline] == base_a
    # ... and the work was spread (Selection.ran_in: each task's process): every full fit, every
    # fold kept and the unfitted model's predictions ran once (the race may run a fold ahead
    # of its round that it then does not need), with workers=1 in this process alone; with
    # workers=2 in this process (its host thread) and a worker process, both running fits (the
    # two full fits start first, one each; one process where only one core is usable)
    baseline = "the unfitted paper model"
    kept = {baseline} | {f"{c.label} (all heights)" for c in in_process.candidates}
    kept |= {f"{c.label} without {f.height_m:g} m" for c in in_process.candidates for f in c.folds}
    for selection in (in_process, in_workers):
        names = [name for name, _ in selection.ran_in]
        assert len(set(names)) == len(names) and kept <= set(names), names
    assert {pid for _, pid in in_process.ran_in} == {os.getpid()}
    fits_by: dict[int, list[str]] = {}
    for name, pid in in_workers.ran_in:
        if name != baseline:
            fits_by.setdefault(pid, []).append(name)
    assert os.getpid() in fits_by and len(fits_by) == min(2, usable_cores()), fits_by


@pytest.fixture(scope="module")
def in_batches(data):
    # the way a GPU runs it (the default there): every fit of the shared structure in one
    # batched program a round; here on the CPU, where it is slower but must give the same fits
    batched = Parallel(batch_fits=True)
    return select_model(
        data, CANDIDATES, blocked_forces=("paper",), parallel=batched, progress=False
    )


def test_fits_batched_in_one_program_give_the_in_process_selection(in_process, in_batches):
    # Each lane's arithmetic is its own, but a batch of 4 lanes is not compiled as 4 programs
    # of 1: the parameters agree to rounding, the optimiser takes the same steps and the
    # selection is the same. Measured: parameters 1.9e-15 and 9.8e-15 relative (two machines),
    # held-out errors 8.2e-15 relative, predicted forces 9.8e-12 N on peaks of 1.5 kN; held at
    # 10x the largest (a lane that took one other step would be off by far more).
    assert in_batches.recommended.label == in_process.recommended.label
    assert [c.label for c in in_batches.within_noise] == [c.label for c in in_process.within_noise]
    for a, b in zip(in_process.candidates, in_batches.candidates):
        np.testing.assert_allclose(b.fit.theta, a.fit.theta, rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(b.fold_errors_pct, a.fold_errors_pct, rtol=1e-13)
        np.testing.assert_allclose(b.fit.predicted_N, a.fit.predicted_N, rtol=0, atol=1e-10)
        assert b.fit.iterations == a.fit.iterations
    base_a = [r.history_error_pct for r in in_process.baseline]
    np.testing.assert_allclose(
        [r.history_error_pct for r in in_batches.baseline], base_a, rtol=1e-12
    )


def test_every_fold_of_every_candidate_is_there(in_workers, data):
    for c in in_workers.candidates:
        assert len(c.folds) == len(data.heights_m)
        assert np.all(np.isfinite(c.fold_errors_pct))


def test_a_bad_worker_count_is_named():
    with pytest.raises(ValueError, match=r"workers=0 .*valid range"):
        Parallel(workers=0)
    with pytest.raises(ValueError, match=r"parallel=-2 must be an rbjax Parallel"):
        select_model(object(), parallel=-2)


def _square(x):
    return x * x


def _die_once(marker, x):
    """Kills its worker process the first time it runs (the marker file tells)."""
    if not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(17)
    return x + 1


def _always_die(x):
    os._exit(17)


def _raise(x):
    raise ValueError(f"bad input {x}")


def test_follow_up_tasks_come_after_the_given_ones_in_order():
    def then(i, result):
        return [Task(f"child of {i}", _square, (result,))] if i < 2 else []

    tasks = [Task("a", _square, (2,)), Task("b", _square, (3,), cost=5)]
    out = run_tasks(Parallel(workers=1), tasks, then=then)
    assert out == [4, 9, 81, 16]  # b runs first (costlier): its child is added first


def test_a_worker_that_dies_costs_time_not_results(tmp_path):
    tasks = [Task("dies once", _die_once, (str(tmp_path / "died"), 1))]
    tasks += [Task(f"square {k}", _square, (k,)) for k in range(4)]
    # host=False: a task that kills the process it runs in would end this one too
    assert run_tasks(Parallel(workers=2, host=False), tasks) == [2, 0, 1, 4, 9]


def test_a_task_whose_worker_always_dies_is_named():
    start = time.perf_counter()
    with pytest.raises(TaskError, match="died 2 times; not finished: fatal fit"):
        run_tasks(
            Parallel(workers=2, retries=1, host=False), [Task("fatal fit", _always_die, (0,))]
        )
    assert time.perf_counter() - start < 60


def _pid(x):
    time.sleep(0.2)  # long enough that the next task finds this one's process busy
    return os.getpid(), x * x


def test_this_process_runs_tasks_beside_its_workers():
    """Parallel(workers=2): one task at a time in this process, the others in one worker
    process (the tasks' results in order either way); host=False: two worker processes, none
    here."""
    tasks = [Task(f"square {k}", _pid, (k,)) for k in range(6)]
    here = run_tasks(Parallel(workers=2), tasks)
    assert [x for _, x in here] == [k * k for k in range(6)]
    pids = {pid for pid, _ in here}
    assert os.getpid() in pids and len(pids) == 2
    away = run_tasks(Parallel(workers=2, host=False), tasks)
    assert [x for _, x in away] == [k * k for k in range(6)]
    assert os.getpid() not in {pid for pid, _ in away}
    with pytest.raises(ValueError, match="host='no' must be True or False"):
        Parallel(workers=2, host="no")


@pytest.mark.parametrize("workers", [1, 2])
def test_a_task_that_raises_is_named_with_its_error(workers):
    tasks = [Task("chunk rows 0–9 (E = 1.6 MPa)", _raise, (3,))]
    with pytest.raises(TaskError, match=r"chunk rows 0–9 \(E = 1.6 MPa\) failed: ValueError"):
        run_tasks(Parallel(workers=workers), tasks)

"""Batched fits: the program calls of many fits gathered into one batch, the way independent
fits share an accelerator.

On a GPU one Levenberg–Marquardt step costs about the same for 1 lane as for 64 (its time is
the sample loop's sequential depth, not arithmetic), so the fits of a model selection — every
candidate, fold and start of one shared structure — should go through the compiled program
together, not one after another. Their drivers (:func:`rbjax.fit.fit`: starts, rounds,
alignment, all on the host between program calls) stay as they are: each fit runs in a thread
of its own, and every call it makes of the fit program (:meth:`rbjax.fit.problem.Problem.
run_batch`, its lanes: one per start) is handed to the :class:`FitBatcher` given to it
(``FitOptions.batcher``, passed explicitly) instead of being run. When every fit taking
part waits for a call, the batcher runs them: the calls of one program (same structure,
optimiser, step budget, data and evaluate-only flag) are stacked into one batch, padded to the
next of a few sizes (:data:`BATCH_SIZES`, so that only a few shapes are compiled) by repeating
its last lane, run once, and split again. A fit that has converged makes no more calls, so its
lanes leave the batch; the rest are re-packed at the next call.

Each lane's arithmetic is that lane's alone (the program is ``vmap``-ped over the lanes), so a
batched fit gives the results it gives alone, to rounding.

:class:`BatchedFitExecutor` is the :class:`concurrent.futures.Executor` that runs tasks this way:
one thread a task, each called with the keyword ``batcher=`` (its one :class:`FitBatcher`),
which the task hands to its fits; :class:`rbjax.Parallel` chooses it with ``batch_fits=True``,
and by default where JAX's default device is not a CPU.
"""

from __future__ import annotations

import concurrent.futures as cf
import dataclasses
import threading
from collections.abc import Callable
from typing import Any

import jax
import numpy as np

from .program import run_lanes

__all__ = ["BATCH_SIZES", "FitBatcher", "BatchedFitExecutor", "padded_size"]

#: The batch sizes a program is compiled for: a batch of B lanes runs at the smallest size ≥ B
#: (beyond the largest, in multiples of it).
BATCH_SIZES = (1, 2, 4, 8, 16, 32, 64)


def padded_size(n: int) -> int:
    """The batch size ``n`` lanes run at (see :data:`BATCH_SIZES`)."""
    for size in BATCH_SIZES:
        if n <= size:
            return size
    top = BATCH_SIZES[-1]
    return -(-n // top) * top


@dataclasses.dataclass(eq=False)
class _Call:
    """One fit's call of a program: its lanes, and (once run) their outputs or the error."""

    key: Any
    lanes: Any  # a pytree of arrays with a leading lane axis
    shared: Any
    outputs: Any = None
    error: BaseException | None = None
    done: bool = False


class FitBatcher:
    """Gathers the program calls of the fits taking part and runs them as batches.

    ``run(key, lanes, shared)`` runs one batch: ``lanes`` (a pytree of arrays whose leading
    axis is the batch) stacked from every call of that ``key``, ``shared`` the first call's
    (equal for all calls of a key); it returns a pytree of outputs with the same leading axis.

    The fits taking part are counted: :meth:`join` before a fit starts, :meth:`leave` when it
    ends. A batch runs when every fit taking part waits in :meth:`call`.
    """

    def __init__(self, run: Callable[[Any, Any, Any], Any]):
        self._run = run
        self._cond = threading.Condition()
        self._members = 0
        self._pending: list[_Call] = []
        self._flushing = False
        self._closed = False
        #: (lanes asked for, lanes run including padding) of every batch run, in order
        self.batches: list[tuple[int, int]] = []

    def close(self) -> None:
        """No more batches: every call waiting now, and every later one, raises
        :class:`concurrent.futures.CancelledError` (the fits of a run that failed stop at their
        next call instead of running on unseen)."""
        with self._cond:
            self._closed = True
            for item in self._pending:
                item.error, item.done = cf.CancelledError("the fit executor was shut down"), True
            self._pending = []
            self._cond.notify_all()

    def join(self) -> None:
        with self._cond:
            self._members += 1

    def leave(self) -> None:
        with self._cond:
            self._members -= 1
        self._flush_when_all_wait()

    def call(self, key, lanes, shared):
        """Hand one call to the batch; its outputs once the batch has run (this thread waits)."""
        item = _Call(key, lanes, shared)
        with self._cond:
            if self._closed:
                raise cf.CancelledError("the fit executor was shut down")
            self._pending.append(item)
        self._flush_when_all_wait()
        with self._cond:
            while not item.done:
                self._cond.wait()
        if item.error is not None:
            raise item.error
        return item.outputs

    def _flush_when_all_wait(self) -> None:
        """Run the pending calls if every fit taking part waits for one (in this thread)."""
        while True:
            with self._cond:
                waiting = sum(not c.done for c in self._pending)
                if self._flushing or not self._pending or waiting < self._members:
                    return
                self._flushing = True
                batch, self._pending = self._pending, []
            try:
                self._run_batches(batch)
            finally:
                with self._cond:
                    self._flushing = False
                    for item in batch:
                        item.done = True
                    self._cond.notify_all()

    def _run_batches(self, calls: list[_Call]) -> None:
        groups: dict[Any, list[_Call]] = {}
        for item in calls:
            groups.setdefault(item.key, []).append(item)
        for key, group in groups.items():
            sizes = [len(jax.tree_util.tree_leaves(c.lanes)[0]) for c in group]
            total = sum(sizes)
            size = padded_size(total)

            def stack(*parts, pad=size - total):
                parts = tuple(np.asarray(x) for x in parts)
                return np.concatenate([*parts, np.repeat(parts[-1][-1:], pad, axis=0)])

            stacked = jax.tree_util.tree_map(stack, *[c.lanes for c in group])
            try:
                out = self._run(key, stacked, group[0].shared)
            except Exception as err:  # noqa: BLE001  (handed to each fit whose call it was)
                for item in group:
                    item.error = err
                continue
            self.batches.append((total, size))
            lo = 0
            for item, n in zip(group, sizes):
                item.outputs = jax.tree_util.tree_map(lambda v, lo=lo, n=n: v[lo : lo + n], out)
                lo += n


class BatchedFitExecutor(cf.Executor):
    """Runs each submitted task in a thread of its own, called with ``batcher=`` this executor's
    :class:`FitBatcher`, which every fit of the task gets (``FitOptions(batcher=...)``): every
    fit call of every task goes through it (see the module docstring).

    Args:
        run: how a batch runs (default: the fit program, :func:`rbjax.fit.program.run_lanes`).
    """

    def __init__(self, run: Callable[[Any, Any, Any], Any] | None = None):
        if run is None:
            run = run_lanes
        self.batcher = FitBatcher(run)
        self._threads: list[threading.Thread] = []

    def submit(self, fn, /, *args, **kwargs):
        future: cf.Future = cf.Future()
        self.batcher.join()

        def work():
            try:
                if future.set_running_or_notify_cancel():
                    try:
                        future.set_result(fn(*args, batcher=self.batcher, **kwargs))
                    except BaseException as err:  # noqa: BLE001  (to the caller by the future)
                        future.set_exception(err)
            finally:
                self.batcher.leave()

        thread = threading.Thread(target=work, daemon=True, name="rbjax-fit")
        self._threads.append(thread)
        thread.start()
        return future

    def shutdown(self, wait=True, *, cancel_futures=False):
        """With ``cancel_futures``, the fits still running stop at their next program call
        (:meth:`FitBatcher.close`)."""
        if cancel_futures:
            self.batcher.close()
        if wait:
            for thread in self._threads:
                thread.join()

"""Leave-one-height-out cross-validation of one candidate model: the errors of a held-out height
(:class:`HeldOut`, :func:`held_out_rows`), the fold fits as tasks of their own
(:func:`fit_task`, :func:`fold_tasks`) and :func:`cross_validate`, which runs them.

A fold refits the candidate without one height, warm-started from its full fit, and predicts
that height (the held-out record's onset is aligned with the prediction's, nothing else is
fitted to it). The held-out error is the rms of predicted − measured force over the held-out
record, in % of its measured peak.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ..._progress import progress as say
from ...fit import FitResult, fit, prepare_data
from ...fit.options import options_or_default
from ...solve.parallel import Parallel, parallel_or_default
from ..parallel.executors import Task, run_tasks

__all__ = [
    "HeldOut",
    "held_out_rows",
    "fit_task",
    "fold_tasks",
    "fold_row",
    "check_folds",
    "cross_validate",
]


@dataclasses.dataclass(frozen=True)
class HeldOut:
    """Errors of the prediction of one held-out height (predicted − measured)."""

    height_m: float
    history_error_pct: float
    contact_time_pct: float
    peak_force_pct: float
    lfe_octave_dB: tuple
    converged: bool = True

    def to_dict(self) -> dict:
        return dataclasses.asdict(self) | {"lfe_octave_dB": list(self.lfe_octave_dB)}


def held_out_rows(result, heights) -> list[HeldOut]:
    """Held-out errors at ``heights`` from a FitResult or a Prediction."""
    rows = []
    for h in heights:
        k = np.isclose(result.heights_m, h, atol=5e-4)
        row = next(r for r in result.per_height if abs(r["height_m"] - h) < 5e-4)
        rms = float(np.sqrt(np.mean((result.predicted_N[k] - result.measured_N[k]) ** 2)))
        peak = float(np.mean(np.max(result.measured_N[k], axis=1)))
        rows.append(
            HeldOut(
                height_m=float(h),
                history_error_pct=100.0 * rms / peak,
                contact_time_pct=row["error"]["contact_time_pct"],
                peak_force_pct=row["error"]["peak_force_pct"],
                lfe_octave_dB=tuple(float(x) for x in row["error"]["lfe_octave_dB"]),
                converged=result.converged,
            )
        )
    return rows


def fit_task(
    data, model, blocked_force, fit_heights, start, fit_kwargs, *, batcher=None
) -> FitResult:
    """One fit of a selection as a task of its own (a module-level function, so that a worker
    process or a Dask worker can run it): :func:`rbjax.fit.fit` without progress lines, its
    ``options`` (in ``fit_kwargs``) with ``fit_heights``, the ``structure`` of ``fit_kwargs``
    and ``batcher`` (given by ``rbjax.Parallel(batch_fits=True)``'s executor)."""
    kwargs = dict(fit_kwargs)
    structure = kwargs.pop("structure", None)
    options = options_or_default(kwargs.pop("options", None))
    options = options.replace(fit_heights=fit_heights, structure=structure, batcher=batcher)
    return fit(
        data,
        model,
        blocked_force=blocked_force,
        start=start,
        options=options,
        progress=False,
        **kwargs,
    )


def _without(data, height_m: float) -> list[float]:
    return [x for x in data.heights_m if abs(x - height_m) > 5e-4]


def fold_tasks(data, model, blocked_force, base: FitResult, heights, fit_kwargs, cost=1.0):
    """The leave-one-height-out refits of one candidate, warm-started from ``base``, one task a
    fold (the base fit's evaluations times ``cost`` estimate each fold's work)."""
    return [
        Task(
            f"{model}/{blocked_force} without {h:g} m",
            fit_task,
            (data, model, blocked_force, _without(data, h), base, fit_kwargs),
            cost=cost * max(base.iterations, 1),
        )
        for h in heights
    ]


def fold_row(model, blocked_force, h, res: FitResult, progress: bool) -> HeldOut:
    """The held-out errors of one fold's fit at its held-out height ``h``, said on stderr."""
    row = held_out_rows(res, [h])[0]
    say(
        f"cv {model}/{blocked_force}: without {h:g} m: held-out error "
        f"{row.history_error_pct:.2f} % of peak ({res.iterations} evaluations)",
        enabled=progress,
    )
    return row


def check_folds(data) -> None:
    """Raises ValueError unless ``data`` hold the two drop heights or more that folds need."""
    if len(data.heights_m) < 2:
        raise ValueError(
            f"cross-validation needs at least 2 drop heights; the data have {len(data.heights_m)}"
        )


def cross_validate(
    data,
    model: str,
    *,
    blocked_force: str = "paper",
    base: FitResult | None = None,
    heights: Sequence[float] | None = None,
    parallel: Parallel | None = None,
    progress: bool = True,
    **fit_kwargs,
) -> tuple[HeldOut, ...]:
    """Leave-one-height-out: refit without each height (warm start from ``base``), predict it.

    The folds are independent tasks, run where ``parallel`` says.

    Args:
        data: a :class:`~rbjax.fit.FitData`, recordings or paths (see
            :func:`rbjax.fit.prepare_data`).
        model: the model name (:mod:`rbjax.fit`).
        blocked_force: the blocked-force definition, ``"paper"`` or ``"momentum"``.
        base: the full fit the folds start from (default: fitted here to every height, with
            ``fit_kwargs``).
        heights: the heights held out in turn, m (default: every height in the data).
        parallel: where the folds run, an :class:`rbjax.Parallel` (default
            ``Parallel(workers=1)``: one after another in this process).
        progress: one line per fold on stderr.
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        One :class:`HeldOut` per held-out height, a tuple in the order of ``heights``.

    Raises:
        ValueError: data with fewer than two drop heights, a held-out height that is not one
            of the data's, or data that cannot be prepared (``rbjax.data.DataError``).
        rbjax.studies.parallel.executors.TaskError: a fold's fit failed (named).
    """
    data = prepare_data(data)
    check_folds(data)
    folds = data.heights_m if heights is None else np.atleast_1d(np.asarray(heights, dtype=float))
    absent = [float(h) for h in folds if not np.any(np.isclose(data.heights_m, h, atol=5e-4))]
    if absent:
        raise ValueError(
            f"heights={absent} m are not drop heights of the data; valid: "
            f"{[float(h) for h in data.heights_m]} m"
        )
    if base is None:
        base = fit(data, model, blocked_force=blocked_force, progress=False, **fit_kwargs)
    tasks = fold_tasks(data, model, blocked_force, base, folds, fit_kwargs)
    where = parallel_or_default(parallel, Parallel(workers=1))
    results = run_tasks(where, tasks, label=f"cv {model}/{blocked_force}")
    return tuple(fold_row(model, blocked_force, h, res, progress) for h, res in zip(folds, results))

"""The held-out comparison: each candidate fitted to some heights only and asked to predict the
others, beside the unfitted paper model (:func:`held_out_comparison`,
:class:`HoldOutComparison`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from ..._progress import progress as say
from ...fit import MODEL_NAMES, FitResult, predict, prepare_data
from ...solve.parallel import Parallel
from ...spectrum.bands import OCTAVE_BANDS
from ...terms.model import BLOCKED_FORCE_OPTIONS
from ...text import fmt, format_table
from ..parallel.executors import Task, run_tasks
from .candidates import candidate_pairs, shared_structures, structure_cost
from .cross_validation import fit_task, held_out_rows

__all__ = ["HoldOutComparison", "held_out_comparison"]


@dataclasses.dataclass(frozen=True, eq=False)
class HoldOutComparison:
    """Errors at heights left out of the fit, per candidate, with the unfitted paper model."""

    fit_heights_m: tuple
    predict_heights_m: tuple
    rows: dict  # label -> tuple[HeldOut]

    def table(self) -> str:

        header = ["model", "h (m)", "history (%)", "Δt_c (%)", "Δpeak (%)"] + [
            f"ΔL {b} (dB)" for b in OCTAVE_BANDS
        ]
        rows = []
        for label, held in self.rows.items():
            for r in held:
                rows.append(
                    [
                        label,
                        f"{r.height_m:.2f}",
                        fmt(r.history_error_pct, ".2f"),
                        fmt(r.contact_time_pct, "+.2f"),
                        fmt(r.peak_force_pct, "+.2f"),
                    ]
                    + [fmt(x, "+.2f") for x in r.lfe_octave_dB]
                )
        fitted = ", ".join(f"{h:g}" for h in self.fit_heights_m)
        return (
            format_table(header, rows)
            + f"\n(fitted to {fitted} m; errors are predicted − measured at the other heights)"
        )

    def to_dict(self) -> dict:
        return {
            "fit_heights_m": list(self.fit_heights_m),
            "predict_heights_m": list(self.predict_heights_m),
            "rows": {k: [r.to_dict() for r in v] for k, v in self.rows.items()},
        }


def held_out_comparison(
    data,
    fit_heights: Sequence[float],
    candidates: Sequence[str] = MODEL_NAMES,
    *,
    blocked_forces: Sequence[str] = BLOCKED_FORCE_OPTIONS,
    starts: dict | None = None,
    parallel: Parallel | None = None,
    progress: bool = True,
    **fit_kwargs,
) -> HoldOutComparison:
    """Fit each candidate to ``fit_heights`` only and predict the other heights; the unfitted
    paper model (``JIS_RUBBER_BALL``, adiabatic gas, ``paper`` blocked force) is the baseline.

    Args:
        data: a :class:`~rbjax.fit.FitData`, recordings or paths (see
            :func:`rbjax.fit.prepare_data`).
        fit_heights: the heights fitted, m; the other heights of the data are predicted.
        candidates: model names, as in :func:`~rbjax.studies.selection.select.select_model`.
        blocked_forces: the blocked-force definitions each name is tried with, as in
            :func:`~rbjax.studies.selection.select.select_model`.
        starts: optional warm starts, {(model, blocked_force): FitResult}.
        parallel: an :class:`rbjax.Parallel`, as in
            :func:`~rbjax.studies.selection.select.select_model` (each candidate's fit is a
            task; default ``Parallel()``).
        progress: one line per fit on stderr.
        fit_kwargs: to :func:`rbjax.fit.fit` (``gas``, ``fix``, ``options``, …).

    Returns:
        The :class:`HoldOutComparison`: the errors at the held-out heights per candidate
        (``"model/blocked force"``) and of ``"paper (unfitted)"``.

    Raises:
        ValueError: every height of the data is in ``fit_heights``, bad candidate names or
            blocked forces, or data that cannot be prepared (``rbjax.data.DataError``).
        rbjax.studies.parallel.executors.TaskError: a candidate's fit failed (named).
    """
    pairs = candidate_pairs(candidates, blocked_forces)
    data = prepare_data(data)
    structures = shared_structures(
        [name for name, _ in pairs],
        fit_kwargs.get("gas", "adiabatic"),
        fit_kwargs.pop("structure", None),
    )
    fit_heights = tuple(float(h) for h in fit_heights)
    rest = tuple(
        float(h) for h in data.heights_m if not any(abs(h - f) < 5e-4 for f in fit_heights)
    )
    if not rest:
        raise ValueError("held_out_comparison: every height is in fit_heights; nothing is held out")
    tasks = [
        Task(
            f"{name}/{bf} fitted to {len(fit_heights)} heights",
            fit_task,
            (
                data,
                name,
                bf,
                fit_heights,
                (starts or {}).get((name, bf)),
                {**fit_kwargs, "structure": structures[name]},
            ),
            cost=structure_cost(name),
        )
        for name, bf in pairs
    ]

    def then(i: int, res: FitResult):
        if i < len(pairs):
            say(f"held-out: {tasks[i].name} ({res.message})", enabled=progress)
        return []

    results = run_tasks(parallel, tasks, then=then, label="held-out comparison")
    rows = {f"{name}/{bf}": tuple(held_out_rows(r, rest)) for (name, bf), r in zip(pairs, results)}
    rows["paper (unfitted)"] = tuple(
        held_out_rows(predict(data, structure=structures[pairs[0][0]]), rest)
    )
    return HoldOutComparison(fit_heights, rest, rows)

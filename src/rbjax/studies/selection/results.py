"""What a model selection yields: a :class:`Candidate` (one model's full fit and its held-out
errors) and the :class:`Selection` (every candidate, the one recommended, and their table).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from ...fit import FitResult
from ...spectrum.bands import OCTAVE_BANDS
from ...text import fmt, format_table

if TYPE_CHECKING:
    from .race import Dropped, RaceSummary

__all__ = ["Candidate", "Selection"]


@dataclasses.dataclass(frozen=True, eq=False)
class Candidate:
    """One candidate model: its full fit and its cross-validated (held-out) errors.

    Attributes:
        model_name: the model name (:mod:`rbjax.fit`).
        blocked_force: its blocked-force definition, ``"paper"`` or ``"momentum"``.
        fit: its full fit to every height (:class:`~rbjax.fit.FitResult`).
        folds: its :class:`~rbjax.studies.selection.cross_validation.HeldOut` errors, one per
            height left out (for a candidate dropped from the race, the folds it ran).
        dropped: why and when it left the race (a
            :class:`~rbjax.studies.selection.race.Dropped`), ``None`` if it ran every fold.
    """

    model_name: str
    blocked_force: str
    fit: FitResult
    folds: tuple
    dropped: Dropped | None = None

    @property
    def label(self) -> str:
        return f"{self.model_name}/{self.blocked_force}"

    @property
    def n_physical(self) -> int:
        """Fitted physical parameters (E and the damping/stiffening ones; ν is held)."""
        return len(self.fit.correlations[0])

    @property
    def fold_errors_pct(self) -> np.ndarray:
        return np.array([f.history_error_pct for f in self.folds])

    @property
    def cv_error_pct(self) -> float:
        """The mean held-out error over the folds run (% of peak; NaN if none ran)."""
        e = self.fold_errors_pct
        return float(np.mean(e)) if e.size else float("nan")

    @property
    def cv_se_pct(self) -> float:
        e = self.fold_errors_pct
        return float(np.std(e, ddof=1) / math.sqrt(e.size)) if e.size > 1 else float("nan")

    def mean_abs(self, name: str):
        if not self.folds:  # dropped from the race before any of its folds ran
            return np.full(len(OCTAVE_BANDS), np.nan) if name == "lfe_octave_dB" else math.nan
        values = np.array([getattr(f, name) for f in self.folds], dtype=float)
        return np.mean(np.abs(values), axis=0)

    def to_dict(self) -> dict:
        return {
            "model_name": self.model_name,
            "blocked_force": self.blocked_force,
            "n_physical": self.n_physical,
            "converged": self.fit.converged,
            "residual_rms_N": self.fit.residual_rms_N,
            "aic": self.fit.aic,
            "bic": self.fit.bic,
            "cv_history_error_pct": self.cv_error_pct,
            "cv_history_error_se_pct": self.cv_se_pct,
            "cv_mean_abs_contact_time_pct": float(self.mean_abs("contact_time_pct")),
            "cv_mean_abs_peak_force_pct": float(self.mean_abs("peak_force_pct")),
            "cv_mean_abs_lfe_octave_dB": self.mean_abs("lfe_octave_dB").tolist(),
            "parameters": {k: v.to_dict() for k, v in self.fit.parameters.items()},
            "folds": [f.to_dict() for f in self.folds],
            "dropped": None if self.dropped is None else self.dropped.to_dict(),
        }


@dataclasses.dataclass(frozen=True, eq=False)
class Selection:
    """The outcome of :func:`~rbjax.studies.selection.select.select_model`.

    Attributes:
        candidates: every :class:`Candidate`, in the order they were tried.
        recommended: the :class:`Candidate` the rule recommends.
        within_noise: the candidates within the noise of the best
            (:func:`~rbjax.studies.selection.rule.recommend`).
        rule: the rule, in words.
        blocked_force_note: what the held-out errors say about the blocked-force definition
            of the recommended model.
        baseline: the unfitted paper model's
            :class:`~rbjax.studies.selection.cross_validation.HeldOut` errors at every height.
        elapsed_s: how long the selection took, s.
        race: the race's rounds and what it dropped
            (:class:`~rbjax.studies.selection.race.RaceSummary`); ``None`` for an exhaustive
            selection (every candidate ran every fold).
        ran_in: where each task ran, ``(task name, process id)`` in the order the tasks
            finished: the full fits (``"zener/paper (all heights)"``), the folds
            (``"zener/paper without 0.4 m"``) and the unfitted model's predictions, each with
            the ``os.getpid()`` of the process that ran it (this one's, a local worker's, a
            Dask worker's on its host). A record of where the work went, not a result: it is
            in neither the table nor ``to_dict``, and two runs of one selection differ in it.
    """

    candidates: tuple
    recommended: Candidate
    within_noise: tuple
    rule: str
    blocked_force_note: str
    baseline: tuple
    elapsed_s: float
    race: RaceSummary | None = None
    ran_in: tuple[tuple[str, int], ...] = ()

    def table(self) -> str:

        header = [
            "model",
            "blocked force",
            "p",
            "conv",
            "rms (N)",
            "CV err (%)",
            "± SE",
            "|Δt_c| (%)",
            "|Δpeak| (%)",
        ]
        header += [f"|ΔL| {b}" for b in OCTAVE_BANDS] + ["AIC", "BIC", ""]
        rows = []
        for c in self.candidates:
            mark = (
                "recommended"
                if c is self.recommended
                else ("within noise" if c in self.within_noise else "")
            )
            cv = fmt(c.cv_error_pct, ".2f")
            if c.dropped is not None:
                mark = f"dropped after round {c.dropped.round}"
                cv = f"{cv} ({len(c.folds)} folds)" if c.folds else "— (no fold)"
            rows.append(
                [
                    c.model_name,
                    c.blocked_force,
                    str(c.n_physical),
                    "yes" if c.fit.converged else "no",
                    fmt(c.fit.residual_rms_N, ".1f"),
                    cv,
                    fmt(c.cv_se_pct, ".2f"),
                    fmt(c.mean_abs("contact_time_pct"), ".2f"),
                    fmt(c.mean_abs("peak_force_pct"), ".2f"),
                ]
                + [fmt(x, ".2f") for x in c.mean_abs("lfe_octave_dB")]
                + [fmt(c.fit.aic, ".0f"), fmt(c.fit.bic, ".0f"), mark]
            )
        base = self.baseline
        rows.append(
            [
                "paper (unfitted)",
                "paper",
                "0",
                "—",
                "—",
                fmt(np.mean([b.history_error_pct for b in base]), ".2f"),
                "—",
                fmt(np.mean([abs(b.contact_time_pct) for b in base]), ".2f"),
                fmt(np.mean([abs(b.peak_force_pct) for b in base]), ".2f"),
            ]
            + [fmt(x, ".2f") for x in np.mean([np.abs(b.lfe_octave_dB) for b in base], axis=0)]
            + ["—", "—", "JIS ball, E = 1.6 MPa"]
        )
        lines = [
            format_table(header, rows),
            "",
            f"held-out errors: leave-one-height-out over {len(self.recommended.folds)} heights "
            "(|Δ|: mean over the folds).",
            f"rule: {self.rule}.",
            f"recommended: {self.recommended.label}.",
            self.blocked_force_note,
            *(self.race.lines() if self.race is not None else []),
            f"selection took {self.elapsed_s:.0f} s.",
        ]
        return "\n".join(lines)

    def to_dict(self) -> dict:

        return {
            "recommended": {
                "model_name": self.recommended.model_name,
                "blocked_force": self.recommended.blocked_force,
            },
            "within_noise": [c.label for c in self.within_noise],
            "rule": self.rule,
            "blocked_force_note": self.blocked_force_note,
            "octave_bands_Hz": list(OCTAVE_BANDS),
            "candidates": [c.to_dict() for c in self.candidates],
            "baseline_paper_unfitted": [b.to_dict() for b in self.baseline],
            "elapsed_s": self.elapsed_s,
            "race": None if self.race is None else self.race.to_dict(),
        }

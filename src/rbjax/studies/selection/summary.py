"""Model selection for summary fits by held-out figures (leave one figure out).

Every candidate model is fitted to all the figures of the fit; then, for each figure in turn,
fitted again without it (warm-started from the full fit) and asked to predict it. The score is
the rms of the held-out errors in units of each figure's uncertainty; the recommended model has
the lowest score. A model is a candidate only where leaving one figure out still leaves at least
as many figures as it has free parameters; with fewer figures than that for every model, the
selection says so and recommends nothing.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from ..._progress import progress as say
from ...fit.layout import fitted_parameter_names, model_from_name
from ...fit.summary import as_table, fit_summary
from ...fit.summary_result import SummaryFitResult
from ...text import format_table

#: The candidates compared by default: the paper's elastic model, with cubic stiffening, and two
#: damping laws (on the fast exact paths; the ball mode runs on the ODE and is left out).
SUMMARY_MODELS = ("paper", "paper+stiffening", "kelvin-voigt", "zener")


@dataclasses.dataclass(frozen=True, eq=False)
class SummaryCandidate:
    fit: SummaryFitResult
    held_out_rms: float
    held_out_errors: tuple


@dataclasses.dataclass(frozen=True, eq=False)
class SummarySelection:
    """Candidates (by model name) with their held-out scores; ``recommended`` (None where no
    model had enough figures) and ``skipped`` (model → why)."""

    candidates: dict
    recommended: str | None
    skipped: dict

    def table(self) -> str:

        rows = [
            [
                name,
                str(c.fit.n_free),
                f"{c.fit.chi2:.3g}",
                f"{c.held_out_rms:.3g}",
                "←" if name == self.recommended else "",
            ]
            for name, c in self.candidates.items()
        ]
        lines = [format_table(["model", "free", "χ² (all)", "held-out rms (σ)", ""], rows)]
        lines += [f"{k}: skipped ({v})" for k, v in self.skipped.items()]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {
            "method": "leave one figure out",
            "recommended": self.recommended,
            "candidates": {
                k: {
                    "held_out_rms_sigma": c.held_out_rms,
                    "held_out_errors_sigma": list(c.held_out_errors),
                    "chi2": c.fit.chi2,
                    "n_free": c.fit.n_free,
                }
                for k, c in self.candidates.items()
            },
            "skipped": dict(self.skipped),
        }


def select_summary(
    table, models: Sequence[str] = SUMMARY_MODELS, *, held_out=(), progress: bool = False, **options
) -> SummarySelection:
    """Compare ``models`` on the table's figures by leave-one-figure-out prediction (see the
    module docstring). ``held_out`` figures stay out of every fit; ``options`` go to
    :func:`rbjax.fit.summary.fit_summary` (``fix``, ``gas``, ``blocked_force``, ``ball``)."""
    table = as_table(table)
    held = {(round(float(h), 4), f) for h, f in held_out}
    entries = [
        (float(table.heights_m[i]), f)
        for i, f in table.entries()
        if (round(float(table.heights_m[i]), 4), f) not in held
    ]
    candidates, skipped = {}, {}
    fix = dict(options.get("fix") or {})
    for name in models:
        structure = model_from_name(
            name,
            gas=options.get("gas", "adiabatic"),
            blocked_force=options.get("blocked_force", "paper"),
        )
        p = len([n for n in fitted_parameter_names(structure) if n != "poisson" and n not in fix])
        if len(entries) - 1 < p:
            skipped[name] = (
                f"{p} free parameters need at least {p + 1} figures to leave one out; the fit has "
                f"{len(entries)}"
            )
            continue
        full = fit_summary(table, name, held_out=list(held_out), **options)
        start = {
            k: v.value
            for k, v in full.parameters.items()
            if not v.fixed and k != "effective_modulus_Pa"
        }
        errors = []
        for h, f in entries:
            part = fit_summary(
                table, name, held_out=list(held_out) + [(h, f)], start=start, **options
            )
            errors.append(part.row(h, f)["normalised_error"])
        rms = math.sqrt(float(np.mean(np.square(errors))))
        candidates[name] = SummaryCandidate(full, rms, tuple(errors))
        say(
            f"select_summary {name}: held-out rms {rms:.3g} σ over {len(errors)} figures",
            enabled=progress,
        )
    recommended = min(candidates, key=lambda k: candidates[k].held_out_rms) if candidates else None
    return SummarySelection(candidates, recommended, skipped)

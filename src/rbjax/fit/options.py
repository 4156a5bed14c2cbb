"""The options of a fit as one frozen object: :class:`FitOptions`.

What :func:`rbjax.fit.fit` compares and how it optimises (the residual's scale, decimation and
extra rows, the optimiser and its step budget, the prediction's path and ``Solver``, how ν is
held or given a prior, the drop-height errors, which heights enter, the shared program), passed
along as one validated object instead of a dozen keywords relayed through the set-up and the
optimiser's rounds (as optimistix passes a solver carrying its tolerances).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

from .._validate import check_choice, check_range, settings_or_default
from ..solve.solver import Solver
from ..terms.model import Model
from .batching import FitBatcher
from .problem import FIT_PATHS
from .program import OPTIMIZERS

SCALES = ("noise", "peak")
EXTRA_TERMS = ("contact_time", "peak_force", "lfe")


@dataclasses.dataclass(frozen=True)
class FitOptions:
    """How a fit compares the model with the records and optimises (``rbjax.fit.fit``).

    Attributes:
        optimizer: ``lm`` (optimistix Levenberg–Marquardt) or ``gauss-newton`` (optimistix).
        scale: residual of record k divided by its noise rms (``noise``) or peak (``peak``).
        decimate: use every n-th sample in the residual (an integer ≥ 1).
        extra_weights: {"contact_time": w, "peak_force": w, "lfe": w} (w ≥ 0): extra residual
            rows w·(relative error) for contact time and peak, w·(ΔL_FE in dB) per octave band.
        max_steps: optimiser steps in all (default 40 per round, at most 8 rounds; 0 evaluates
            the start only).
        path: ``auto`` (default: the force at the records' own samples by fixed steps,
            :mod:`rbjax.fit.record_forces`, where the model allows it; the diffrax ODE with its
            events for moving floors or when a ``solver`` is given), ``samples`` or ``ode``
            (the reference). ``method`` of the previous release.
        solver: an ``rbjax.Solver`` (forced to ``adjoint="forward"``): the prediction then runs
            on the diffrax ODE.
        hold_poisson: value in (−1, 0.5] at which ν is held when the Jacobian shows E and ν are
            not separately identifiable (always, for these models: §2.1 Eqs. 1–3).
        poisson_prior: (mean, std) of a Gaussian prior on ν instead of holding it
            (−1 < mean < 0.5, std > 0).
        height_error: also fit each record's drop-height error, bounded by ±1 cm.
        fit_heights: heights (m) whose records enter the fit (default all); the others are
            predicted (onset-aligned, nothing fitted to them) and reported as held out.
        structure: a model containing every term of the fitted model (e.g.
            ``rbjax.terms.model.structure_model``): the fit runs in its compiled program with the
            terms the model lacks held at their values, so fits of different models share one
            program (model selection does this).
        batcher: the :class:`~rbjax.fit.batching.FitBatcher` the fit's program calls go to,
            gathered with those of other fits into one batch per program (what
            ``rbjax.Parallel(batch_fits=True)`` gives each fit of a study; default ``None``:
            each call runs at once).

    Raises:
        ValueError: ``optimizer``, ``scale`` or ``path`` is not an option; ``decimate`` is
            not an integer ≥ 1; ``hold_poisson`` is outside (−1, 0.5]; ``poisson_prior`` is
            not a (mean, std) with −1 < mean < 0.5, std > 0; ``extra_weights`` names an
            unknown term or gives a negative or non-finite weight; ``max_steps`` is not an
            integer ≥ 0; ``solver`` is not an ``rbjax.Solver``; ``structure`` is not an
            ``rbjax.Model``; ``batcher`` is not a ``FitBatcher``; ``height_error`` is not a
            bool; ``fit_heights`` is not a sequence of finite heights.
    """

    optimizer: str = "lm"
    scale: str = "noise"
    decimate: int = 1
    extra_weights: Mapping[str, float] | None = None
    max_steps: int | None = None
    path: str = "auto"
    solver: Solver | None = None
    hold_poisson: float = 0.5
    poisson_prior: tuple[float, float] | None = None
    height_error: bool = False
    fit_heights: Sequence[float] | None = None
    structure: Model | None = None
    batcher: FitBatcher | None = None

    def __post_init__(self):
        check_choice("optimizer", self.optimizer, OPTIMIZERS)
        check_choice("scale", self.scale, SCALES)
        check_choice("path", self.path, FIT_PATHS)
        if not (isinstance(self.decimate, int) and self.decimate >= 1):
            raise ValueError(f"decimate={self.decimate!r} must be an integer >= 1")
        if not (
            isinstance(self.hold_poisson, int | float)
            and not isinstance(self.hold_poisson, bool)
            and -1.0 < self.hold_poisson <= 0.5
        ):
            raise ValueError(
                f"hold_poisson={self.hold_poisson!r} is outside the valid range (-1, 0.5]"
            )
        if self.poisson_prior is not None:
            mean, std = (float(x) for x in self.poisson_prior)
            if not (-1.0 < mean < 0.5 and std > 0):
                raise ValueError(
                    f"poisson_prior={self.poisson_prior!r}: need (mean, std) with -1 < mean < 0.5 "
                    "and std > 0"
                )
            object.__setattr__(self, "poisson_prior", (mean, std))
        for k, weight in (self.extra_weights or {}).items():
            if k not in EXTRA_TERMS:
                raise ValueError(
                    f"extra_weights: unknown term {k!r}; valid: {', '.join(EXTRA_TERMS)}"
                )
            check_range(f"extra_weights[{k!r}]", weight, lower=0.0, lower_open=False)
        steps = self.max_steps
        if steps is not None and not (
            isinstance(steps, (int, np.integer)) and not isinstance(steps, bool) and steps >= 0
        ):
            raise ValueError(
                f"max_steps={steps!r} is outside the valid range: an integer ≥ 0 "
                "(0: evaluate the start only)"
            )
        if self.solver is not None and not isinstance(self.solver, Solver):
            raise ValueError(f"solver={self.solver!r} must be an rbjax.Solver")
        if self.structure is not None and not isinstance(self.structure, Model):
            raise ValueError(f"structure={self.structure!r} must be an rbjax.Model or None")
        if self.batcher is not None and not isinstance(self.batcher, FitBatcher):
            raise ValueError(f"batcher={self.batcher!r} must be an rbjax.fit.batching.FitBatcher")
        if not isinstance(self.height_error, bool):
            raise ValueError(f"height_error={self.height_error!r} must be True or False")
        if self.fit_heights is not None:
            heights = np.atleast_1d(np.asarray(self.fit_heights, dtype=float))
            if heights.ndim != 1 or not np.all(np.isfinite(heights)):
                raise ValueError(
                    f"fit_heights={self.fit_heights!r} must be a sequence of finite heights (m)"
                )

    def replace(self, **changes) -> FitOptions:
        """A copy with ``changes`` (validated again)."""
        return dataclasses.replace(self, **changes)

    def steps_budget(self, default: int) -> int:
        """``max_steps``, or ``default`` where it is not given."""
        return default if self.max_steps is None else int(self.max_steps)


def options_or_default(options: FitOptions | None) -> FitOptions:
    """``options``, or ``FitOptions()`` when it is ``None`` (anything else: a ``ValueError``)."""
    return settings_or_default("options", FitOptions, options)

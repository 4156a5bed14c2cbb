"""The set-up of one fit (the first step of :func:`rbjax.fit.driver.fit`): the model, the
parameters held, the conditioned records, the :class:`~rbjax.fit.problem.Problem` with its
layout and constants, and which records enter the fit, in one frozen :class:`FitSetup` that the
later steps (:mod:`~rbjax.fit.start`, :mod:`~rbjax.fit.estimates`) read."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..terms.ball import Ball
from ..terms.model import Model
from .layout import CONSTANT_PARAMETERS, FitLayout, fitted_parameter_names
from .options import FitOptions
from .problem import Problem, candidate_model, embed, fit_path, fit_solver
from .records import FitData, prepare_data

#: Parameters that may be held at 0 (the ball mode off, μ = 0, or lossless, η = 0; the
#: series element rigid, C = 0).
NON_NEGATIVE_FIX = ("mode_mass_ratio", "mode_loss_factor", "series_compliance_m_per_N")


def validate_fix(names, fix):
    out = {}
    for k, v in (fix or {}).items():
        if k not in names:
            raise ValueError(
                f"fix: unknown parameter {k!r} for this model; valid: {', '.join(sorted(names))}"
            )
        try:
            value = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"fix: {k}={v!r} is not a number") from None
        out[k] = value
    if "poisson" in out and not -1.0 < out["poisson"] <= 0.5:
        raise ValueError(f"fix: poisson={out['poisson']!r} is outside the valid range (-1, 0.5]")
    for k, v in out.items():
        if k in NON_NEGATIVE_FIX:
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(
                    f"fix: {k}={v!r} must be non-negative and finite (valid range: [0, inf))"
                )
        elif k != "poisson" and not (math.isfinite(v) and v > 0):
            raise ValueError(f"fix: {k}={v!r} must be positive and finite (valid range: (0, inf))")
    return out


def _height_mask(data: FitData, heights) -> np.ndarray:
    if heights is None:
        return np.ones(data.n_records, dtype=bool)
    wanted = np.atleast_1d(np.asarray(heights, dtype=float))
    mask = np.zeros(data.n_records, dtype=bool)
    for h in wanted:
        hit = np.isclose(data.height_m, h, atol=5e-4)
        if not hit.any():
            raise ValueError(
                f"fit_heights: no record at height {h:g} m; heights in the data: "
                f"{', '.join(f'{x:g}' for x in data.heights_m)}"
            )
        mask |= hit
    return mask


@dataclasses.dataclass(frozen=True, eq=False)
class FitSetup:
    """What every step of a fit reads (built once by :func:`set_up`, never changed).

    ``model_name``/``candidate``: the model as named and as built; ``fittable``: its fitted
    parameter names; ``fixed``: name → value held; ``ball``: with the held geometry;
    ``fit_mask``: the records that enter the fit; ``constants``: the layout's constant values;
    ``why_ode``: why the prediction runs on the diffrax ODE (``None`` on the sampled path);
    ``extra``: the extra residual rows' weights; ``poisson_prior``: (mean, std) of ν or ``None``.
    """

    model_name: str
    candidate: Model
    fittable: tuple[str, ...]
    fixed: dict[str, float]
    ball: Ball
    data: FitData
    fit_mask: np.ndarray
    problem: Problem
    constants: np.ndarray
    why_ode: str | None
    extra: dict[str, float]
    poisson_prior: tuple[float, float] | None

    @property
    def layout(self) -> FitLayout:
        return self.problem.layout

    @property
    def structure(self) -> Model:
        """The model whose compiled program the fit runs (``candidate`` or its shared structure)."""
        return self.problem.structure_model

    @property
    def label(self) -> str:
        """The fit's name in progress lines."""
        return f"fit {self.model_name}/{self.candidate.blocked_force}"


def set_up(
    data, model, *, blocked_force: str, gas: str, ball: Ball, fix, options: FitOptions
) -> FitSetup:
    """The model and the parameters it holds (checked), the records, and the problem built on
    them (see :func:`rbjax.fit.driver.fit` for the arguments, ``options`` its
    :class:`~rbjax.fit.options.FitOptions`)."""
    model_name, candidate = candidate_model(model, blocked_force, gas)
    fittable = fitted_parameter_names(candidate)
    fixed = validate_fix(set(fittable) | set(CONSTANT_PARAMETERS[:3]), fix)
    poisson_prior, extra_weights = options.poisson_prior, options.extra_weights
    if "poisson" in fixed and poisson_prior is not None:
        raise ValueError("poisson is both fixed and given a prior; choose one")
    data = prepare_data(data)
    ball = ball.replace(**{k: v for k, v in fixed.items() if k in CONSTANT_PARAMETERS})
    fit_mask = _height_mask(data, options.fit_heights)
    structure = embed(candidate, options.structure, ball)
    path, why_ode = fit_path(options.path, structure, options.solver)
    problem = Problem(
        data,
        ball,
        structure,
        fit_solver(options.solver),
        height_error=options.height_error,
        decimate=options.decimate,
        scale=options.scale,
        path=path,
        feature_rows=any(w > 0 for w in (extra_weights or {}).values()),
    )
    problem.batcher = options.batcher
    return FitSetup(
        model_name=model_name,
        candidate=candidate,
        fittable=fittable,
        fixed=fixed,
        ball=ball,
        data=data,
        fit_mask=fit_mask,
        problem=problem,
        constants=problem.layout.constant_values(ball, structure),
        why_ode=why_ode,
        extra=dict(extra_weights or {}),
        poisson_prior=poisson_prior,
    )

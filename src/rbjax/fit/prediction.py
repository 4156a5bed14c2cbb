"""Predictions of given (unfitted) models against the records, and their exact Jacobians."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .._x64 import require_x64
from ..solve.solver import Solver
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.model import Model
from ..terms.parameters import replace
from .batching import FitBatcher
from .layout import fitted_parameter_names
from .problem import Problem, aligned, candidate_model, fit_path, fit_solver, per_height_rows
from .records import prepare_data
from .result import Prediction


def predict(
    data,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    *,
    solver: Solver | None = None,
    structure: Model | None = None,
    batcher: FitBatcher | None = None,
) -> Prediction:
    """Compare a given (unfitted) model with the records; nothing is fitted.

    The model's floor force goes through the records' measuring chain; each record's onset
    is aligned with the predicted one (5 % of the peak); contact time, peak and octave-band
    L_FE are read off both with the same estimator.

    Args:
        data: a :class:`FitData`, Recording objects, or paths/a directory (see
            :func:`prepare_data`).
        ball: geometry, mass and E, ν of the ball.
        model: any ``rbjax.Model`` (default: the paper's elastic model).
        solver: an ``rbjax.Solver`` (forced to ``adjoint="forward"``): the prediction then
            runs on the diffrax ODE; default: the fit's path for the model.
        structure: run in that model's compiled program (see :func:`fit`).
        batcher: the :class:`~rbjax.fit.batching.FitBatcher` the program's calls go to (as
            ``FitOptions.batcher``; default: they run at once).

    Returns:
        The :class:`Prediction`: ``per_height`` rows as in :class:`FitResult` (all held
        out), the time axis, the measured and the predicted (filtered) records, N, and each
        record's drop height, m.

    Raises:
        RuntimeError: float64 was switched off after importing rbjax.
        ValueError: ``solver`` is not an ``rbjax.Solver``, or ``structure`` has another gas
            or lacks a term of ``model``.
        TypeError: a model name that is not a str.
        DataError: the records cannot be prepared (see :func:`prepare_data`).
    """
    require_x64()
    model = Model() if model is None else model
    problem, _, out = aligned(data, ball, model, solver, structure, batcher)
    d = problem.data
    rows = per_height_rows(
        problem, out["force"], out["features"], np.zeros(d.n_records, dtype=bool)
    )
    return Prediction(tuple(rows), d.time_s, d.force_N, out["force"], d.height_m)


def model_histories(
    data,
    model: str | Model,
    params: Mapping[str, float],
    onset_shift_s,
    *,
    blocked_force: str = "paper",
    gas: str = "adiabatic",
    ball: Ball = JIS_RUBBER_BALL,
    solver: Solver | None = None,
):
    """The predicted records of :func:`fit` and their exact Jacobian, for given parameters.

    Args:
        data: a :class:`FitData`, Recording objects, or paths/a directory (see
            :func:`prepare_data`).
        model: a model name or an ``rbjax.Model`` (its values replaced by ``params``).
        params: name → value of every name of ``rbjax.fit.fitted_parameter_names(model)``, in the
            units the names state (others are not used).
        onset_shift_s: the contact start of each record in its time axis, s: one per
            record, or one for all.
        blocked_force: for a model name: ``paper`` or ``momentum``. A ``Model`` brings its own.
        gas: for a model name: ``adiabatic`` or ``none``. A ``Model`` brings its own.
        ball: geometry and mass (R, h, M); its E, ν are replaced by ``params``.
        solver: an ``rbjax.Solver`` (forced to ``adjoint="forward"``): the prediction then
            runs on the diffrax ODE.

    Returns:
        A tuple ``(force_N, jacobian, names)``: the filtered floor force
        (n_records, n_samples), N; d force/d parameter (n_records, n_samples, n_parameters)
        by forward-mode differentiation through the solver; and the parameter names (the
        physical ones, then ``shift[k]``).

    Raises:
        ValueError: ``params`` lacks a parameter of the model, ``model`` is not a model
            name, a value is outside its parameter's range, or ``solver`` is not an
            ``rbjax.Solver``.
        DataError: the records cannot be prepared (see :func:`prepare_data`).
        RuntimeError: JAX runs in float32 (``jax_enable_x64`` switched off).
    """
    require_x64()
    _, candidate = candidate_model(model, blocked_force, gas)
    names = fitted_parameter_names(candidate)
    missing = [n for n in names if n not in params]
    if missing:
        raise ValueError(f"params: missing {missing} for model {model!r}")
    data = prepare_data(data)
    _, ball, candidate = replace({n: float(params[n]) for n in names}, 1.0, ball, candidate)
    problem = Problem(
        data,
        ball,
        candidate,
        fit_solver(solver),
        height_error=False,
        decimate=1,
        scale="noise",
        path=fit_path("auto", candidate, solver)[0],
    )
    lay = problem.layout
    shifts = np.broadcast_to(np.asarray(onset_shift_s, dtype=float), (data.n_records,))
    theta = lay.theta(ball, candidate, shifts)
    weights = problem.weights(np.ones(data.n_records, dtype=bool))
    weights["record"] = np.ones(data.n_records)
    out = problem.run(
        theta, np.zeros(len(lay.names), dtype=bool), weights, lay.constant_values(ball, candidate)
    )
    n = data.n_records * data.n_samples
    jac = out["jac_theta"][:n].reshape(data.n_records, data.n_samples, -1)
    return out["force"], jac, tuple(lay.names)

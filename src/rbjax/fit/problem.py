"""One fit problem: the records, the parameter layout and the compiled program, and the steps
every fit and prediction shares (onset alignment, the per-height table, embedding a model in a
shared structure that holds its terms).
"""

from __future__ import annotations

import dataclasses
import hashlib
import math

import jax
import numpy as np

from .._validate import check_choice
from ..solve.record_samples import (
    first_contact_jacobian,
    record_samples_unsupported,
    substeps_for_rate,
)
from ..solve.solver import Solver
from ..terms.ball import Ball
from ..terms.model import Model
from ..terms.parameters import parameter_names, parameter_table, replace
from . import uncertainty as unc
from .batching import FitBatcher
from .layout import FASTEST_AT_LOWER, FIT_RANGES, FitLayout, model_from_name, parse_model_name
from .program import Structure, run_program
from .records import FitData, prepare_data
from .result import plain_value

#: Optimiser steps per compiled call (a static size of the program).
STEPS_PER_ROUND = 40


#: The paths of the fit's prediction: ``auto`` (``samples`` where the model allows it, else
#: ``ode`` with the reason shown), ``samples`` (the force at the record's samples by fixed steps,
#: :mod:`rbjax.fit.record_forces`), ``ode`` (the diffrax ODE with its events, the reference).
FIT_PATHS = ("auto", "samples", "ode")


def fit_solver(solver):
    if solver is None:
        return Solver(adjoint="forward")
    if not isinstance(solver, Solver):
        raise ValueError(f"solver={solver!r} must be an rbjax.Solver")
    return solver if solver.adjoint == "forward" else dataclasses.replace(solver, adjoint="forward")


def fit_path(path: str, model: Model, solver) -> tuple[str, str | None]:
    """(path, why the ODE) of a fit of ``model``: the sampled path unless the model needs the
    ODE's events (a moving floor), a ``Solver`` is given, or ``path="ode"``."""
    check_choice("path", path, FIT_PATHS)
    reason = record_samples_unsupported(model)
    if path == "samples" and reason is not None:
        raise ValueError(f"path='samples' cannot fit this model: {reason}")
    if path == "ode":
        return "ode", None
    if path == "auto" and solver is not None:
        return "ode", "a Solver was given"
    return ("samples", None) if reason is None else ("ode", reason)


def fit_substeps(ball: Ball, model: Model, rate_Hz: float) -> int:
    """The most Runge–Kutta steps per sample the sampled path takes for any value a fit of
    ``model`` can reach (each evaluation takes the count its own values need, up to this:
    :func:`~rbjax.solve.record_samples.substeps_at`): by the fastest rate of the vector field at
    first contact (its Jacobian's spectral radius), at the model's values and with each
    ``FIT_RANGES`` parameter at the bound where it is fastest (the upper, or the lower for those
    in ``FASTEST_AT_LOWER``)."""
    names = set(parameter_names(1.0, ball, model))
    corner = {
        n: (lo if n in FASTEST_AT_LOWER else hi) for n, (lo, hi) in FIT_RANGES.items() if n in names
    }
    # one compiled Jacobian for both points and for every fit of the same structure in the process
    points = [(ball, model), replace(corner, 1.0, ball, model)[1:]]
    fastest = max(
        float(np.max(np.abs(np.linalg.eigvals(np.asarray(_first_contact_jacobian(b, m))))))
        for b, m in points
    )
    return substeps_for_rate(fastest, rate_Hz)


_first_contact_jacobian = jax.jit(first_contact_jacobian)


class Problem:
    """The data, the layout and the compiled program of one fit (runtime masks aside)."""

    def __init__(
        self,
        data: FitData,
        ball: Ball,
        structure_model: Model,
        solver: Solver,
        *,
        height_error: bool,
        decimate: int,
        scale: str,
        path: str = "samples",
        feature_rows: bool = False,
    ):
        self.data = data
        #: where the program calls go (``None``: run at once; see :meth:`run_batch`): the fit's
        #: ``FitOptions.batcher``, set by whoever builds the problem
        self.batcher: FitBatcher | None = None
        self.ball = ball
        self.structure_model = structure_model
        self.layout = FitLayout(ball, structure_model, data.n_records, height_error)
        lay = self.layout
        filtered = data.lowpass_Hz is not None

        treedef = jax.tree_util.tree_structure((0.0, ball, structure_model))
        self.structure = Structure(
            treedef=treedef,
            physical_positions=lay.physical_positions,
            constant_positions=lay.constant_positions,
            specs=lay.specs,
            n_records=data.n_records,
            n_samples=data.n_samples,
            rate_Hz=float(data.rate_Hz),
            filtered=filtered,
            height_error=height_error,
            decimate=int(decimate),
            poisson_index=lay.index("poisson"),
            solver=solver,
            path=path,
            feature_rows=feature_rows,
            max_substeps=fit_substeps(ball, structure_model, float(data.rate_Hz))
            if path == "samples"
            else 0,
        )
        self.measured = data.measured_features
        feats = np.stack(
            [
                self.measured["onset_s"],
                self.measured["onset_s"] + self.measured["contact_time_s"],
                self.measured["peak_force_N"],
            ],
            axis=1,
        )
        self.arrays = {
            "heights": np.asarray(data.height_m, dtype=float),
            "sos": data.lowpass_sos,
            "measured": np.asarray(data.force_N, dtype=float),
            "features": np.concatenate([feats, self.measured["lfe_octave_dB"]], axis=1),
        }
        #: what the program's shared data are, for gathering fits of the same records as lanes
        self.data_digest = hashlib.sha256(
            b"".join(np.ascontiguousarray(v).tobytes() for v in self.arrays.values())
        ).hexdigest()
        self.record_weights = 1.0 / (
            np.maximum(data.noise_rms_N, 1e-12)
            if scale == "noise"
            else self.measured["peak_force_N"]
        )
        self.decimate = int(decimate)
        # noise correlation from the pre-contact samples (up to 1 ms before each onset)
        quiet = [
            data.force_N[k, : max(int((data.onset_s[k] - 1e-3) * data.rate_Hz), 0)]
            for k in range(data.n_records)
        ]
        n_quiet = min(len(q) for q in quiet)
        self.tau_noise = (
            unc.integrated_autocorrelation(
                np.stack([q[:n_quiet] for q in quiet])[:, :: self.decimate]
            )
            if n_quiet >= 16
            else 1.0
        )

    @property
    def n_hist_per_record(self) -> int:
        return len(range(0, self.data.n_samples, self.decimate))

    def weights(self, fit_mask, extra=None, prior=(0.0, 1.0, 0.0)):
        extra = extra or {}
        if any(float(v) > 0 for v in extra.values()) and not self.structure.feature_rows:
            raise ValueError(
                "extra weights need a Problem built with feature_rows=True (their Jacobian rows)"
            )
        return {
            "fit_mask": np.asarray(fit_mask, dtype=bool),
            "record": self.record_weights,
            "contact_time": float(extra.get("contact_time", 0.0)),
            "peak_force": float(extra.get("peak_force", 0.0)),
            "lfe": float(extra.get("lfe", 0.0)),
            "prior": np.asarray(prior, dtype=float),
        }

    def run_batch(
        self, thetas, free, weights, constants, *, optimizer="lm", phi_c=None, w=None, atol=None
    ):
        """The compiled program on B lanes (``thetas`` (B, n); ``weights`` a list of B weight
        dicts or one for all; ``phi_c``, ``w``, ``atol`` per lane, or none of them: an
        evaluation at θ, one Jacobian and no optimiser step): one output dict per lane.

        With a ``batcher`` (:class:`~rbjax.fit.batching.FitBatcher`) the lanes join those of
        the other fits that share it (one batch on the accelerator). Otherwise, on a CPU the
        lanes go
        through the program one at a time: it is compute-bound, so B lanes in lockstep cost B
        lanes' work, and each would run as many steps as the slowest (measured in
        ``benchmarks/fitting.py --only fit_time``); on an accelerator they go in one call."""
        lay = self.layout
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        b, n = thetas.shape
        evaluate_only = atol is None
        lanes = {
            "phi_c": np.stack([lay.to_phi(th) for th in thetas]) if phi_c is None else phi_c,
            "w": np.broadcast_to(np.eye(n), (b, n, n)) if w is None else w,
            "free": np.broadcast_to(np.asarray(free, dtype=bool), (b, n)),
            "held": thetas,
            "constants": np.broadcast_to(np.asarray(constants, dtype=float), (b, len(constants))),
            "weights": _stacked(weights if isinstance(weights, list) else [weights] * b),
            "atol": np.full(b, math.inf) if atol is None else np.asarray(atol, dtype=float),
        }
        if self.batcher is not None:
            key = (self.structure, optimizer, STEPS_PER_ROUND, evaluate_only, self.data_digest)
            out = self.batcher.call(key, lanes, self.arrays)
        else:
            per_call = 1 if jax.default_backend() == "cpu" else b
            parts = [
                run_program(
                    self.structure,
                    optimizer,
                    STEPS_PER_ROUND,
                    jax.tree_util.tree_map(lambda x, lo=lo: x[lo : lo + per_call], lanes),
                    self.arrays,
                    evaluate_only,
                )
                for lo in range(0, b, per_call)
            ]
            out = jax.tree_util.tree_map(lambda *xs: np.concatenate(xs), *parts)
        fields = out._asdict()
        return [{k: v[i] for k, v in fields.items()} for i in range(b)]

    def run(
        self, theta, free, weights, constants, *, optimizer="lm", phi_c=None, w=None, atol=None
    ):
        """The compiled program on one lane (see :meth:`run_batch`)."""
        return self.run_batch(
            np.asarray(theta)[None],
            free,
            [weights],
            constants,
            optimizer=optimizer,
            phi_c=None if phi_c is None else np.asarray(phi_c)[None],
            w=None if w is None else np.asarray(w)[None],
            atol=None if atol is None else [atol],
        )[0]

    def history_rows(self, r, fit_mask):
        """(rows of the fitted records' history residuals) as (n_fit, n_per_record)."""
        hist = r[: self.data.n_records * self.n_hist_per_record].reshape(self.data.n_records, -1)
        return hist[np.asarray(fit_mask, dtype=bool)]

    def history_jacobian(self, jac, fit_mask):
        n = self.data.n_records * self.n_hist_per_record
        j = jac[:n].reshape(self.data.n_records, self.n_hist_per_record, -1)
        return j[np.asarray(fit_mask, dtype=bool)].reshape(-1, jac.shape[1])

    def history_rms_N(self, force, mask):
        if not np.any(mask):
            return float("nan")
        return float(np.sqrt(np.mean((force[mask] - self.data.force_N[mask]) ** 2)))


def _stacked(weights: list[dict]) -> dict:
    """Per-lane weight dicts as one dict of arrays with a leading lane axis."""
    return {k: np.stack([np.asarray(x[k]) for x in weights]) for k in weights[0]}


def realign(problem: Problem, theta, feats, which, *, rescale_E: bool, fit_mask):
    """Move the onset shifts of the records ``which`` so that the predicted onset (5 % of the
    peak, rising edge) meets the measured one; optionally rescale E so that the predicted
    contact times match on the fitted records (t_c ∝ 1/√k)."""
    lay = problem.layout
    theta = theta.copy()
    shift = theta[lay.shift_slice]
    shift[which] += (problem.measured["onset_s"] - feats[:, 0])[which]
    theta[lay.shift_slice] = shift
    if rescale_E:
        tc_pred = (feats[:, 1] - feats[:, 0])[fit_mask]
        ratio = float(np.median(tc_pred / problem.measured["contact_time_s"][fit_mask]))
        if math.isfinite(ratio) and ratio > 0:
            theta[lay.index("youngs_Pa")] *= ratio**2
    return theta


def per_height_rows(problem: Problem, force, feats, fit_mask) -> list[dict]:
    d = problem.data
    meas = problem.measured
    pred = {
        "contact_time_s": feats[:, 1] - feats[:, 0],
        "peak_force_N": feats[:, 2],
        "lfe_octave_dB": feats[:, 3:],
    }
    rows = []
    for h in d.heights_m:
        k = np.isclose(d.height_m, h)
        m = {q: np.mean(meas[q][k], axis=0) for q in pred}
        f = {q: np.mean(pred[q][k], axis=0) for q in pred}
        rows.append(
            {
                "height_m": float(h),
                "n_drops": int(d.n_drops[k].sum()),
                "in_fit": bool(fit_mask[k].all()),
                "residual_rms_N": float(np.sqrt(np.mean((force[k] - d.force_N[k]) ** 2))),
                "measured": {q: plain_value(v) for q, v in m.items()},
                "fitted": {q: plain_value(v) for q, v in f.items()},
                "error": {
                    "contact_time_pct": float(
                        100 * (f["contact_time_s"] / m["contact_time_s"] - 1)
                    ),
                    "peak_force_pct": float(100 * (f["peak_force_N"] / m["peak_force_N"] - 1)),
                    "lfe_octave_dB": plain_value(f["lfe_octave_dB"] - m["lfe_octave_dB"]),
                },
            }
        )
    return rows


def candidate_model(model, blocked_force, gas) -> tuple[str, Model]:
    if isinstance(model, Model):
        return model.name, model
    parse_model_name(model)
    return model, model_from_name(model, gas=gas, blocked_force=blocked_force)


def embed(model: Model, structure: Model | None, ball: Ball) -> Model:
    """``model``'s values inside ``structure`` (a structure with its terms), or ``model`` itself."""
    if structure is None:
        return model
    if structure.gas != model.gas:
        raise ValueError(
            f"structure gas={structure.gas!r} differs from the model's gas={model.gas!r}"
        )
    have = set(parameter_names(1.0, ball, structure))
    mine = [n for n in parameter_names(1.0, ball, model) if n != "height_m"]
    missing = [n for n in mine if n not in have]
    if missing or not {type(d) for d in model.damping} <= {type(d) for d in structure.damping}:
        raise ValueError(
            f"structure lacks the terms of model {model.name!r} (parameters {missing})"
        )

    values = {
        r.name: r.value
        for r in parameter_table(1.0, ball, model)
        if r.name in have and r.name != "height_m"
    }
    return replace(values, 1.0, ball, structure)[2]


def aligned(data, ball: Ball, model: Model, solver, structure=None, batcher=None):
    """The problem and the onset-aligned evaluation of a given model (nothing fitted; the
    program's calls go to ``batcher`` where one is given)."""
    data = prepare_data(data)
    model = embed(model, structure, ball)
    problem = Problem(
        data,
        ball,
        model,
        fit_solver(solver),
        height_error=False,
        decimate=1,
        scale="noise",
        path=fit_path("auto", model, solver)[0],
    )
    problem.batcher = batcher
    lay = problem.layout
    delay = 2.613 / (2 * math.pi * data.lowpass_Hz) if data.lowpass_Hz else 0.0
    theta = lay.theta(ball, model, data.onset_s - delay)
    constants = lay.constant_values(ball, model)
    mask = np.zeros(data.n_records, dtype=bool)
    free = np.zeros(len(lay.names), dtype=bool)
    out = problem.run(theta, free, problem.weights(mask), constants)
    theta = realign(
        problem,
        theta,
        out["features"],
        np.ones(data.n_records, bool),
        rescale_E=False,
        fit_mask=mask,
    )
    out = problem.run(theta, free, problem.weights(np.ones(data.n_records, bool)), constants)
    return problem, theta, out

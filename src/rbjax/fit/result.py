"""The outcome of a fit: frozen, JSON-ready, with a text summary and figures."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..spectrum.bands import OCTAVE_BANDS
from ..terms.ball import Ball
from ..terms.model import Model
from ..terms.serialize import ball_to_dict, model_to_dict
from ..text import fmt, format_table


@dataclasses.dataclass(frozen=True)
class ParameterEstimate:
    """A fitted (or held) parameter: value, standard deviation, 95 % interval, unit.

    Attributes:
        value: the fitted (or held) value, in ``unit``.
        std: its standard deviation (linearised; 0 for a held one), in ``unit``.
        ci95: the 95 % interval (lower, upper), in ``unit``: ±1.96 standard deviations in
            the fit's unconstrained coordinate, mapped back (so it respects the bounds).
        unit: the unit, e.g. ``Pa`` (``1`` for a dimensionless parameter).
        fixed: whether the parameter was held, not fitted.
    """

    value: float
    std: float
    ci95: tuple[float, float]
    unit: str
    fixed: bool = False

    def to_dict(self) -> dict:
        return {
            "value": self.value,
            "std": self.std,
            "ci95": list(self.ci95),
            "unit": self.unit,
            "fixed": self.fixed,
        }


@dataclasses.dataclass(frozen=True, eq=False)
class FitResult:
    """The outcome of :func:`fit` (frozen). ``to_dict()`` is JSON-ready; ``plot(dir)`` draws it.

    Attributes:
        model_name: ``paper``, ``kelvin-voigt``, ``hunt-crossley``, ``zener`` (+``+stiffening``),
            or the name of the ``Model`` fitted.
        blocked_force, gas: the fitted model's blocked-force and gas options.
        ball, model: the fitted ``rbjax.Ball`` and ``rbjax.Model`` (``rbjax.simulate`` them).
        parameters: name → :class:`ParameterEstimate` (held ones with ``fixed=True``, std 0),
            plus ``effective_modulus_Pa`` = E/√(1−ν²), the combination the data determine.
        correlations: (names, matrix) of the free physical parameters.
        identifiability: plain-language statement of what the data determine.
        per_height: one dict per drop height: measured and fitted contact time, peak force and
            octave-band L_FE (same estimator on both, through the measuring chain), residual rms.
        residual_rms_N: rms of F_pred − F_measured over the fitted records.
        converged, message, iterations, optimizer: whether the optimiser converged, its message,
            its function evaluations and its name (``lm`` or ``gauss-newton``).
        n_eff_factor: τ, the samples per independent residual (N_eff = N/τ).
        n_residuals, n_free: N, the history residuals, and p, the free parameters (onset
            shifts included), of the information criteria.
        aic, bic: information criteria of the history residuals (see :func:`fit`).
        time_s, measured_N, predicted_N, heights_m, in_fit: the records, for plots and checks.
        onset_shift_s: the fitted contact start of each record in its time axis, s.
        theta: the full internal parameter vector (natural units; warm starts).
        n_starts, n_converged_starts: the starts tried (alternatives for parameters whose fit
            has several minima, in one compiled program) and how many converged; the result is
            the converged start of least cost.
    """

    model_name: str
    blocked_force: str
    gas: str
    ball: Ball
    model: Model
    parameters: dict
    correlations: tuple
    identifiability: str
    per_height: tuple
    residual_rms_N: float
    converged: bool
    message: str
    iterations: int
    optimizer: str
    n_eff_factor: float
    n_residuals: int
    n_free: int
    aic: float
    bic: float
    time_s: np.ndarray = dataclasses.field(repr=False)
    measured_N: np.ndarray = dataclasses.field(repr=False)
    predicted_N: np.ndarray = dataclasses.field(repr=False)
    heights_m: np.ndarray = dataclasses.field(repr=False)
    in_fit: np.ndarray = dataclasses.field(repr=False)
    onset_shift_s: np.ndarray = dataclasses.field(repr=False)
    theta: np.ndarray = dataclasses.field(repr=False)
    n_starts: int = 1
    n_converged_starts: int = 1

    @property
    def name(self) -> str:
        return self.model_name

    def to_dict(self) -> dict:
        """JSON-ready dict; ``ball``/``model`` in the ``rbjax.terms.serialize`` format
        (``rbjax simulate --params FIT.json`` reproduces the fitted model)."""
        return {
            **model_fields(self),
            "per_height": [plain_value(row) for row in self.per_height],
            "octave_bands_Hz": list(OCTAVE_BANDS),
            "residual_rms_N": self.residual_rms_N,
            "converged": bool(self.converged),
            "message": self.message,
            "iterations": int(self.iterations),
            "optimizer": self.optimizer,
            "n_residuals": int(self.n_residuals),
            "n_free": int(self.n_free),
            "n_eff_factor": self.n_eff_factor,
            "aic": self.aic,
            "bic": self.bic,
            "onset_shift_s": self.onset_shift_s.tolist(),
            "starts": {"tried": int(self.n_starts), "converged": int(self.n_converged_starts)},
        }

    def summary(self) -> str:
        """A short human-readable report (parameters, identifiability, per-height table)."""

        lines = [
            f"model {self.model_name} (blocked force {self.blocked_force}, gas {self.gas}): "
            f"{self.message}"
        ]
        lines += parameter_lines(self)
        bands = OCTAVE_BANDS
        header = [
            "h (m)",
            "fit",
            "rms (N)",
            "t_c meas (ms)",
            "t_c fit (ms)",
            "peak meas (N)",
            "peak fit (N)",
        ] + [f"ΔL {b}" for b in bands]
        rows = []
        for r in self.per_height:
            rows.append(
                [
                    f"{r['height_m']:.2f}",
                    "yes" if r["in_fit"] else "no",
                    fmt(r["residual_rms_N"], ".2f"),
                    fmt(1e3 * r["measured"]["contact_time_s"], ".2f"),
                    fmt(1e3 * r["fitted"]["contact_time_s"], ".2f"),
                    fmt(r["measured"]["peak_force_N"], ".0f"),
                    fmt(r["fitted"]["peak_force_N"], ".0f"),
                ]
                + [fmt(x, "+.2f") for x in r["error"]["lfe_octave_dB"]]
            )
        lines.append(format_table(header, rows))
        return "\n".join(lines)

    def plot(self, out_dir) -> list[Path]:
        """Write ``histories.png`` (measured vs fitted with residuals), ``lfe_bands.png`` and
        ``correlations.png`` into ``out_dir``; return their paths (``rbjax.plot.plot_fit``)."""
        # lazy: rbjax.plot imports matplotlib (0.1–0.2 s; pyplot ~1 s)
        from ..plot import plot_fit

        return plot_fit(self, out_dir)


@dataclasses.dataclass(frozen=True, eq=False)
class Prediction:
    """A model's predicted records next to the measured ones (nothing fitted); see
    :func:`predict`.

    Attributes:
        per_height: one dict per drop height, as :attr:`FitResult.per_height` (every record
            held out).
        time_s: the records' time axis, s.
        measured_N: the measured records (n_records, n_samples), N.
        predicted_N: the predicted records through the measuring chain, N, same shape.
        heights_m: the drop height of each record, m.
        converged: True (nothing is optimised; as :attr:`FitResult.converged`).
    """

    per_height: tuple
    time_s: np.ndarray
    measured_N: np.ndarray
    predicted_N: np.ndarray
    heights_m: np.ndarray
    converged: bool = True


def model_fields(fit) -> dict:
    """The JSON of what a fit (:class:`FitResult`, ``SummaryFitResult``) says of its model:
    name, blocked force, gas, ball and model (``rbjax.terms.serialize`` format), parameters,
    correlations, identifiability."""

    names, matrix = fit.correlations
    return {
        "model_name": fit.model_name,
        "blocked_force": fit.blocked_force,
        "gas": fit.gas,
        "ball": ball_to_dict(fit.ball),
        "model": model_to_dict(fit.model),
        "parameters": {k: v.to_dict() for k, v in fit.parameters.items()},
        "correlations": {"names": list(names), "matrix": np.asarray(matrix).tolist()},
        "identifiability": fit.identifiability,
    }


def parameter_lines(fit) -> list[str]:
    """The lines of a fit's text summary on its parameters (value ± std, 95 % interval; held
    ones marked) and what the data determine."""
    lines = []
    for k, p in fit.parameters.items():
        if p.fixed:
            lines.append(f"  {k:22s} {p.value:.6g} {p.unit} (held)")
        else:
            lines.append(
                f"  {k:22s} {p.value:.6g} ± {p.std:.2g} {p.unit}  (95 %: {p.ci95[0]:.6g} … "
                f"{p.ci95[1]:.6g})"
            )
    return lines + ["identifiability: " + fit.identifiability]


def plain_value(x):
    if isinstance(x, dict):
        return {k: plain_value(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return (
            [plain_value(v) for v in np.asarray(x).tolist()]
            if isinstance(x, np.ndarray)
            else [plain_value(v) for v in x]
        )
    if isinstance(x, (np.floating, float)):
        return float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x

"""The outcome of a summary fit (:func:`rbjax.fit.summary.fit_summary`): frozen, JSON-ready,
with a text summary and a figure."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ..terms.ball import Ball
from ..terms.model import Model
from ..text import fmt, format_table
from .result import model_fields, parameter_lines

#: How each figure is shown: (label, unit, scale from SI to the unit shown).
DISPLAY = {
    "contact_time_s": ("contact time", "ms", 1e3),
    "peak_force_N": ("peak force", "N", 1.0),
    "restitution": ("restitution", "1", 1.0),
}


def display(figure: str) -> tuple[str, str, float]:
    if figure in DISPLAY:
        return DISPLAY[figure]
    band = figure.removeprefix("lfe_").removesuffix("_dB")
    if band.startswith("third_"):
        return (f"L_FE {band.removeprefix('third_')} Hz (1/3 oct.)", "dB", 1.0)
    return (f"L_FE {band} Hz", "dB", 1.0)


@dataclasses.dataclass(frozen=True, eq=False)
class SummaryFitResult:
    """The outcome of :func:`~rbjax.fit.summary.fit_summary` (frozen).

    Attributes:
        model_name, blocked_force, gas: the model fitted.
        ball, model: the fitted ``rbjax.Ball`` and ``rbjax.Model`` (``rbjax.simulate`` them).
        parameters: name → :class:`~rbjax.fit.result.ParameterEstimate` (held ones ``fixed``),
            plus ``effective_modulus_Pa`` = E/√(1−ν²).
        correlations: (names, matrix) of the free parameters.
        identifiability: what the figures determine, what was held and why, defaults assumed.
        rows: one dict per figure of the table: height, figure, measured ± sd, fitted ±
            fitted_sd (delta method), normalised error (fitted − measured)/sd, in_fit.
        chi2, n_figures (in the fit), n_free; converged, message; source (the table's file).
    """

    model_name: str
    blocked_force: str
    gas: str
    ball: Ball
    model: Model
    parameters: dict
    correlations: tuple
    identifiability: str
    rows: tuple
    chi2: float
    n_figures: int
    n_free: int
    converged: bool
    message: str
    source: str
    heights_m: np.ndarray = dataclasses.field(repr=False)
    figures: tuple = ()
    time_s: float = 0.0

    def row(self, height_m: float, figure: str) -> dict:
        """The row of ``figure`` at ``height_m``."""
        for r in self.rows:
            if r["figure"] == figure and abs(r["height_m"] - height_m) < 5e-4:
                return r
        raise KeyError(f"no figure {figure!r} at {height_m:g} m in {self.source}")

    def to_dict(self) -> dict:
        return {
            "kind": "summary fit",
            "source": self.source,
            **model_fields(self),
            "figures": [dict(r) for r in self.rows],
            "chi2": self.chi2,
            "n_figures": self.n_figures,
            "n_free": self.n_free,
            "converged": bool(self.converged),
            "message": self.message,
            "time_s": self.time_s,
        }

    def summary(self) -> str:

        lines = [
            f"model {self.model_name} (blocked force {self.blocked_force}, gas {self.gas}) fitted "
            f"to {self.n_figures} figures of {self.source}: χ² = {self.chi2:.3g}, {self.n_free} "
            f"free; {self.message}"
        ]
        lines += parameter_lines(self)
        rows = []
        for r in self.rows:
            label, unit, k = display(r["figure"])
            rows.append(
                [
                    f"{r['height_m']:.2f}",
                    label,
                    unit,
                    fmt(k * r["measured"], ".4g"),
                    fmt(k * r["sd"], ".2g"),
                    fmt(k * r["fitted"], ".4g"),
                    fmt(k * r["fitted_sd"], ".2g"),
                    fmt(r["normalised_error"], "+.2f"),
                    "fit" if r["in_fit"] else "held out",
                ]
            )
        lines.append(
            format_table(
                [
                    "h (m)",
                    "figure",
                    "unit",
                    "measured",
                    "± sd",
                    "fitted",
                    "± sd",
                    "(fit−meas)/sd",
                    "",
                ],
                rows,
            )
        )
        return "\n".join(lines)

    def plot(self, out_dir) -> list[Path]:
        """Write ``summary_fit.png`` (each figure against drop height: measured ± 2 sd, fitted
        ± 2 sd) into ``out_dir``; return its path."""
        # lazy: matplotlib costs 0.1–0.2 s at import (pyplot ~1 s)
        import matplotlib

        matplotlib.use("Agg")
        # lazy: matplotlib.pyplot costs ~1 s at import
        import matplotlib.pyplot as plt

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        figures = [f for f in self.figures if any(r["figure"] == f for r in self.rows)]
        fig, axes = plt.subplots(1, len(figures), figsize=(3.2 * len(figures), 3.4), squeeze=False)
        for ax, f in zip(axes[0], figures):
            label, unit, k = display(f)
            rows = [r for r in self.rows if r["figure"] == f]
            h = np.array([r["height_m"] for r in rows])
            for key, sdkey, style, name in (
                ("measured", "sd", "ko", "measured"),
                ("fitted", "fitted_sd", "C0s", f"{self.model_name}"),
            ):
                ax.errorbar(
                    h,
                    [k * r[key] for r in rows],
                    yerr=[2 * k * r[sdkey] for r in rows],
                    fmt=style,
                    capsize=3,
                    label=name,
                    mfc="none" if key == "fitted" else None,
                )
            for r in rows:
                if not r["in_fit"]:
                    ax.annotate(
                        "held out",
                        (r["height_m"], k * r["measured"]),
                        textcoords="offset points",
                        xytext=(4, 6),
                        fontsize=7,
                    )
            ax.set_xlabel("drop height (m)")
            ax.set_ylabel(f"{label} ({unit})")
        axes[0][0].legend(fontsize=8)
        fig.tight_layout()
        path = out / "summary_fit.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return [path]

"""The result objects of the global sensitivity methods: indices per output and parameter, with
their intervals, a text table, a bar chart, the JSON summary and SALib's own result.

Every result has ``parameters``, ``outputs``, ``ranges``, ``n_evaluations``, ``n_valid`` (per
output: the base points, trajectories or rows the estimator used; those with a failed
evaluation are left out), ``samples`` (inputs and outputs of every evaluation), ``salib``
(output → the ``SALib`` ``ResultDict``, e.g. ``result.salib["peak_force_N"].to_df()``) and
``.driver(output)``, ``.table()``, ``.plot()``, ``.to_dict()``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import ClassVar

import numpy as np


@dataclasses.dataclass(frozen=True)
class IndexResult:
    """What the results share (see the module docstring). Subclasses name their per-output,
    per-parameter index attributes in ``_INDICES`` (label, attribute, interval attribute or
    None), the one that ranks the parameters in ``_RANKING``, and their settings in
    ``_DESIGN``."""

    _METHOD: ClassVar[str]
    _RANKING: ClassVar[str]
    _INDICES: ClassVar[tuple[tuple[str, str, str | None], ...]]
    _DESIGN: ClassVar[tuple[str, ...]]
    _PLOTTED: ClassVar[tuple[tuple[str, str, str | None], ...] | None] = None  # default: _INDICES
    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    ranges: dict
    n_evaluations: int
    n_valid: dict

    def driver(self, output: str) -> str:
        """The parameter with the largest ranking index of ``output`` (Sobol, FAST: the total
        index, what drives the output's spread; Morris: μ*; PAWN: the median KS statistic;
        DGSM: the total-index bound, exact where computed)."""
        return self.parameters[int(np.nanargmax(self._rank(output)))]

    def _rank(self, output: str) -> np.ndarray:
        """The index that ranks the parameters of ``output``."""
        return np.asarray(getattr(self, self._RANKING)[output], dtype=float)

    def _driver_or(self, output: str, default):
        """``driver(output)``, or ``default`` when no index of the output is finite."""
        return self.driver(output) if np.any(np.isfinite(self._rank(output))) else default

    def _extra(self, output: str) -> dict:
        """Per-output scalars of the JSON summary besides the indices (subclasses add some)."""
        return {"n_valid": self.n_valid[output]}

    def _extra_indices(self, output: str) -> dict:
        """Per-output JSON entries that are not one value per parameter (Sobol: second order)."""
        return {}

    def to_dict(self) -> dict:
        """The JSON summary: the method and its settings, the ranges, then per output its
        driver, scalars and each index (with its interval) as parameter → value."""

        def per_parameter(values) -> dict:
            return dict(zip(self.parameters, np.asarray(values).tolist()))

        outputs = {}
        for o in self.outputs:
            entry = {"driver": self._driver_or(o, None), **self._extra(o)}
            for _, attr, ci in self._INDICES:
                entry[attr] = per_parameter(getattr(self, attr)[o])
                if ci:
                    entry[ci] = per_parameter(getattr(self, ci)[o])
            outputs[o] = entry | self._extra_indices(o)
        return {
            "method": self._METHOD,
            "parameters": list(self.parameters),
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "n_evaluations": self.n_evaluations,
            **{k: getattr(self, k) for k in self._DESIGN},
            "outputs": outputs,
        }

    def _title(self) -> str:
        return f"{self._METHOD}, {self.n_evaluations} evaluations"

    def table(self) -> str:
        """A text table: per output its driver, then a row per parameter with each index (and
        its interval)."""
        lines = [self._title()]
        for o in self.outputs:
            lines.append(f"{o}  (driver: {self._driver_or(o, '—')}, valid {self.n_valid[o]})")
            for j, p in enumerate(self.parameters):
                cells = []
                for label, attr, ci in self._INDICES:
                    cell = f"{label} {getattr(self, attr)[o][j]:9.4g}"
                    if ci:
                        lo, hi = getattr(self, ci)[o][j]
                        cell += f" [{lo:9.4g}, {hi:9.4g}]"
                    cells.append(cell)
                lines.append(f"  {p:<20} " + "   ".join(cells))
        return "\n".join(lines)

    def plot(self, outputs: Sequence[str] | None = None, *, figsize=None):
        """Bars of each index per parameter, with its interval as whiskers; one panel per output
        (default: all). Returns the figure."""
        # lazy: matplotlib.pyplot costs ~1 s at import
        import matplotlib.pyplot as plt

        # lazy: rbjax.plot imports matplotlib (0.1–0.2 s; pyplot ~1 s)
        from ... import plot as _plot  # noqa: F401  (selects a headless backend when needed)

        outputs = tuple(self.outputs if outputs is None else outputs)
        unknown = [o for o in outputs if o not in self.outputs]
        if unknown or not outputs:
            raise ValueError(
                f"outputs={list(outputs)!r}: unknown {unknown}; valid: {', '.join(self.outputs)}"
            )
        ncols = min(4, len(outputs))
        nrows = -(-len(outputs) // ncols)
        fig, axes = plt.subplots(
            nrows,
            ncols,
            figsize=figsize or (3.4 * ncols + 0.6, 3.4 * nrows),
            squeeze=False,
            layout="constrained",
        )
        x = np.arange(len(self.parameters))
        plotted = self._PLOTTED or self._INDICES
        width = 0.8 / len(plotted)
        for ax, o in zip(axes.flat, outputs):
            for k, (label, attr, ci) in enumerate(plotted):
                value = np.asarray(getattr(self, attr)[o], dtype=float)
                err = np.abs(np.asarray(getattr(self, ci)[o]).T - value) if ci else None
                ax.bar(
                    x + (k - (len(plotted) - 1) / 2) * width,
                    value,
                    width,
                    yerr=err,
                    capsize=2,
                    label=label,
                )
            ax.set_xticks(x, self.parameters, rotation=60, fontsize=8)
            ax.set_title(o, fontsize=9)
            ax.grid(alpha=0.3, axis="y")
        for ax in list(axes.flat)[len(outputs) :]:
            ax.set_visible(False)
        axes[0][0].legend(fontsize=8)
        fig.suptitle(self._title(), fontsize=10)
        return fig


@dataclasses.dataclass(frozen=True)
class SobolResult(IndexResult):
    """Sobol indices of each output (``sobol_indices``; SALib ``sobol.analyze``).

    Attributes:
        n_base: base sample size N; ``n_evaluations`` = N (d + 2), or N (2d + 2) with the
            second-order indices.
        design: ``"sobol"`` (Saltelli's scheme on a scrambled Sobol' sequence, SALib
            ``sample.sobol``) or ``"random"`` (the same scheme on pseudo-random points).
        first_order, total_order: output → S_i (Saltelli et al. 2010), S_Ti (Jansen 1999), (d,).
        first_order_ci, total_order_ci: output → intervals (d, 2): the index ± SALib's bootstrap
            half-width (z · bootstrap standard deviation).
        second_order, second_order_ci: output → S_ij (Saltelli 2002) above the diagonal, NaN
            elsewhere, (d, d), and the half-widths of their intervals; None without them.
        confidence: level of the intervals.
        mean, variance: output → mean and variance over the A and B samples.
    """

    n_base: int
    design: str
    confidence: float
    first_order: dict
    total_order: dict
    first_order_ci: dict
    total_order_ci: dict
    second_order: dict | None
    second_order_ci: dict | None
    mean: dict
    variance: dict
    samples: dict = dataclasses.field(repr=False, default_factory=dict)
    salib: dict = dataclasses.field(repr=False, default_factory=dict)

    _METHOD = "sobol"
    _RANKING = "total_order"
    _INDICES = (("S", "first_order", "first_order_ci"), ("S_T", "total_order", "total_order_ci"))
    _DESIGN = ("n_base", "design", "confidence")

    def _title(self) -> str:
        return (
            f"Sobol indices, {self.n_evaluations} evaluations (N = {self.n_base}, {self.design} "
            f"design), {self.confidence:.0%} bootstrap CI"
        )

    def _extra(self, output: str) -> dict:
        return super()._extra(output) | {
            "mean": self.mean[output],
            "variance": self.variance[output],
        }

    def _extra_indices(self, output: str) -> dict:
        if self.second_order is None or self.second_order_ci is None:
            return {}
        s2, ci = np.asarray(self.second_order[output]), np.asarray(self.second_order_ci[output])
        pairs = [
            (i, j) for i in range(len(self.parameters)) for j in range(i + 1, len(self.parameters))
        ]
        return {
            "second_order": {
                f"{self.parameters[i]},{self.parameters[j]}": float(s2[i, j]) for i, j in pairs
            },
            "second_order_ci": {
                f"{self.parameters[i]},{self.parameters[j]}": [
                    float(s2[i, j] - ci[i, j]),
                    float(s2[i, j] + ci[i, j]),
                ]
                for i, j in pairs
            },
        }


@dataclasses.dataclass(frozen=True)
class MorrisResult(IndexResult):
    """Morris elementary-effect screening (``morris_screening``; SALib ``morris.analyze``).

    Attributes:
        mu, mu_star, sigma: output → mean, mean absolute value and standard deviation of the
            elementary effects per parameter, (d,), in output units per full range of the
            parameter (an effect of 1: the output changes by 1 across the range).
        mu_star_ci: output → bootstrap intervals of μ*, (d, 2).
        n_trajectories, n_levels, optimal_trajectories (None: the plain design), confidence.
    """

    n_trajectories: int
    n_levels: int
    optimal_trajectories: int | None
    confidence: float
    mu: dict
    mu_star: dict
    sigma: dict
    mu_star_ci: dict
    samples: dict = dataclasses.field(repr=False, default_factory=dict)
    salib: dict = dataclasses.field(repr=False, default_factory=dict)

    _METHOD = "morris"
    _RANKING = "mu_star"
    _INDICES = (("mu*", "mu_star", "mu_star_ci"), ("mu", "mu", None), ("sigma", "sigma", None))
    _DESIGN = ("n_trajectories", "n_levels", "optimal_trajectories", "confidence")

    def _title(self) -> str:
        return (
            f"Morris screening, {self.n_evaluations} evaluations ({self.n_trajectories} "
            f"trajectories, {self.n_levels} levels)"
        )


@dataclasses.dataclass(frozen=True)
class FastResult(IndexResult):
    """Extended FAST indices (``fast_indices``; SALib ``fast.analyze``, Saltelli et al. 1999).

    Attributes:
        n_per_parameter: samples N per parameter's search curve; ``n_evaluations`` = N d.
        interference: the interference factor M.
        first_order, total_order, first_order_ci, total_order_ci: as ``SobolResult``.
    """

    n_per_parameter: int
    interference: int
    confidence: float
    first_order: dict
    total_order: dict
    first_order_ci: dict
    total_order_ci: dict
    samples: dict = dataclasses.field(repr=False, default_factory=dict)
    salib: dict = dataclasses.field(repr=False, default_factory=dict)

    _METHOD = "fast"
    _RANKING = "total_order"
    _INDICES = SobolResult._INDICES
    _DESIGN = ("n_per_parameter", "interference", "confidence")

    def _title(self) -> str:
        return (
            f"eFAST indices, {self.n_evaluations} evaluations (N = {self.n_per_parameter} per "
            f"parameter, M = {self.interference})"
        )


@dataclasses.dataclass(frozen=True)
class PawnResult(IndexResult):
    """PAWN indices (``pawn_indices``; SALib ``pawn.analyze``, Pianosi & Wagener 2015, 2018):
    statistics over ``n_conditioning`` slices of each parameter's range of the
    Kolmogorov–Smirnov distance between the output's conditional and unconditional
    distributions (0: no influence).

    Attributes:
        minimum, mean, median, maximum, cv: output → (d,) each (``median`` ranks).
        n_samples, n_conditioning.
    """

    n_samples: int
    n_conditioning: int
    minimum: dict
    mean: dict
    median: dict
    maximum: dict
    cv: dict
    samples: dict = dataclasses.field(repr=False, default_factory=dict)
    salib: dict = dataclasses.field(repr=False, default_factory=dict)

    _METHOD = "pawn"
    _RANKING = "median"
    _INDICES = (("median", "median", None), ("max", "maximum", None), ("min", "minimum", None))
    _DESIGN = ("n_samples", "n_conditioning")

    def _extra_indices(self, output: str) -> dict:
        return {
            k: dict(zip(self.parameters, np.asarray(getattr(self, k)[output]).tolist()))
            for k in ("mean", "cv")
        }

    def _title(self) -> str:
        return (
            f"PAWN indices (KS statistics), {self.n_evaluations} evaluations, "
            f"{self.n_conditioning} slices"
        )

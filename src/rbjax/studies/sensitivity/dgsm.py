"""Derivative-based global sensitivity measures (DGSM) from exact gradients, beside SALib's
finite differences on the same design.

For independent inputs x_i uniform on [a_i, b_i] and an output f of variance V (Sobol' &
Kucherenko 2009):

    ν_i = E[(∂f/∂x_i)²],        S_Ti ≤ ν_i (b_i − a_i)² / (π² V).

The bound is the Poincaré inequality of the uniform distribution, whose constant (b − a)²/π² is
reached by f = cos(π (x − a)/(b − a)); for a response linear in x_i, ν_i = c², and S_Ti V =
c²(b − a)²/12, so the bound is 12/π² ≈ 1.22 times S_Ti: a ratio near 1.22 says the output is
close to linear (additive) in that parameter, a larger one that it bends inside the range.

:func:`dgsm_measures` samples SALib's DGSM design (``sample.finite_diff``: N base points of a
Sobol' sequence, each followed by d points moved by ``delta`` × the value in one parameter),
evaluates it, and analyses it with SALib (``analyze.dgsm``: ν_i from one-sided differences);
with a ``jacobian`` (exact derivatives, e.g. ``jax.jacfwd``) it computes ν_i and the bound at
the same base points from the exact gradient, with the wall time of each.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping

import numpy as np

from ..._validate import check_range
from ._common import (
    check_count,
    check_ranges,
    finite_groups,
    inputs_dict,
    interval,
    outputs_dict,
    salib_problem,
    salib_seed,
    shared_fields,
)
from .results import IndexResult


@dataclasses.dataclass(frozen=True)
class DGSMResult(IndexResult):
    """DGSM of each output (``dgsm_measures``).

    Attributes:
        n_base: base points N; ``n_evaluations`` = N (d + 1), the finite-difference design.
        delta: relative finite-difference step (the point moves by ``delta`` × its value).
        variance: output → variance V over the base points.
        nu, nu_ci: output → ν_i = E[(∂f/∂x_i)²] from the exact gradient at the base points, (d,),
            in (output unit / parameter unit)², and its interval ± z·(standard error), (d, 2);
            NaN without a ``jacobian``.
        total_bound: output → ν_i (b_i − a_i)²/(π² V), the upper bound of the total Sobol index.
        nu_fd, nu_fd_ci, total_bound_fd: the same from SALib's finite differences
            (SALib's ``vi`` and ``dgsm``).
        seconds_exact, seconds_fd: wall time of the ``jacobian`` call (N points) and of the
            ``func`` call on the design (N (d + 1) points), compilation included.
    """

    n_base: int
    delta: float
    confidence: float
    variance: dict
    nu: dict
    nu_ci: dict
    total_bound: dict
    nu_fd: dict
    nu_fd_ci: dict
    total_bound_fd: dict
    seconds_exact: float
    seconds_fd: float
    samples: dict = dataclasses.field(repr=False, default_factory=dict)
    salib: dict = dataclasses.field(repr=False, default_factory=dict)

    _METHOD = "dgsm"
    _RANKING = "total_bound"
    _INDICES = (
        ("nu", "nu", "nu_ci"),
        ("nu_fd", "nu_fd", "nu_fd_ci"),
        ("S_T <=", "total_bound", None),
        ("(fd)", "total_bound_fd", None),
    )
    _PLOTTED = (
        ("S_T bound (exact)", "total_bound", None),
        ("S_T bound (finite diff.)", "total_bound_fd", None),
    )
    _DESIGN = ("n_base", "delta", "confidence", "seconds_exact", "seconds_fd")

    def _title(self) -> str:
        return (
            f"DGSM, {self.n_base} base points: exact gradients ({self.seconds_exact:.2f} s) and "
            f"finite differences ({self.n_evaluations} evaluations, {self.seconds_fd:.2f} s)"
        )

    def _extra(self, output: str) -> dict:
        return super()._extra(output) | {"variance": self.variance[output]}

    def _rank(self, output: str) -> np.ndarray:
        exact = np.asarray(self.total_bound[output], dtype=float)
        return (
            exact
            if np.any(np.isfinite(exact))
            else np.asarray(self.total_bound_fd[output], dtype=float)
        )


def dgsm_measures(
    func: Callable,
    ranges: Mapping,
    n_base: int,
    *,
    jacobian: Callable | None = None,
    delta: float = 1e-4,
    seed: int = 0,
    n_bootstrap: int = 200,
    confidence: float = 0.95,
) -> DGSMResult:
    """DGSM ν_i and the total-index bounds of ``func``: exact (``jacobian``) and SALib's.

    ``func`` is called once on SALib's finite-difference design (N (d + 1) rows, ``delta`` the
    relative step; see the module docstring); ``jacobian`` (optional) once on the N base
    points: it takes the same dict of inputs and returns output → (N, d) derivatives (or one
    (N, d) array for an output ``"y"``). Base points with a non-finite output or derivative are
    left out. ν's intervals are ± z·(standard error of the mean of squares) at level
    ``confidence``.
    """
    ranges = check_ranges(ranges)
    n = check_count("n_base", n_base, 2)
    check_range("delta", delta, lower=0.0, upper=1.0)
    n_bootstrap = check_count("n_bootstrap", n_bootstrap, 2)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    # lazy: SALib costs 1.7–4 s at import
    from SALib.analyze import dgsm as analyze
    from SALib.sample import finite_diff as sample

    problem, d = salib_problem(ranges), len(ranges)
    x = sample.sample(problem, n, delta=float(delta), seed=seed)
    inputs = inputs_dict(x, ranges)
    start = time.perf_counter()
    outputs = outputs_dict(func(inputs), x.shape[0])
    seconds_fd = time.perf_counter() - start
    grads: dict = {}
    seconds_exact = math.nan
    if jacobian is not None:
        start = time.perf_counter()
        grads = jacobian(inputs_dict(x[:: d + 1], ranges))
        seconds_exact = time.perf_counter() - start
        grads = {
            k: np.asarray(v, dtype=float)
            for k, v in (grads.items() if isinstance(grads, Mapping) else {"y": grads}.items())
        }
        missing = [o for o in outputs if o not in grads or grads[o].shape != (n, d)]
        if missing:
            raise ValueError(f"jacobian returned no ({n}, {d}) derivatives for {missing}")

    from scipy.stats import norm  # lazy: scipy.stats costs 0.5–1.5 s at import (RESULTS.md)

    z = float(norm.ppf(0.5 + confidence / 2.0))
    widths2 = np.array([(hi - lo) ** 2 for lo, hi in ranges.values()])
    res: dict[str, dict] = {
        k: {}
        for k in (
            "var",
            "nu",
            "nu_ci",
            "bound",
            "nu_fd",
            "nu_fd_ci",
            "bound_fd",
            "n_valid",
            "salib",
        )
    }
    for name, y in outputs.items():
        keep = finite_groups(y, d + 1)
        if grads:
            keep &= np.all(np.isfinite(grads[name]), axis=1)
        res["n_valid"][name] = m = int(keep.sum())
        base = y[:: d + 1][keep]
        res["var"][name] = variance = float(np.var(base)) if m else math.nan
        nan_d, nan_d2 = np.full(d, np.nan), np.full((d, 2), np.nan)
        res["nu"][name], res["nu_ci"][name], res["bound"][name] = nan_d, nan_d2, nan_d
        res["nu_fd"][name], res["nu_fd_ci"][name], res["bound_fd"][name] = nan_d, nan_d2, nan_d
        if m < 2 or not variance > 0.0:
            continue
        rows = np.repeat(keep, d + 1)
        si = analyze.analyze(
            problem,
            x[rows],
            y[rows],
            num_resamples=n_bootstrap,
            conf_level=confidence,
            seed=salib_seed(seed),
        )
        res["salib"][name] = si
        res["nu_fd"][name] = np.asarray(si["vi"], dtype=float)
        res["nu_fd_ci"][name] = interval(
            si["vi"], z * np.asarray(si["vi_std"]) / math.sqrt(m)
        )  # SALib's std of (Δf/Δx)²
        res["bound_fd"][name] = np.asarray(si["dgsm"], dtype=float)
        if grads:
            squares = grads[name][keep] ** 2
            res["nu"][name] = nu = squares.mean(axis=0)
            res["nu_ci"][name] = interval(nu, z * squares.std(axis=0, ddof=1) / math.sqrt(m))
            res["bound"][name] = nu * widths2 / (math.pi**2 * variance)
    return DGSMResult(
        **shared_fields(ranges, outputs, x.shape[0], res),
        n_base=n,
        delta=float(delta),
        confidence=float(confidence),
        variance=res["var"],
        nu=res["nu"],
        nu_ci=res["nu_ci"],
        total_bound=res["bound"],
        nu_fd=res["nu_fd"],
        nu_fd_ci=res["nu_fd_ci"],
        total_bound_fd=res["bound_fd"],
        seconds_exact=seconds_exact,
        seconds_fd=seconds_fd,
        samples={**inputs, **outputs, "base": np.repeat(np.arange(n), d + 1)},
    )

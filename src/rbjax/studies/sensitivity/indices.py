"""Global sensitivity indices on SALib: sample (SALib) → evaluate (``func``, one call) → analyse
(SALib).

Over independent uniform ranges of the inputs:

* :func:`sobol_indices`: first-, total- and second-order Sobol indices (SALib ``sample.sobol``,
  Saltelli's scheme on a scrambled Sobol' sequence, and ``analyze.sobol``: Saltelli et al. 2010
  first order, Jansen 1999 total order, Saltelli 2002 second order, bootstrap intervals);
* :func:`morris_screening`: Morris (1991) elementary effects, optionally on Campolongo's
  optimised trajectories (SALib ``sample.morris``, ``analyze.morris``);
* :func:`fast_indices`: extended FAST first- and total-order indices (Saltelli et al. 1999;
  SALib ``sample.fast_sampler``, ``analyze.fast``);
* :func:`pawn_indices`: the moment-independent PAWN indices (Pianosi & Wagener 2015) on a Latin
  hypercube (SALib ``sample.latin``, ``analyze.pawn``).

``func`` takes a dict parameter → (N,) array and returns an (N,) array or a dict of them (one
per output); it is called once, with every row of the design. Base points (Sobol), trajectories
(Morris) or rows (PAWN) with a non-finite output are left out for that output (``n_valid``);
eFAST needs every row (an output with one failed row has NaN indices). The derivative-based
measures are :mod:`rbjax.studies.sensitivity.dgsm`; :mod:`rbjax.studies.sensitivity.study`
applies all of them to the impact model.
"""

from __future__ import annotations

import math
import warnings
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
from .results import FastResult, MorrisResult, PawnResult, SobolResult

#: Designs of ``sobol_indices``: Saltelli's scheme on a scrambled Sobol' sequence (SALib) or on
#: pseudo-random points (to compare convergence).
SOBOL_DESIGNS = ("sobol", "random")


def _random_saltelli(problem: dict, n: int, second_order: bool, seed: int) -> np.ndarray:
    """Saltelli's scheme on pseudo-random points, rows laid out as SALib's ``sample.sobol``:
    per base point A, A_B^(1..d), [B_A^(1..d)], B (a design SALib does not provide)."""
    d = problem["num_vars"]
    base = np.random.default_rng(seed).random((n, 2 * d))
    a, b = base[:, :d], base[:, d:]
    eye = np.eye(d, dtype=bool)
    ab = np.where(eye[None], b[:, None, :], a[:, None, :])  # (n, d, d): A with column i from B
    blocks = (
        [a[:, None], ab]
        + ([np.where(eye[None], a[:, None, :], b[:, None, :])] if second_order else [])
        + [b[:, None]]
    )
    unit = np.concatenate(blocks, axis=1).reshape(-1, d)
    low, high = np.array(problem["bounds"]).T
    return low + (high - low) * unit


def _store_first_and_total(res: dict, name: str, si) -> None:
    """First- and total-order indices of output ``name`` and their intervals (Sobol, eFAST),
    from SALib's result ``si``, into ``res``."""
    res["S1"][name], res["ST"][name] = np.asarray(si["S1"]), np.asarray(si["ST"])
    res["S1_ci"][name] = interval(si["S1"], si["S1_conf"])
    res["ST_ci"][name] = interval(si["ST"], si["ST_conf"])


def sobol_indices(
    func: Callable,
    ranges: Mapping,
    n_base: int,
    *,
    second_order: bool = True,
    design: str = "sobol",
    seed: int = 0,
    n_bootstrap: int = 200,
    confidence: float = 0.95,
) -> SobolResult:
    """First-, total- and (``second_order``) second-order Sobol indices of ``func`` (SALib).

    ``n_base`` N, a power of two for the Sobol' sequence (its balance holds for 2^m points):
    N (d + 2) evaluations, N (2d + 2) with the second order. ``design="random"`` lays the same
    scheme on pseudo-random points (any N), for comparison. Intervals: the index ± SALib's
    bootstrap half-width over the base points (``n_bootstrap`` resamples, level
    ``confidence``; the bootstrap treats the points as independent, so for the Sobol' design
    it overstates the error: replicate the study with other seeds to measure it).
    """
    ranges = check_ranges(ranges)
    if design not in SOBOL_DESIGNS:
        raise ValueError(
            f"design={design!r} is not known; valid: {', '.join(map(repr, SOBOL_DESIGNS))}"
        )
    why = (
        " for the Sobol' sequence design (its balance holds for 2^m points)"
        if design == "sobol"
        else ""
    )
    n = check_count("n_base", n_base, 2, power_of_two=design == "sobol", why=why)
    n_bootstrap = check_count("n_bootstrap", n_bootstrap, 2)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    # lazy: SALib costs 1.7–4 s at import
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample

    problem, d = salib_problem(ranges), len(ranges)
    if design == "sobol":
        x = sample.sample(problem, n, calc_second_order=second_order, scramble=True, seed=seed)
    else:
        x = _random_saltelli(problem, n, second_order, seed)
    step = 2 * d + 2 if second_order else d + 2
    inputs = inputs_dict(x, ranges)
    outputs = outputs_dict(func(inputs), n * step)
    block = np.concatenate(
        [[0], 2 + np.arange(d), 2 + d + np.arange(d) if second_order else [], [1]]
    ).astype(int)

    res: dict[str, dict] = {
        k: {}
        for k in ("S1", "ST", "S1_ci", "ST_ci", "S2", "S2_ci", "mean", "var", "n_valid", "salib")
    }
    nan_d, nan_dd = np.full(d, np.nan), np.full((d, d), np.nan)
    for name, y in outputs.items():
        keep = finite_groups(y, step)
        m = int(keep.sum())
        rows = y.reshape(n, step)[keep]
        res["n_valid"][name] = m
        both = np.concatenate([rows[:, 0], rows[:, -1]])
        res["mean"][name] = float(np.mean(both)) if m else math.nan
        res["var"][name] = float(np.var(both)) if m else math.nan
        if m < 2 or not np.ptp(both) > 0.0:  # too few points, or a constant output: no index
            res["S1"][name] = res["ST"][name] = nan_d
            res["S1_ci"][name] = res["ST_ci"][name] = np.full((d, 2), np.nan)
            res["S2"][name] = res["S2_ci"][name] = nan_dd
            continue
        si = analyze.analyze(
            problem,
            rows.reshape(-1),
            calc_second_order=second_order,
            num_resamples=n_bootstrap,
            conf_level=confidence,
            seed=salib_seed(seed),
        )
        res["salib"][name] = si
        _store_first_and_total(res, name, si)
        if second_order:
            res["S2"][name], res["S2_ci"][name] = np.asarray(si["S2"]), np.asarray(si["S2_conf"])
    return SobolResult(
        **shared_fields(ranges, outputs, n * step, res),
        n_base=n,
        design=design,
        confidence=float(confidence),
        first_order=res["S1"],
        total_order=res["ST"],
        first_order_ci=res["S1_ci"],
        total_order_ci=res["ST_ci"],
        second_order=res["S2"] if second_order else None,
        second_order_ci=res["S2_ci"] if second_order else None,
        mean=res["mean"],
        variance=res["var"],
        samples={
            **inputs,
            **outputs,
            "block": np.tile(block, n),
            "base": np.repeat(np.arange(n), step),
        },
    )


def morris_screening(
    func: Callable,
    ranges: Mapping,
    n_trajectories: int,
    *,
    n_levels: int = 4,
    optimal_trajectories: int | None = None,
    seed: int = 0,
    n_bootstrap: int = 200,
    confidence: float = 0.95,
) -> MorrisResult:
    """Morris (1991) elementary effects of ``func`` over uniform ranges (SALib).

    ``n_trajectories`` r one-at-a-time trajectories on the ``n_levels``-level grid (SALib
    ``sample.morris``); with ``optimal_trajectories`` = k < r, the k of them that are spread
    farthest apart (Campolongo et al. 2007) are kept. r (d + 1) (or k (d + 1)) evaluations.
    Effects are in output units per full range of the parameter.
    """
    ranges = check_ranges(ranges)
    r = check_count("n_trajectories", n_trajectories, 2)
    p = check_count("n_levels", n_levels, 2)
    if p % 2:
        raise ValueError(
            f"n_levels={n_levels!r} must be an even integer ≥ 2 (an odd grid biases the effects)"
        )
    if optimal_trajectories is not None:
        k = check_count("optimal_trajectories", optimal_trajectories, 2)
        if k >= r:
            raise ValueError(
                f"optimal_trajectories={k!r} must be fewer than n_trajectories={r!r} "
                "(the candidates it picks from)"
            )
    n_bootstrap = check_count("n_bootstrap", n_bootstrap, 2)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    # lazy: SALib costs 1.7–4 s at import
    from SALib.analyze import morris as analyze
    from SALib.sample import morris as sample

    problem, d = salib_problem(ranges), len(ranges)
    x = sample.sample(
        problem, r, num_levels=p, optimal_trajectories=optimal_trajectories, seed=seed
    )
    n_traj = x.shape[0] // (d + 1)
    inputs = inputs_dict(x, ranges)
    outputs = outputs_dict(func(inputs), x.shape[0])
    res: dict[str, dict] = {
        k: {} for k in ("mu", "mu_star", "sigma", "mu_star_ci", "n_valid", "salib")
    }
    for name, y in outputs.items():
        keep = finite_groups(y, d + 1)
        res["n_valid"][name] = m = int(keep.sum())
        if m < 2:
            res["mu"][name] = res["mu_star"][name] = res["sigma"][name] = np.full(d, np.nan)
            res["mu_star_ci"][name] = np.full((d, 2), np.nan)
            continue
        rows = np.repeat(keep, d + 1)
        si = analyze.analyze(
            problem,
            x[rows],
            y[rows],
            num_resamples=n_bootstrap,
            conf_level=confidence,
            num_levels=p,
            seed=salib_seed(seed),
        )
        res["salib"][name] = si
        for key in ("mu", "mu_star", "sigma"):
            res[key][name] = np.asarray(si[key], dtype=float)
        res["mu_star_ci"][name] = interval(si["mu_star"], si["mu_star_conf"])
    return MorrisResult(
        **shared_fields(ranges, outputs, x.shape[0], res),
        n_trajectories=n_traj,
        n_levels=p,
        optimal_trajectories=optimal_trajectories,
        confidence=float(confidence),
        mu=res["mu"],
        mu_star=res["mu_star"],
        sigma=res["sigma"],
        mu_star_ci=res["mu_star_ci"],
        samples={**inputs, **outputs, "trajectory": np.repeat(np.arange(n_traj), d + 1)},
    )


def fast_indices(
    func: Callable,
    ranges: Mapping,
    n_per_parameter: int,
    *,
    interference: int = 4,
    seed: int = 0,
    n_bootstrap: int = 200,
    confidence: float = 0.95,
) -> FastResult:
    """Extended FAST first- and total-order indices of ``func`` (SALib; Saltelli et al. 1999).

    ``n_per_parameter`` N samples along each parameter's search curve (N > 4 M², M the
    ``interference`` factor): N d evaluations. The intervals are SALib's bootstrap, which SALib
    itself calls indicative only for eFAST (SALib issue 649; its warning is silenced here).
    """
    ranges = check_ranges(ranges)
    m_int = check_count("interference", interference, 1)
    n = check_count(
        "n_per_parameter",
        n_per_parameter,
        4 * m_int**2 + 1,
        why=f" (N > 4 M² = {4 * m_int**2} for M = {m_int})",
    )
    n_bootstrap = check_count("n_bootstrap", n_bootstrap, 2)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    # lazy: SALib costs 1.7–4 s at import
    from SALib.analyze import fast as analyze
    from SALib.sample import fast_sampler as sample

    problem, d = salib_problem(ranges), len(ranges)
    x = sample.sample(problem, n, M=m_int, seed=seed)
    inputs = inputs_dict(x, ranges)
    outputs = outputs_dict(func(inputs), x.shape[0])
    res: dict[str, dict] = {k: {} for k in ("S1", "ST", "S1_ci", "ST_ci", "n_valid", "salib")}
    for name, y in outputs.items():
        res["n_valid"][name] = int(np.isfinite(y).sum())
        if not np.all(np.isfinite(y)):  # the Fourier analysis needs every point of each curve
            res["S1"][name] = res["ST"][name] = np.full(d, np.nan)
            res["S1_ci"][name] = res["ST_ci"][name] = np.full((d, 2), np.nan)
            continue
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", "FAST confidence intervals", UserWarning)
            si = analyze.analyze(
                problem,
                y,
                M=m_int,
                num_resamples=n_bootstrap,
                conf_level=confidence,
                seed=salib_seed(seed),
            )
        res["salib"][name] = si
        _store_first_and_total(res, name, si)
    return FastResult(
        **shared_fields(ranges, outputs, x.shape[0], res),
        n_per_parameter=n,
        interference=m_int,
        confidence=float(confidence),
        first_order=res["S1"],
        total_order=res["ST"],
        first_order_ci=res["S1_ci"],
        total_order_ci=res["ST_ci"],
        samples={**inputs, **outputs, "curve": np.repeat(np.arange(d), n)},
    )


def pawn_indices(
    func: Callable, ranges: Mapping, n_samples: int, *, n_conditioning: int = 10, seed: int = 0
) -> PawnResult:
    """PAWN indices of ``func`` (SALib; Pianosi & Wagener 2015) from ``n_samples`` Latin
    hypercube points, each parameter's range cut into ``n_conditioning`` slices."""
    ranges = check_ranges(ranges)
    s = check_count("n_conditioning", n_conditioning, 2)
    n = check_count("n_samples", n_samples, 2 * s, why=f" (at least 2 per slice, {s} slices)")
    # lazy: SALib costs 1.7–4 s at import
    from SALib.analyze import pawn as analyze
    from SALib.sample import latin as sample

    problem, d = salib_problem(ranges), len(ranges)
    x = sample.sample(problem, n, seed=seed)
    inputs = inputs_dict(x, ranges)
    outputs = outputs_dict(func(inputs), n)
    keys = ("minimum", "mean", "median", "maximum", "CV")
    res: dict[str, dict] = {k: {} for k in keys + ("n_valid", "salib")}
    for name, y in outputs.items():
        keep = np.isfinite(y)
        res["n_valid"][name] = m = int(keep.sum())
        if m < 2 * s:
            for k in keys:
                res[k][name] = np.full(d, np.nan)
            continue
        with warnings.catch_warnings():  # SALib's pandas summary warns on a future dtype change
            warnings.simplefilter("ignore", FutureWarning)
            si = analyze.analyze(problem, x[keep], y[keep], S=s, seed=salib_seed(seed))
        res["salib"][name] = si
        for k in keys:
            res[k][name] = np.asarray(si[k], dtype=float)
    return PawnResult(
        **shared_fields(ranges, outputs, n, res),
        n_samples=n,
        n_conditioning=s,
        minimum=res["minimum"],
        mean=res["mean"],
        median=res["median"],
        maximum=res["maximum"],
        cv=res["CV"],
        samples={**inputs, **outputs},
    )

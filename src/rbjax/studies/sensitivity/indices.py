"""Global sensitivity of the rubber-ball impact: Sobol indices and Morris screening.

Sobol first- and total-order indices (:func:`sobol_indices`, Saltelli 2010 first-order and
Jansen 1999 total-order estimators, bootstrap confidence intervals) and Morris elementary-effect
screening (:func:`morris_screening`) over uniform parameter ranges; :func:`global_sensitivity`
applies them to the impact model (contact time, peak force, restitution: paper §2.4, Eq. 7;
L_FE per octave band: Eq. 11), evaluated in batches sharded over the JAX devices
(:mod:`rbjax.studies.sweep`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import ClassVar

import numpy as np

from ..._validate import check_range
from ...solve.batch import SCALAR_OUTPUTS as SWEEP_SCALAR_OUTPUTS
from ...solve.batch import assemble, canonical_name, evaluate, lfe_output_names
from ...solve.simulate import make_model
from ...terms.ball import JIS_RUBBER_BALL, Ball
from ...terms.model import Model, Solver
from ._common import _is_lfe


def _check_ranges(ranges: Mapping, canonical: Callable = lambda n: n) -> dict[str, tuple[float, float]]:
    if not isinstance(ranges, Mapping) or not ranges:
        raise ValueError(f"ranges={ranges!r} must be a non-empty mapping of parameter name to (low, high)")
    out = {}
    for name, bounds in ranges.items():
        try:
            low, high = (float(b) for b in bounds)
        except (TypeError, ValueError):
            raise ValueError(f"ranges[{name!r}]={bounds!r} must be a pair (low, high) of numbers") from None
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"ranges[{name!r}]=({low!r}, {high!r}) must be finite with low < high")
        out[canonical(name)] = (low, high)
    return out


def _outputs_dict(y) -> dict[str, np.ndarray]:
    if isinstance(y, Mapping):
        return {k: np.asarray(v, dtype=float) for k, v in y.items()}
    return {"y": np.asarray(y, dtype=float)}


def _scale(unit: np.ndarray, ranges: dict) -> dict[str, np.ndarray]:
    return {name: lo + (hi - lo) * unit[:, j] for j, (name, (lo, hi)) in enumerate(ranges.items())}


@dataclasses.dataclass(frozen=True)
class _IndexResult:
    """What ``SobolResult`` and ``MorrisResult`` share: the first fields (parameter and output
    names, the uniform ranges), per-output, per-parameter indices of which one (``_RANKING``:
    S_Ti, μ*) ranks the parameters, and their JSON summary and text table."""

    _RANKING: ClassVar[str]
    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    ranges: dict

    def driver(self, output: str) -> str:
        """The parameter with the largest ranking index of ``output``: the largest total-order
        index (Sobol), what drives the output's spread; the largest μ* (Morris), the most
        influential one."""
        return self.parameters[int(np.nanargmax(getattr(self, self._RANKING)[output]))]

    def _driver_or(self, output: str, default):
        """``driver(output)``, or ``default`` when no index of the output is finite."""
        return self.driver(output) if np.any(np.isfinite(getattr(self, self._RANKING)[output])) else default

    def _summary(self, head: dict, design: dict, scalars: Callable[[str], dict], indices: tuple[str, ...]) -> dict:
        """``to_dict``: ``head``, the parameters and ranges, ``design``, then per output its driver,
        ``scalars(output)`` and each index attribute in ``indices`` as parameter → value."""
        return {
            **head,
            "parameters": list(self.parameters),
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            **design,
            "outputs": {
                o: {
                    "driver": self._driver_or(o, None),
                    **scalars(o),
                    **{k: dict(zip(self.parameters, getattr(self, k)[o].tolist())) for k in indices},
                }
                for o in self.outputs
            },
        }

    def _table(self, title: str, note: Callable[[str], str], row: Callable[[str, int], str]) -> str:
        """``table``: ``title``, then per output a line naming its driver (and ``note(output)``)
        and a line ``row(output, j)`` per parameter j."""
        lines = [title]
        for o in self.outputs:
            lines.append(f"{o}  (driver: {self._driver_or(o, '—')}{note(o)})")
            lines.extend(f"  {p:<20} {row(o, j)}" for j, p in enumerate(self.parameters))
        return "\n".join(lines)


@dataclasses.dataclass(frozen=True)
class SobolResult(_IndexResult):
    """Sobol indices of each output (see ``sobol_indices``).

    Attributes:
        parameters, outputs: names.
        ranges: parameter → (low, high), the uniform input ranges.
        n_base: base sample size n; ``n_evaluations`` = n (d + 2).
        first_order, total_order: output → indices S_i, S_Ti, shape (d,).
        first_order_ci, total_order_ci: output → bootstrap percentile intervals, shape (d, 2).
        confidence: level of the intervals.
        mean, variance: output → mean and variance over the A and B samples.
        n_valid: output → number of base rows with every evaluation finite (rows with a
            flagged solve are left out).
        samples: the inputs and outputs of every evaluation, with ``block`` = 0 for A, 1 for B,
            2 + i for A_B^(i).
    """

    n_base: int
    n_evaluations: int
    first_order: dict
    total_order: dict
    first_order_ci: dict
    total_order_ci: dict
    confidence: float
    mean: dict
    variance: dict
    n_valid: dict
    samples: dict = dataclasses.field(repr=False)

    _RANKING = "total_order"

    def to_dict(self) -> dict:
        return self._summary(
            {"method": "sobol", "estimators": "first order: Saltelli et al. 2010; total order: Jansen 1999; percentile bootstrap"},
            {"n_base": self.n_base, "n_evaluations": self.n_evaluations, "confidence": self.confidence},
            lambda o: {"mean": self.mean[o], "variance": self.variance[o], "n_valid": self.n_valid[o]},
            ("first_order", "total_order", "first_order_ci", "total_order_ci"),
        )

    def table(self) -> str:
        def row(o: str, j: int) -> str:
            s, (slo, shi) = self.first_order[o][j], self.first_order_ci[o][j]
            t, (tlo, thi) = self.total_order[o][j], self.total_order_ci[o][j]
            return f"S {s:7.3f} [{slo:6.3f}, {shi:6.3f}]   S_T {t:7.3f} [{tlo:6.3f}, {thi:6.3f}]"

        title = f"Sobol indices, {self.n_evaluations} evaluations (n = {self.n_base}), {self.confidence:.0%} bootstrap CI"
        return self._table(title, lambda o: f", valid rows {self.n_valid[o]}", row)


def _sobol_estimates(ya, yb, yab):
    """S_i (Saltelli 2010) and S_Ti (Jansen 1999) from rows (..., n); yab: (d, ..., n).

    The outputs are centred on the mean of y_A and y_B first: that leaves the expectation of
    the first-order estimator unchanged (E[y_{A_B^i} − y_A] = 0) and removes its variance
    term proportional to the squared mean (large for, e.g., a contact time of 20 ± 1 ms).
    """
    both = np.concatenate([ya, yb], axis=-1)
    centre = np.mean(both, axis=-1, keepdims=True)
    ya, yb, yab = ya - centre, yb - centre, yab - centre
    variance = np.var(both, axis=-1)
    first = np.mean(yb * (yab - ya), axis=-1) / variance
    total = 0.5 * np.mean((ya - yab) ** 2, axis=-1) / variance
    return first, total


def sobol_indices(
    func: Callable,
    ranges: Mapping,
    n_base: int,
    *,
    seed: int = 0,
    n_bootstrap: int = 200,
    confidence: float = 0.95,
) -> SobolResult:
    """First- and total-order Sobol indices of ``func`` over independent uniform inputs.

    ``func`` takes a dict parameter → (N,) array and returns an (N,) array or a dict of them
    (one per output); it is called once, with all N = n_base (d + 2) rows (the A, B and
    A_B^(i) matrices of Saltelli et al. 2010, from a seeded pseudo-random design). Estimators:
    S_i = mean(y_B (y_{A_B^i} − y_A)) / V (Saltelli et al. 2010) and
    S_Ti = mean((y_A − y_{A_B^i})²) / (2V) (Jansen 1999), V the variance of y_A and y_B
    together; confidence intervals by the percentile bootstrap over the n base rows. Rows with a
    non-finite output are dropped for that output (``n_valid``).
    """
    ranges = _check_ranges(ranges)
    check_range("n_base", n_base, lower=1.0, upper=math.inf, lower_open=False)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    check_range("n_bootstrap", n_bootstrap, lower=0.0, upper=math.inf, lower_open=False)
    n, d = int(n_base), len(ranges)
    rng = np.random.default_rng(seed)
    a, b = rng.random((n, d)), rng.random((n, d))
    ab = np.repeat(a[None], d, axis=0)
    ab[np.arange(d), :, np.arange(d)] = b.T
    unit = np.concatenate([a, b, ab.reshape(d * n, d)])
    inputs = _scale(unit, ranges)
    outputs = _outputs_dict(func(inputs))
    block = np.repeat(np.arange(d + 2), n)
    samples = {**inputs, **outputs, "block": block}

    alpha = 0.5 * (1.0 - confidence)
    res: dict[str, dict] = {k: {} for k in ("first", "total", "first_ci", "total_ci", "mean", "var", "n_valid")}
    boot_rng = np.random.default_rng([seed, 1])
    for name, y in outputs.items():
        if y.shape != (n * (d + 2),):
            raise ValueError(f"func returned {name!r} with shape {y.shape}; expected ({n * (d + 2)},)")
        blocks = y.reshape(d + 2, n)
        keep = np.all(np.isfinite(blocks), axis=0)
        ya, yb, yab = blocks[0, keep], blocks[1, keep], blocks[2:, keep]
        m = int(keep.sum())
        res["n_valid"][name] = m
        res["mean"][name] = float(np.mean(np.concatenate([ya, yb]))) if m else math.nan
        res["var"][name] = float(np.var(np.concatenate([ya, yb]))) if m else math.nan
        if m < 2:
            nan = np.full(d, np.nan)
            res["first"][name], res["total"][name] = nan, nan
            res["first_ci"][name] = res["total_ci"][name] = np.full((d, 2), np.nan)
            continue
        res["first"][name], res["total"][name] = _sobol_estimates(ya, yb, yab)
        boot_first, boot_total = np.empty((n_bootstrap, d)), np.empty((n_bootstrap, d))
        for r in range(int(n_bootstrap)):
            idx = boot_rng.integers(0, m, m)
            boot_first[r], boot_total[r] = _sobol_estimates(ya[idx], yb[idx], yab[:, idx])
        q = [100 * alpha, 100 * (1 - alpha)]
        res["first_ci"][name] = np.percentile(boot_first, q, axis=0).T if n_bootstrap else np.full((d, 2), np.nan)
        res["total_ci"][name] = np.percentile(boot_total, q, axis=0).T if n_bootstrap else np.full((d, 2), np.nan)
    return SobolResult(
        parameters=tuple(ranges),
        outputs=tuple(outputs),
        ranges=ranges,
        n_base=n,
        n_evaluations=n * (d + 2),
        first_order=res["first"],
        total_order=res["total"],
        first_order_ci=res["first_ci"],
        total_order_ci=res["total_ci"],
        confidence=float(confidence),
        mean=res["mean"],
        variance=res["var"],
        n_valid=res["n_valid"],
        samples=samples,
    )


@dataclasses.dataclass(frozen=True)
class MorrisResult(_IndexResult):
    """Morris elementary-effect screening (see ``morris_screening``).

    Attributes:
        mu, mu_star, sigma: output → mean, mean absolute value and standard deviation of the
            elementary effects per parameter, shape (d,), in output units per full range of
            the parameter (an effect of 1 means the output changes by 1 across the range).
        n_trajectories, n_levels, n_evaluations = n_trajectories (d + 1).
    """

    n_trajectories: int
    n_levels: int
    n_evaluations: int
    mu: dict
    mu_star: dict
    sigma: dict
    samples: dict = dataclasses.field(repr=False)

    _RANKING = "mu_star"

    def to_dict(self) -> dict:
        return self._summary(
            {"method": "morris"},
            {"n_trajectories": self.n_trajectories, "n_levels": self.n_levels, "n_evaluations": self.n_evaluations},
            lambda o: {},
            ("mu", "mu_star", "sigma"),
        )

    def table(self) -> str:
        def row(o: str, j: int) -> str:
            return f"mu* {self.mu_star[o][j]:11.4g}  mu {self.mu[o][j]:11.4g}  sigma {self.sigma[o][j]:11.4g}"

        title = f"Morris screening, {self.n_evaluations} evaluations ({self.n_trajectories} trajectories, {self.n_levels} levels)"
        return self._table(title, lambda o: "", row)


def morris_screening(func: Callable, ranges: Mapping, n_trajectories: int, *, n_levels: int = 4, seed: int = 0) -> MorrisResult:
    """Morris (1991) elementary effects of ``func`` over uniform ranges (one-at-a-time trajectories).

    Each trajectory starts at a random point of the p-level grid of the unit cube and moves
    every parameter once, in random order, by Δ = p / (2(p − 1)) (up if that stays inside,
    else down). The elementary effect of parameter i is (y(x ± Δe_i) − y(x)) / (±Δ), in output
    units per full range. ``func`` is called once with all r (d + 1) points (see
    ``sobol_indices``). Effects with a non-finite output are left out.
    """
    ranges = _check_ranges(ranges)
    check_range("n_trajectories", n_trajectories, lower=1.0, upper=math.inf, lower_open=False)
    if not isinstance(n_levels, (int, np.integer)) or n_levels < 2 or n_levels % 2:
        raise ValueError(f"n_levels={n_levels!r} must be an even integer >= 2")
    r, d, p = int(n_trajectories), len(ranges), int(n_levels)
    delta = p / (2.0 * (p - 1))
    rng = np.random.default_rng(seed)
    points = np.empty((r, d + 1, d))
    moved = np.empty((r, d), dtype=int)
    step = np.empty((r, d))
    for t in range(r):
        x = rng.integers(0, p, d) / (p - 1)
        order = rng.permutation(d)
        points[t, 0] = x
        for k, i in enumerate(order):
            s = delta if x[i] + delta <= 1.0 + 1e-12 else -delta
            x = x.copy()
            x[i] += s
            points[t, k + 1] = x
            moved[t, k], step[t, k] = i, s
    inputs = _scale(points.reshape(-1, d), ranges)
    outputs = _outputs_dict(func(inputs))
    res: dict[str, dict] = {"mu": {}, "mu_star": {}, "sigma": {}}
    for name, y in outputs.items():
        y = y.reshape(r, d + 1)
        effects = np.full((r, d), np.nan)
        effects[np.arange(r)[:, None], moved] = np.diff(y, axis=1) / step
        with np.errstate(invalid="ignore"):
            res["mu"][name] = np.nanmean(effects, axis=0)
            res["mu_star"][name] = np.nanmean(np.abs(effects), axis=0)
            res["sigma"][name] = np.nanstd(effects, axis=0, ddof=1) if r > 1 else np.full(d, np.nan)
    return MorrisResult(
        parameters=tuple(ranges),
        outputs=tuple(outputs),
        ranges=ranges,
        n_trajectories=r,
        n_levels=p,
        n_evaluations=r * (d + 1),
        mu=res["mu"],
        mu_star=res["mu_star"],
        sigma=res["sigma"],
        samples={**inputs, **outputs, "trajectory": np.repeat(np.arange(r), d + 1)},
    )


def _impact_outputs(outputs) -> tuple[tuple[str, ...], bool]:
    """Expand ``"lfe"`` to the band names; check the names; say whether L_FE is needed."""
    valid = SWEEP_SCALAR_OUTPUTS + lfe_output_names()
    expanded: list[str] = []
    for o in [outputs] if isinstance(outputs, str) else outputs:
        expanded.extend(lfe_output_names() if o == "lfe" else [o])
    unknown = [o for o in expanded if o not in valid]
    if unknown or not expanded:
        raise ValueError(f"outputs={list(outputs)!r}: unknown {unknown}; valid: 'lfe', {', '.join(valid)}")
    names = tuple(dict.fromkeys(expanded))
    return names, any(_is_lfe(o) for o in names)


def global_sensitivity(
    ranges: Mapping,
    n: int,
    *,
    method: str = "sobol",
    outputs=("contact_time_s", "peak_force_N", "restitution", "lfe"),
    height_m: float = 1.0,
    ball: Ball = JIS_RUBBER_BALL,
    gas: str = "adiabatic",
    blocked_force: str = "paper",
    damping=None,
    stiffening=None,
    model: Model | None = None,
    solver: Solver | None = None,
    seed: int = 0,
    n_bootstrap: int = 200,
    confidence: float = 0.95,
    n_levels: int = 4,
    chunk_size: int = 1024,
    devices=None,
    progress: bool = False,
) -> SobolResult | MorrisResult:
    """Global sensitivity of the impact outputs over uniform parameter ranges.

    Args:
        ranges: parameter name (any case; see ``rbjax.studies.sweep.parameter_names``) → (low, high).
        n: ``method="sobol"``: base sample size (n (d + 2) impacts); ``"morris"``: number of
            trajectories (n (d + 1) impacts).
        outputs: among ``contact_time_s``, ``peak_force_N``, ``restitution``,
            ``max_deflection_m``, ``lfe_<band>_dB`` and ``"lfe"`` (all octave bands).
        height_m, ball, gas, blocked_force, damping, stiffening: the nominal impact (or pass
            ``model``); parameters not in ``ranges`` keep these values.
        seed, n_bootstrap, confidence, n_levels: of the estimators.
        chunk_size, devices, progress: batching and sharding (``rbjax.studies.sweep.evaluate``).

    Returns:
        ``SobolResult`` or ``MorrisResult``; ``.driver(output)`` names the parameter that drives
        an output's spread. Elastic models use the quadrature fast path for the scalar outputs;
        L_FE needs the force history (ODE).
    """
    if model is None:
        model = make_model(gas=gas, blocked_force=blocked_force, damping=damping, stiffening=stiffening)
    ranges = _check_ranges(ranges, lambda name: canonical_name(name, model))
    names, lfe = _impact_outputs(outputs)
    for name, (lo, hi) in ranges.items():  # bounds must be valid parameter values (named errors)
        bounds = {name: np.array([lo, hi])}
        assemble(bounds, height_m, ball, model)
        if name == "height_m":
            check_range("height_m", bounds[name], lower=0.0)

    def func(inputs):
        out = evaluate(inputs, height_m=height_m, ball=ball, model=model, solver=solver, lfe=lfe, chunk_size=chunk_size, devices=devices, progress=progress)
        return {o: out[o] for o in names}

    if method == "sobol":
        return sobol_indices(func, ranges, n, seed=seed, n_bootstrap=n_bootstrap, confidence=confidence)
    if method == "morris":
        return morris_screening(func, ranges, n, n_levels=n_levels, seed=seed)
    raise ValueError(f"method={method!r} is not known; valid: 'sobol', 'morris'")

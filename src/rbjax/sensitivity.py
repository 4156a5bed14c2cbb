"""Sensitivity of the rubber-ball impact to its parameters: local, global, and conformance.

* **Local** (:func:`local_sensitivity`): the Jacobian of the contact time, peak force,
  restitution coefficient (paper §2.4, Eq. 7 solved to the end of contact) and the octave-band
  force exposure levels L_FE 31.5 Hz–1 kHz (Eq. 11, from the 44.1 kHz × 1 s force history,
  §2.4) with respect to the drop height (Eq. 10), the ball parameters (R, h, M, E, ν: §2.1,
  Eqs. 1–3, 6) and the damping parameters, by forward-mode automatic differentiation
  (``jax.jvp`` per parameter, ``Solver(adjoint="forward")``) through the diffrax solve and its
  event times. Elasticities ∂ln y/∂ln x are % change of the output per % change of the
  parameter; for an L_FE band, whose dB value is already logarithmic, the elasticity is that
  of the band's force energy E (L_FE = 10 log10 E, so ∂ln E/∂ln x = (ln 10/10) x ∂L_FE/∂x).
* **Global**: Sobol first- and total-order indices (:func:`sobol_indices`, Saltelli 2010
  first-order and Jansen 1999 total-order estimators, bootstrap confidence intervals) and
  Morris elementary-effect screening (:func:`morris_screening`) over uniform parameter ranges;
  :func:`global_sensitivity` applies them to the impact model, evaluated in batches sharded
  over the JAX devices (:mod:`rbjax.sweep`).
* **Conformance probability** (:func:`conformance_probability`): Monte Carlo probability that
  a ball whose drop height, mass or rubber vary stays inside the rubber-ball tolerances
  (ISO 16283-2:2020 Table A.1 = ISO 10140-5:2010 Table F.1 = JIS A 1418-2:2019 Table A.2:
  L_FE per octave band 31.5–500 Hz, contact time, restitution, mass, drop height), with Wilson
  score confidence intervals.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping

import jax
import jax.numpy as jnp
import numpy as np

from ._validate import as_float, check_range
from .ball import JIS_RUBBER_BALL, Ball
from .batch import SCALAR_OUTPUTS as SWEEP_SCALAR_OUTPUTS
from .batch import (
    assemble,
    canonical_name,
    evaluate,
    lfe_output_names,
    parameter_names,
)
from .model import Model, Solver
from .parameters import parameter_table
from .simulate import (
    PAPER_DURATION_S,
    PAPER_RATE_Hz,
    _simulate,
    check_inputs,
    make_model,
    trajectory,
)

SCALAR_OUTPUTS = ("contact_time_s", "peak_force_N", "restitution")
_LN10_OVER_10 = math.log(10.0) / 10.0


def _is_lfe(name: str) -> bool:
    return name.startswith("lfe_")


# ----------------------------------------------------------------------------------------------
# Local sensitivity.


@dataclasses.dataclass(frozen=True)
class Sensitivity:
    """Local derivatives of the impact outputs at each drop height (see ``local_sensitivity``).

    Attributes:
        height_m: drop heights, shape (H,).
        parameters: the parameters differentiated against (``wrt``).
        outputs: output names: ``contact_time_s``, ``peak_force_N``, ``restitution`` and
            ``lfe_<band>_dB`` per octave band.
        values: output → values, shape (H,).
        parameter_values: parameter → value at each height, shape (H,).
        jacobian: output → parameter → ∂output/∂parameter, shape (H,), in output units per
            parameter unit. NaN where ``status != 0``.
        status: solver status per height (0 ok; see ``rbjax.STATUS_NAMES``).
    """

    height_m: np.ndarray
    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    values: dict
    parameter_values: dict
    jacobian: dict
    status: np.ndarray

    @property
    def status_name(self) -> list[str]:
        from .impact import STATUS_NAMES

        return [STATUS_NAMES[int(s)] for s in self.status]

    @property
    def elasticity(self) -> dict:
        """output → parameter → ∂ln y/∂ln x (% per %), shape (H,).

        For an L_FE band it is the elasticity of the band energy, (ln 10/10)·x·∂L_FE/∂x.
        """
        out = {}
        for o in self.outputs:
            scale = _LN10_OVER_10 if _is_lfe(o) else 1.0 / self.values[o]
            out[o] = {p: self.jacobian[o][p] * self.parameter_values[p] * scale for p in self.parameters}
        return out

    def to_dict(self) -> list[dict]:
        """One dict per height: ``height_m``, ``status``, ``values``, ``jacobian``, ``elasticity``."""
        el = self.elasticity
        names = self.status_name
        rows = []
        for i, h in enumerate(self.height_m):
            rows.append(
                {
                    "height_m": float(h),
                    "status": names[i],
                    "parameters": {p: float(self.parameter_values[p][i]) for p in self.parameters},
                    "values": {o: float(self.values[o][i]) for o in self.outputs},
                    "jacobian": {o: {p: float(self.jacobian[o][p][i]) for p in self.parameters} for o in self.outputs},
                    "elasticity": {o: {p: float(el[o][p][i]) for p in self.parameters} for o in self.outputs},
                }
            )
        return rows

    def plot(self, height_index: int = 0, outputs=None, *, figsize=None):
        """Tornado chart of the elasticities at one height: a panel per output, bars sorted by size.

        A bar is the % change of the output (band energy for L_FE) per % change of the
        parameter. Returns the matplotlib figure (``fig.savefig("tornado.png")``).
        """
        import matplotlib.pyplot as plt

        from . import plot as _plot  # noqa: F401  (selects a headless backend when needed)

        outputs = self.outputs if outputs is None else tuple(outputs)
        unknown = set(outputs) - set(self.outputs)
        if unknown:
            raise ValueError(f"outputs {sorted(unknown)} are not known; valid: {', '.join(self.outputs)}")
        n = len(self.height_m)
        if not (isinstance(height_index, (int, np.integer)) and 0 <= height_index < n):
            raise ValueError(f"height_index={height_index!r} is outside the valid range: an integer in [0, {n - 1}]")
        i = int(height_index)
        el = self.elasticity
        ncols = min(3, len(outputs))
        nrows = math.ceil(len(outputs) / ncols)
        fig, axes = plt.subplots(
            nrows, ncols, squeeze=False, layout="constrained", figsize=figsize or (4.0 * ncols, 0.35 * len(self.parameters) * nrows + 1.2 * nrows)
        )
        for ax, o in zip(axes.flat, outputs):
            vals = np.array([el[o][p][i] for p in self.parameters])
            order = np.argsort(np.abs(np.nan_to_num(vals)))
            colors = ["tab:red" if v < 0 else "tab:blue" for v in vals[order]]
            ax.barh(np.arange(len(order)), vals[order], color=colors)
            ax.set_yticks(np.arange(len(order)), [self.parameters[k] for k in order])
            ax.axvline(0.0, color="k", lw=0.8)
            label = f"L_FE {o[4:-3]} Hz (energy)" if _is_lfe(o) else o
            ax.set_title(label, fontsize=9)
            ax.set_xlabel("elasticity (% per %)", fontsize=8)
            ax.tick_params(labelsize=8)
        for ax in list(axes.flat)[len(outputs) :]:
            ax.set_visible(False)
        fig.suptitle(f"Local sensitivity at drop height {self.height_m[i]:g} m ({self.status_name[i]})", fontsize=10)
        return fig


@functools.lru_cache(maxsize=16)
def _local_jacobian_fn(names: tuple, wrt: tuple, solver: Solver, n_times: int, n_total: int, rate_Hz: float) -> Callable:
    """Jitted (θ, ball, model) → (values, tangents per wrt parameter, status); one compile per setup."""
    from .spectrum import lfe_octave_dB

    def outputs(theta, ball, model):
        height, ball, model = assemble(theta, None, ball, model)
        result = _simulate(height, ball, model, solver)
        out = {k: getattr(result, k) for k in SCALAR_OUTPUTS}
        if n_times:  # the force history on the contact window, zero-padded to the record (§2.4)
            force = trajectory(height, jnp.arange(n_times) / rate_Hz, ball, model, solver).force_N
            force = jnp.pad(force, ((0, 0), (0, n_total - n_times)))
            lfe = lfe_octave_dB(force, rate_Hz)
            out.update({name: lfe[:, j] for j, name in enumerate(lfe_output_names())})
        return out, result.status

    def fn(theta, ball, model):
        def tangent(i):
            return {k: jnp.where(i == wrt.index(k), 1.0, 0.0) * jnp.ones_like(v) if k in wrt else jnp.zeros_like(v) for k, v in theta.items()}

        def push(i):
            return jax.jvp(lambda t: outputs(t, ball, model), (theta,), (tangent(i),), has_aux=True)

        values, tangents, status = jax.vmap(push)(jnp.arange(len(wrt)))
        first = lambda x: x[0]  # noqa: E731  (the primal does not depend on the tangent)
        return jax.tree_util.tree_map(first, values), tangents, first(status)

    return jax.jit(fn)


def local_sensitivity(
    height_m,
    ball: Ball = JIS_RUBBER_BALL,
    *,
    wrt=None,
    gas: str = "adiabatic",
    blocked_force: str = "paper",
    damping=None,
    stiffening=None,
    model: Model | None = None,
    lfe: bool = True,
    solver: Solver | None = None,
    rate_Hz: float = PAPER_RATE_Hz,
    duration_s: float = PAPER_DURATION_S,
) -> Sensitivity:
    """Jacobian of the impact outputs w.r.t. the parameters, by forward-mode AD (paper §2).

    Args:
        height_m: drop height(s) h_D in m (scalar or 1-D).
        ball: the ball at which to differentiate.
        wrt: parameter names (any letter case), default all: ``height_m``, ``radius_m``,
            ``wall_m``, ``mass_kg``, ``youngs_Pa``, ``poisson``, the fields of ``damping``
            (e.g. ``damping_Ns_per_m``) and ``beta`` with ``stiffening``.
        gas, blocked_force, damping, stiffening: the model, as in ``rbjax.simulate`` (or pass
            ``model``, e.g. from ``rbjax.serialize.load_params``).
        lfe: also differentiate L_FE in the octave bands 31.5 Hz–1 kHz (Eq. 11, §2.4).
        solver: integration settings (its adjoint is set to ``"forward"``).
        rate_Hz, duration_s: the force record for L_FE (default the paper's 44.1 kHz × 1 s).

    Returns:
        A ``Sensitivity``; heights whose solve is flagged (status ≠ 0) have NaN values and
        derivatives.
    """
    check_inputs(height_m, ball, rate_Hz, duration_s)
    heights = np.atleast_1d(np.asarray(height_m, dtype=np.float64))
    if heights.ndim != 1:
        raise ValueError(f"height_m has shape {np.shape(height_m)}; expected a scalar or 1-D array")
    if model is None:
        model = make_model(gas=gas, blocked_force=blocked_force, damping=damping, stiffening=stiffening)
    valid = parameter_names(model)
    wrt = valid if wrt is None else tuple(dict.fromkeys(canonical_name(w, model) for w in ([wrt] if isinstance(wrt, str) else wrt)))
    if not wrt:
        raise ValueError(f"wrt is empty; valid parameters: {', '.join(valid)}")
    wrt = tuple(p for p in valid if p in wrt)  # a canonical order: one compiled program per set
    solver = dataclasses.replace(Solver() if solver is None else solver, adjoint="forward")

    n_times = n_total = 0
    if lfe:
        n_total = int(round(rate_Hz * duration_s))
        tc = np.asarray(_simulate(heights, ball, model, solver).contact_time_s)
        longest = float(np.nanmax(tc)) if np.any(np.isfinite(tc)) else 0.0
        n_times = min(n_total, int(math.ceil(longest * rate_Hz)) + 2)

    ball_arrays = ball.as_arrays()
    theta = {row.name: jnp.asarray(row.value, dtype=jnp.float64) for row in parameter_table(1.0, ball, model)}
    theta["height_m"] = jnp.asarray(heights)
    fn = _local_jacobian_fn(valid, wrt, solver, n_times, n_total, float(rate_Hz))
    values, tangents, status = fn(theta, ball_arrays, model)

    status = np.asarray(status).astype(int)
    bad = status != 0
    mask = lambda x: np.where(bad, np.nan, np.broadcast_to(np.asarray(x, dtype=float), heights.shape))  # noqa: E731
    outputs = SCALAR_OUTPUTS + (lfe_output_names() if lfe else ())
    return Sensitivity(
        height_m=heights,
        parameters=wrt,
        outputs=outputs,
        values={o: mask(values[o]) for o in outputs},
        parameter_values={p: np.broadcast_to(np.asarray(theta[p], dtype=float), heights.shape).copy() for p in wrt},
        jacobian={o: {p: mask(tangents[o][j]) for j, p in enumerate(wrt)} for o in outputs},
        status=status,
    )


# ----------------------------------------------------------------------------------------------
# Global sensitivity: Sobol indices and Morris screening.


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
class SobolResult:
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

    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    ranges: dict
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

    def driver(self, output: str) -> str:
        """The parameter with the largest total-order index: what drives the output's spread."""
        return self.parameters[int(np.nanargmax(self.total_order[output]))]

    def to_dict(self) -> dict:
        return {
            "method": "sobol",
            "estimators": "first order: Saltelli et al. 2010; total order: Jansen 1999; percentile bootstrap",
            "parameters": list(self.parameters),
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "n_base": self.n_base,
            "n_evaluations": self.n_evaluations,
            "confidence": self.confidence,
            "outputs": {
                o: {
                    "driver": self.driver(o) if np.any(np.isfinite(self.total_order[o])) else None,
                    "mean": self.mean[o],
                    "variance": self.variance[o],
                    "n_valid": self.n_valid[o],
                    "first_order": dict(zip(self.parameters, self.first_order[o].tolist())),
                    "total_order": dict(zip(self.parameters, self.total_order[o].tolist())),
                    "first_order_ci": dict(zip(self.parameters, self.first_order_ci[o].tolist())),
                    "total_order_ci": dict(zip(self.parameters, self.total_order_ci[o].tolist())),
                }
                for o in self.outputs
            },
        }

    def table(self) -> str:
        lines = [f"Sobol indices, {self.n_evaluations} evaluations (n = {self.n_base}), {self.confidence:.0%} bootstrap CI"]
        for o in self.outputs:
            lines.append(f"{o}  (driver: {self.driver(o) if np.any(np.isfinite(self.total_order[o])) else '—'}, valid rows {self.n_valid[o]})")
            for j, p in enumerate(self.parameters):
                s, (slo, shi) = self.first_order[o][j], self.first_order_ci[o][j]
                t, (tlo, thi) = self.total_order[o][j], self.total_order_ci[o][j]
                lines.append(f"  {p:<20} S {s:7.3f} [{slo:6.3f}, {shi:6.3f}]   S_T {t:7.3f} [{tlo:6.3f}, {thi:6.3f}]")
        return "\n".join(lines)


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
class MorrisResult:
    """Morris elementary-effect screening (see ``morris_screening``).

    Attributes:
        mu, mu_star, sigma: output → mean, mean absolute value and standard deviation of the
            elementary effects per parameter, shape (d,), in output units per full range of
            the parameter (an effect of 1 means the output changes by 1 across the range).
        n_trajectories, n_levels, n_evaluations = n_trajectories (d + 1).
    """

    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    ranges: dict
    n_trajectories: int
    n_levels: int
    n_evaluations: int
    mu: dict
    mu_star: dict
    sigma: dict
    samples: dict = dataclasses.field(repr=False)

    def driver(self, output: str) -> str:
        """The parameter with the largest μ*: the most influential one."""
        return self.parameters[int(np.nanargmax(self.mu_star[output]))]

    def to_dict(self) -> dict:
        return {
            "method": "morris",
            "parameters": list(self.parameters),
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "n_trajectories": self.n_trajectories,
            "n_levels": self.n_levels,
            "n_evaluations": self.n_evaluations,
            "outputs": {
                o: {
                    "driver": self.driver(o) if np.any(np.isfinite(self.mu_star[o])) else None,
                    "mu": dict(zip(self.parameters, self.mu[o].tolist())),
                    "mu_star": dict(zip(self.parameters, self.mu_star[o].tolist())),
                    "sigma": dict(zip(self.parameters, self.sigma[o].tolist())),
                }
                for o in self.outputs
            },
        }

    def table(self) -> str:
        lines = [f"Morris screening, {self.n_evaluations} evaluations ({self.n_trajectories} trajectories, {self.n_levels} levels)"]
        for o in self.outputs:
            lines.append(f"{o}  (driver: {self.driver(o) if np.any(np.isfinite(self.mu_star[o])) else '—'})")
            for j, p in enumerate(self.parameters):
                lines.append(f"  {p:<20} mu* {self.mu_star[o][j]:11.4g}  mu {self.mu[o][j]:11.4g}  sigma {self.sigma[o][j]:11.4g}")
        return "\n".join(lines)


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
        ranges: parameter name (any case; see ``rbjax.sweep.parameter_names``) → (low, high).
        n: ``method="sobol"``: base sample size (n (d + 2) impacts); ``"morris"``: number of
            trajectories (n (d + 1) impacts).
        outputs: among ``contact_time_s``, ``peak_force_N``, ``restitution``,
            ``max_deflection_m``, ``lfe_<band>_dB`` and ``"lfe"`` (all octave bands).
        height_m, ball, gas, blocked_force, damping, stiffening: the nominal impact (or pass
            ``model``); parameters not in ``ranges`` keep these values.
        seed, n_bootstrap, confidence, n_levels: of the estimators.
        chunk_size, devices, progress: batching and sharding (``rbjax.sweep.evaluate``).

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


# ----------------------------------------------------------------------------------------------
# Conformance probability.

DISTRIBUTION_KINDS = {"uniform": ("low", "high"), "normal": ("mean", "sd"), "lognormal": ("median", "sigma")}


def _distribution(name: str, spec) -> tuple[str, float, float]:
    """(kind, a, b) from ``{"kind": ..., <two parameters>}`` or ``(kind, a, b)``."""
    if isinstance(spec, Mapping):
        spec = dict(spec)
        kind = spec.pop("kind", None)
        keys = DISTRIBUTION_KINDS.get(kind)
        if keys is None or set(spec) != set(keys):
            raise ValueError(
                f"distributions[{name!r}]={spec!r} (kind {kind!r}) is not valid; valid: "
                + "; ".join(f"{{kind = {k!r}, {', '.join(v)}}}" for k, v in DISTRIBUTION_KINDS.items())
            )
        a, b = (spec[k] for k in keys)
    else:
        try:
            kind, a, b = spec
        except (TypeError, ValueError):
            raise ValueError(f"distributions[{name!r}]={spec!r} must be a mapping or (kind, a, b)") from None
        if kind not in DISTRIBUTION_KINDS:
            raise ValueError(f"distributions[{name!r}] kind {kind!r} is not known; valid: {', '.join(DISTRIBUTION_KINDS)}")
    a, b = float(a), float(b)
    ok = math.isfinite(a) and math.isfinite(b) and (a < b if kind == "uniform" else b > 0.0) and (kind != "lognormal" or a > 0.0)
    if not ok:
        need = {"uniform": "low < high", "normal": "sd > 0", "lognormal": "median > 0 and sigma > 0"}[kind]
        raise ValueError(f"distributions[{name!r}] = {kind}({a!r}, {b!r}) is not valid: needs {need}")
    return kind, a, b


def draw_samples(distributions: Mapping, n_samples: int, seed: int = 0) -> dict[str, np.ndarray]:
    """n_samples independent draws per parameter: uniform(low, high), normal(mean, sd), or
    lognormal(median, sigma) (ln X ~ N(ln median, sigma²)); seeded, identical on every host."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, spec in distributions.items():
        kind, a, b = _distribution(name, spec)
        if kind == "uniform":
            out[name] = rng.uniform(a, b, n_samples)
        elif kind == "normal":
            out[name] = rng.normal(a, b, n_samples)
        else:
            out[name] = a * np.exp(b * rng.standard_normal(n_samples))
    return out


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (Wilson 1927; ``scipy.stats.binomtest``);
    (nan, nan) for n = 0."""
    if n == 0:
        return (math.nan, math.nan)
    from scipy.stats import binomtest

    ci = binomtest(int(successes), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return (float(ci.low), float(ci.high))


@dataclasses.dataclass(frozen=True)
class ConformanceProbability:
    """Monte Carlo conformance of the rubber ball to its tolerance table.

    Attributes:
        n_samples: draws; ``n_valid`` of them solved (status 0) and enter the probabilities.
        probability: item → fraction of valid samples inside the tolerance: ``lfe_<band>_dB``
            for 31.5–500 Hz, ``lfe`` (all five bands), ``contact_time_s``, ``restitution``,
            ``mass_kg``, ``height_m``, ``overall`` (every item).
        interval: item → Wilson score interval at ``confidence``.
        distributions: the input distributions, as (kind, a, b).
        samples: inputs, outputs and per-item pass flags of every draw.
    """

    n_samples: int
    n_valid: int
    confidence: float
    probability: dict
    interval: dict
    distributions: dict
    samples: dict = dataclasses.field(repr=False)

    def to_dict(self) -> dict:
        from .standards import CLAUSE

        return {
            "method": "monte-carlo conformance",
            "clause": CLAUSE,
            "n_samples": self.n_samples,
            "n_valid": self.n_valid,
            "confidence": self.confidence,
            "interval_method": "Wilson score",
            "distributions": {k: list(v) for k, v in self.distributions.items()},
            "probability": dict(self.probability),
            "interval": {k: list(v) for k, v in self.interval.items()},
        }

    def table(self) -> str:
        lines = [f"Conformance probability, {self.n_valid} valid of {self.n_samples} samples, {self.confidence:.0%} Wilson interval"]
        for k, p in self.probability.items():
            lo, hi = self.interval[k]
            lines.append(f"  {k:<18} {p:7.4f}  [{lo:.4f}, {hi:.4f}]")
        return "\n".join(lines)


def conformance_flags(values: Mapping, tolerances=None) -> dict[str, np.ndarray]:
    """Per-sample pass flags, vectorised, by the rule of ``rbjax.standards.check_conformance``
    (lower ≤ value ≤ upper of ``RUBBER_BALL_TOLERANCES``). ``values`` holds arrays of the band
    levels ``lfe_<band>_dB``, ``contact_time_s``, ``restitution``, ``mass_kg``, ``height_m``."""
    from .standards import RUBBER_BALL_TOLERANCES, TOLERANCED_OCTAVE_BANDS

    tol = RUBBER_BALL_TOLERANCES if tolerances is None else tolerances
    inside = lambda t, v: (t.lower <= v) & (v <= t.upper)  # noqa: E731
    flags = {f"lfe_{b}_dB": inside(tol.lfe_octave_dB[b], values[f"lfe_{b}_dB"]) for b in TOLERANCED_OCTAVE_BANDS}
    flags["lfe"] = np.all(np.stack(list(flags.values())), axis=0)
    flags["contact_time_s"] = inside(tol.contact_time, values["contact_time_s"])
    flags["restitution"] = inside(tol.restitution, values["restitution"])
    flags["mass_kg"] = inside(tol.mass, values["mass_kg"])
    flags["height_m"] = inside(tol.drop_height, values["height_m"])
    flags["overall"] = flags["lfe"] & flags["contact_time_s"] & flags["restitution"] & flags["mass_kg"] & flags["height_m"]
    return flags


def conformance_probability(
    n_samples: int,
    distributions: Mapping,
    *,
    seed: int = 0,
    height_m: float = 1.0,
    ball: Ball = JIS_RUBBER_BALL,
    gas: str = "adiabatic",
    blocked_force: str = "paper",
    damping=None,
    stiffening=None,
    model: Model | None = None,
    solver: Solver | None = None,
    confidence: float = 0.95,
    chunk_size: int = 1024,
    devices=None,
    progress: bool = False,
) -> ConformanceProbability:
    """Probability that the ball meets the rubber-ball tolerances when its parameters vary.

    ``distributions`` maps parameter names (height, ball or damping fields, any case) to
    ``{"kind": "uniform", "low", "high"}``, ``{"kind": "normal", "mean", "sd"}`` or
    ``{"kind": "lognormal", "median", "sigma"}`` (or a tuple ``(kind, a, b)``), e.g.
    ``{"height_m": ("uniform", 0.99, 1.01), "mass_kg": ("normal", 2.5, 0.05),
    "youngs_Pa": ("lognormal", 1.6e6, 0.1)}``. Each of ``n_samples`` draws is simulated (the
    others keep ``height_m``, ``ball`` and the model), its L_FE per octave band (Eq. 11, §2.4),
    contact time, restitution, mass and drop height are checked against
    ``rbjax.standards.RUBBER_BALL_TOLERANCES`` (ISO 16283-2 Table A.1 = ISO 10140-5 Table F.1 =
    JIS A 1418-2 Table A.2), and the pass fractions come with Wilson score intervals. The L_FE
    limits hold for the standard drop height, so vary ``height_m`` around 1 m. Draws whose solve
    is flagged (status ≠ 0) are left out and counted (``n_valid``).
    """
    check_range("n_samples", n_samples, lower=1.0, upper=math.inf, lower_open=False)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    if model is None:
        model = make_model(gas=gas, blocked_force=blocked_force, damping=damping, stiffening=stiffening)
    if not isinstance(distributions, Mapping) or not distributions:
        raise ValueError(f"distributions={distributions!r} must be a non-empty mapping of parameter name to distribution")
    distributions = {canonical_name(k, model): v for k, v in distributions.items()}
    parsed = {k: _distribution(k, v) for k, v in distributions.items()}
    samples = draw_samples(distributions, int(n_samples), seed)
    out = evaluate(samples, height_m=height_m, ball=ball, model=model, solver=solver, lfe=True, chunk_size=chunk_size, devices=devices, progress=progress)
    n = int(n_samples)
    values = dict(out)
    values["mass_kg"] = samples.get("mass_kg", np.full(n, as_float(ball.mass_kg)))
    values["height_m"] = samples.get("height_m", np.full(n, float(height_m)))
    valid = out["status"] == 0
    flags = conformance_flags(values)
    n_valid = int(valid.sum())
    probability, interval = {}, {}
    for k, f in flags.items():
        hits = int(np.sum(f & valid))
        probability[k] = hits / n_valid if n_valid else math.nan
        interval[k] = wilson_interval(hits, n_valid, confidence)
    return ConformanceProbability(
        n_samples=n,
        n_valid=n_valid,
        confidence=float(confidence),
        probability=probability,
        interval=interval,
        distributions=parsed,
        samples={**{f"input_{k}": v for k, v in samples.items()}, **out, **{f"pass_{k}": v & valid for k, v in flags.items()}},
    )

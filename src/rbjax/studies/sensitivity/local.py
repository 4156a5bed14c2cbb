"""Local sensitivity of the rubber-ball impact: Jacobians and elasticities by forward-mode AD.

:func:`local_sensitivity` gives the Jacobian of the contact time, peak force, restitution
coefficient (paper §2.4, Eq. 7 solved to the end of contact) and the octave-band force exposure
levels L_FE 31.5 Hz–1 kHz (Eq. 11, from the 44.1 kHz × 1 s force history, §2.4) with respect
to the drop height (Eq. 10), the ball parameters (R, h, M, E, ν: §2.1, Eqs. 1–3, 6) and the
damping parameters, by forward-mode automatic differentiation (``jax.jvp`` per parameter,
``Solver(adjoint="forward")``) through the diffrax solve and its event times. Elasticities
∂ln y/∂ln x are % change of the output per % change of the parameter; for an L_FE band, whose
dB value is already logarithmic, the elasticity is that of the band's force energy E
(L_FE = 10 log10 E, so ∂ln E/∂ln x = (ln 10/10) x ∂L_FE/∂x).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np

from ...solve.batch import assemble, canonical_name, lfe_output_names
from ...solve.inputs import PAPER_DURATION_S, PAPER_RATE_Hz, check_inputs
from ...solve.options import model_from_shortcuts
from ...solve.outcome import STATUS_NAMES
from ...solve.simulate import simulate_model, trajectory
from ...solve.solver import Solver
from ...spectrum.levels import lfe_octave_dB
from ...terms.ball import JIS_RUBBER_BALL, Ball
from ...terms.model import Model
from ...terms.parameters import parameter_names, parameter_table
from ._common import is_lfe

SCALAR_OUTPUTS = ("contact_time_s", "peak_force_N", "restitution")
_LN10_OVER_10 = math.log(10.0) / 10.0


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

        return [STATUS_NAMES[int(s)] for s in self.status]

    @property
    def elasticity(self) -> dict:
        """output → parameter → ∂ln y/∂ln x (% per %), shape (H,).

        For an L_FE band it is the elasticity of the band energy, (ln 10/10)·x·∂L_FE/∂x.
        """
        out = {}
        for o in self.outputs:
            scale = _LN10_OVER_10 if is_lfe(o) else 1.0 / self.values[o]
            out[o] = {
                p: self.jacobian[o][p] * self.parameter_values[p] * scale for p in self.parameters
            }
        return out

    def to_dict(self) -> list[dict]:
        """One dict per height: ``height_m``, ``status``, ``values``, ``jacobian``,
        ``elasticity``."""
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
                    "jacobian": {
                        o: {p: float(self.jacobian[o][p][i]) for p in self.parameters}
                        for o in self.outputs
                    },
                    "elasticity": {
                        o: {p: float(el[o][p][i]) for p in self.parameters} for o in self.outputs
                    },
                }
            )
        return rows

    def plot(self, height_index: int = 0, outputs=None, *, figsize=None):
        """Tornado chart of the elasticities at one height: a panel per output, bars sorted by size.

        A bar is the % change of the output (band energy for L_FE) per % change of the
        parameter. Returns the matplotlib figure (``fig.savefig("tornado.png")``).
        """
        # lazy: matplotlib.pyplot costs ~1 s at import
        import matplotlib.pyplot as plt

        # lazy: rbjax.plot imports matplotlib (0.1–0.2 s; pyplot ~1 s)
        from ... import plot as _plot  # noqa: F401  (selects a headless backend when needed)

        outputs = self.outputs if outputs is None else tuple(outputs)
        unknown = set(outputs) - set(self.outputs)
        if unknown:
            raise ValueError(
                f"outputs {sorted(unknown)} are not known; valid: {', '.join(self.outputs)}"
            )
        n = len(self.height_m)
        if not (isinstance(height_index, (int, np.integer)) and 0 <= height_index < n):
            raise ValueError(
                f"height_index={height_index!r} is outside the valid range: "
                f"an integer in [0, {n - 1}]"
            )
        i = int(height_index)
        el = self.elasticity
        ncols = min(3, len(outputs))
        nrows = math.ceil(len(outputs) / ncols)
        fig, axes = plt.subplots(
            nrows,
            ncols,
            squeeze=False,
            layout="constrained",
            figsize=figsize or (4.0 * ncols, 0.35 * len(self.parameters) * nrows + 1.2 * nrows),
        )
        for ax, o in zip(axes.flat, outputs):
            vals = np.array([el[o][p][i] for p in self.parameters])
            order = np.argsort(np.abs(np.nan_to_num(vals)))
            colors = ["tab:red" if v < 0 else "tab:blue" for v in vals[order]]
            ax.barh(np.arange(len(order)), vals[order], color=colors)
            ax.set_yticks(np.arange(len(order)), [self.parameters[k] for k in order])
            ax.axvline(0.0, color="k", lw=0.8)
            label = f"L_FE {o[4:-3]} Hz (energy)" if is_lfe(o) else o
            ax.set_title(label, fontsize=9)
            ax.set_xlabel("elasticity (% per %)", fontsize=8)
            ax.tick_params(labelsize=8)
        for ax in list(axes.flat)[len(outputs) :]:
            ax.set_visible(False)
        fig.suptitle(
            f"Local sensitivity at drop height {self.height_m[i]:g} m ({self.status_name[i]})",
            fontsize=10,
        )
        return fig


@functools.lru_cache(maxsize=16)
def _local_jacobian_fn(
    names: tuple, wrt: tuple, solver: Solver, n_times: int, n_total: int, rate_Hz: float
) -> Callable:
    """Jitted (θ, ball, model) → (values, tangents per wrt parameter, status); one compile per
    setup."""

    def outputs(theta, ball, model):
        height, ball, model = assemble(theta, None, ball, model)
        result = simulate_model(height, ball, model, solver)
        out = {k: getattr(result, k) for k in SCALAR_OUTPUTS}
        if n_times:  # the force history on the contact window, zero-padded to the record (§2.4)
            force = trajectory(height, jnp.arange(n_times) / rate_Hz, ball, model, solver).force_N
            force = jnp.pad(force, ((0, 0), (0, n_total - n_times)))
            lfe = lfe_octave_dB(force, rate_Hz)
            out.update({name: lfe[:, j] for j, name in enumerate(lfe_output_names())})
        return out, result.status

    def fn(theta, ball, model):
        def tangent(i):
            return {
                k: jnp.where(i == wrt.index(k), 1.0, 0.0) * jnp.ones_like(v)
                if k in wrt
                else jnp.zeros_like(v)
                for k, v in theta.items()
            }

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
        model: an ``rbjax.Model`` (default ``Model()``), e.g. from
            ``rbjax.terms.serialize.load_params``.
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
    model = model_from_shortcuts("local_sensitivity", model, {})
    valid = parameter_names(model=model)
    wrt = (
        valid
        if wrt is None
        else tuple(
            dict.fromkeys(
                canonical_name(w, model) for w in ([wrt] if isinstance(wrt, str) else wrt)
            )
        )
    )
    if not wrt:
        raise ValueError(f"wrt is empty; valid parameters: {', '.join(valid)}")
    wrt = tuple(p for p in valid if p in wrt)  # a canonical order: one compiled program per set
    solver = dataclasses.replace(Solver() if solver is None else solver, adjoint="forward")

    n_times = n_total = 0
    if lfe:
        n_total = int(round(rate_Hz * duration_s))
        tc = np.asarray(simulate_model(heights, ball, model, solver).contact_time_s)
        longest = float(np.nanmax(tc)) if np.any(np.isfinite(tc)) else 0.0
        n_times = min(n_total, int(math.ceil(longest * rate_Hz)) + 2)

    ball_arrays = ball.as_arrays()
    theta = {
        row.name: jnp.asarray(row.value, dtype=jnp.float64)
        for row in parameter_table(1.0, ball, model)
    }
    theta["height_m"] = jnp.asarray(heights)
    fn = _local_jacobian_fn(valid, wrt, solver, n_times, n_total, float(rate_Hz))
    values, tangents, status = fn(theta, ball_arrays, model)

    status = np.asarray(status).astype(int)
    bad = status != 0
    mask = lambda x: np.where(  # noqa: E731
        bad, np.nan, np.broadcast_to(np.asarray(x, dtype=float), heights.shape)
    )
    outputs = SCALAR_OUTPUTS + (lfe_output_names() if lfe else ())
    return Sensitivity(
        height_m=heights,
        parameters=wrt,
        outputs=outputs,
        values={o: mask(values[o]) for o in outputs},
        parameter_values={
            p: np.broadcast_to(np.asarray(theta[p], dtype=float), heights.shape).copy() for p in wrt
        },
        jacobian={o: {p: mask(tangents[o][j]) for j, p in enumerate(wrt)} for o in outputs},
        status=status,
    )

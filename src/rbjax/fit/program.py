"""The fit as one compiled JAX program: prediction through the measuring chain, residuals, and
optimistix Levenberg–Marquardt (or Gauss–Newton) with exact forward-mode Jacobians.

The program depends only on the model's *structure* (which terms exist) and the data's shape;
everything else is a runtime value: the parameter values, which of them are free (a mask), the
records in the fit (a mask), the extra residual weights, the ν prior. So every candidate of a
model selection, embedded in one shared structure whose unused terms are held at their off
values, and every cross-validation fold run through the same compiled program, and the
program can be exported and kept on disk (no host callback; see :mod:`rbjax.fit.program_store`).

Residuals r(θ) (all rows always present; rows of records outside the fit are 0):

- history rows (F_pred,k(t_i) − F_meas,k(t_i))·w_k for every ``decimate``-th sample, w_k = 1/σ_k;
- ``extra_weights``: w_tc(t_c,pred/t_c,meas − 1), w_pk(F̂_pred/F̂_meas − 1) per record and
  w_L(ΔL_FE) per record and octave band (paper Eq. 11);
- the ν prior row u·(ν − mean)/std (u = 0 without a prior).

The optimiser works in whitened coordinates u: φ = φ_c + W u, θ = where(free, T(φ), θ_held)
with T the per-parameter transforms (log, interval, identity) and W chosen on the host from
the Jacobian at φ_c. The residual function is a ``custom_jvp`` whose tangent rule computes the
whole Jacobian J_θ once by ``jax.jacfwd`` (the model is traced once) and returns J_u du; J_θ
also comes back as auxiliary output for the uncertainties. The predicted forces come from the
sampled path (:mod:`rbjax.fit.record_forces`: fixed steps at the records' own samples, only the
physical columns carried through the solve) or, with ``Structure.path == "ode"``, from the
diffrax ODE with its events (:func:`sample_force`). The optimiser is vmapped over a batch of
lanes, each with its own free mask, constants and weights (the starts of a fit; or the fits of
a model selection, gathered by :mod:`rbjax.fit.batching`; :meth:`rbjax.fit.problem.Problem.
run_batch` sends one lane a call on a CPU); a lane with an infinite tolerance only evaluates
(one Jacobian, no step taken).
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import equinox as eqx
import jax
import jax.extend
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx

from ..solve.simulate import trajectory
from ..spectrum.filters import sosfilt_jax
from .program_store import load_or_export
from .record_forces import ball_and_model, record_forces
from .records import pulse_features

OPTIMIZERS = ("lm", "gauss-newton")


def sample_force(height_m, tau_s, rate_Hz, ball, model, solver):
    """The floor force at sample times τ_i (from first contact), continuous in the onset.

    Damped models and the ``momentum`` blocked force jump at first contact (c·v0, (M/2R)v0²),
    so a point sample F(t_i − s) would jump as the onset s moves across a sample, and the
    residual would be discontinuous in s. The sample whose interval [τ_i − Δ/2, τ_i + Δ/2]
    (Δ = 1/rate) contains the contact start takes the in-contact fraction of that interval
    times the force at the midpoint of the in-contact part (the box average of the jump);
    every other sample is the point value F(τ_i). Continuous and piecewise smooth in s.
    """

    half = 0.5 / rate_Hz
    inside = jnp.clip((tau_s + half) * rate_Hz, 0.0, 1.0)
    midpoint = 0.5 * (jnp.maximum(tau_s - half, 0.0) + tau_s + half)
    return inside * trajectory(height_m, midpoint, ball, model, solver).force_N


class Structure(eqx.Module):
    """Everything static about a fit program (hashable: the cache key of the compiled program)."""

    treedef: object = eqx.field(static=True)
    physical_positions: tuple = eqx.field(static=True)
    constant_positions: tuple = eqx.field(static=True)
    specs: tuple = eqx.field(static=True)
    n_records: int = eqx.field(static=True)
    n_samples: int = eqx.field(static=True)
    rate_Hz: float = eqx.field(static=True)
    filtered: bool = eqx.field(static=True)
    height_error: bool = eqx.field(static=True)
    decimate: int = eqx.field(static=True)
    poisson_index: int = eqx.field(static=True)
    solver: object = eqx.field(static=True)
    #: ``"samples"``: the force at the record's samples by fixed steps
    #: (:mod:`rbjax.fit.record_forces`); ``"ode"``: the diffrax ODE with its events, every column
    #: carried through it (moving floors).
    path: str = eqx.field(static=True, default="samples")
    #: the sampled path's most Runge–Kutta steps per sample (those of the fit range's fastest
    #: corner); each evaluation takes the count its parameters need, up to this
    #: (:func:`rbjax.solve.record_samples.substeps_at`)
    max_substeps: int = eqx.field(static=True, default=2)
    #: False when no extra weight is given: the feature rows are then 0 and their Jacobian is
    #: not computed (the features are still returned, for the onsets and the report).
    feature_rows: bool = eqx.field(static=True, default=True)


def _unpack(s: Structure, theta, constants):
    p, k = len(s.physical_positions), s.n_records
    ball, model = ball_and_model(s, theta[:p], constants)
    shifts = theta[p : p + k]
    dh = theta[p + k : p + 2 * k] if s.height_error else jnp.zeros(k)
    return ball, model, shifts, dh


def predict(s: Structure, theta, constants, data):
    """(force (K, N) through the measuring chain, features (K, 3 + 6)) at θ."""
    if s.path == "samples":
        force = record_forces(s, theta, constants, data["heights"])
    else:
        ball, model, shifts, dh = _unpack(s, theta, constants)
        times = jnp.arange(s.n_samples) / s.rate_Hz
        force = jax.vmap(
            lambda h, sh: sample_force(h, times - sh, s.rate_Hz, ball, model, s.solver)
        )(data["heights"] + dh, shifts)
    if s.filtered:
        force = sosfilt_jax(data["sos"], force)
    feats = pulse_features(
        force if s.feature_rows else jax.lax.stop_gradient(force), s.rate_Hz, int(round(s.rate_Hz))
    )
    return force, feats


def residuals(s: Structure, theta, constants, data, weights):
    """The residual vector (see the module docstring) and (force, features)."""
    force, feats = predict(s, theta, constants, data)
    inside = weights["fit_mask"]
    hist = jnp.where(inside[:, None], (force - data["measured"]) * weights["record"][:, None], 0.0)
    rows = [hist[:, :: s.decimate].reshape(-1)]
    meas = data["features"]
    tc = (feats[:, 1] - feats[:, 0]) / (meas[:, 1] - meas[:, 0]) - 1.0
    rows.append(jnp.where(inside, weights["contact_time"] * tc, 0.0))
    rows.append(jnp.where(inside, weights["peak_force"] * (feats[:, 2] / meas[:, 2] - 1.0), 0.0))
    rows.append(
        jnp.where(inside[:, None], weights["lfe"] * (feats[:, 3:] - meas[:, 3:]), 0.0).reshape(-1)
    )
    mean, std, unit = weights["prior"][0], weights["prior"][1], weights["prior"][2]
    rows.append(jnp.atleast_1d(unit * (theta[s.poisson_index] - mean) / std))
    return jnp.concatenate(rows), (force, feats)


def _theta_of_phi(s: Structure, phi, free, held):
    natural = jnp.stack([spec.from_unconstrained(phi[i]) for i, spec in enumerate(s.specs)])
    slope = jnp.stack([spec.slope(phi[i]) for i, spec in enumerate(s.specs)])
    return jnp.where(free, natural, held), jnp.where(free, slope, 0.0)


@functools.partial(jax.jit, static_argnums=0)
def _value_and_jac(s: Structure, u, phi_c, w, free, held, constants, data, weights):
    """r, dr/du and the auxiliary (r, dr/dθ, force, features) at u, by ``jax.jacfwd`` in θ.

    Traced once per program (see :func:`compiled`).
    """
    theta, slope = _theta_of_phi(s, phi_c + w @ u, free, held)

    def f(t):
        r, (force, feats) = residuals(s, t, constants, data, weights)
        return r, (r, force, feats)

    jac, (r, force, feats) = jax.jacfwd(f, has_aux=True)(theta)
    return r, (jac * slope[None, :]) @ w, (r, jac, force, feats)


class ProgramOutput(NamedTuple):
    """What the fit program returns for a batch of lanes (each field with a leading lane axis).

    Attributes:
        u: the optimum in whitened coordinates (0 where only evaluated).
        successful: the optimiser converged (where only evaluated: the residuals are finite).
        max_steps_reached: the optimiser stopped at its step budget.
        steps: optimiser steps taken.
        r: the residuals at the last accepted point.
        jac_theta: dr/dθ there.
        force: the predicted force through the measuring chain there (K, N).
        features: onset, end of contact, peak and octave L_FE there (K, 3 + 6).
    """

    u: np.ndarray
    successful: np.ndarray
    max_steps_reached: np.ndarray
    steps: np.ndarray
    r: np.ndarray
    jac_theta: np.ndarray
    force: np.ndarray
    features: np.ndarray


@functools.lru_cache(maxsize=8)
def compiled(s: Structure, optimizer: str, max_steps: int):
    """The jitted fit program of a structure (cached in this process; :func:`run_program` also
    keeps it on disk through :mod:`rbjax.fit.program_store`).

    ``run(phi_c, w, free, held, constants, data, weights, atol)``, vmapped over lanes (every
    argument but ``data`` has a leading lane axis) → a dict of the fields of
    :class:`ProgramOutput`. A lane with ``atol = inf`` only evaluates at φ_c: the optimiser's
    first step evaluates there and stops, as every step it could take is within tolerance, so
    its outputs are those at φ_c, u = 0 (see :func:`run_program`). The model is in the program
    once (an evaluate-only branch beside the optimiser held a second copy: 40 % of the program
    and a quarter of its compile time).
    """

    def run(phi_c, w, free, held, constants, data, weights, atol):
        # Trace the model and its Jacobian once, here; the optimiser's init and step replay the
        # jaxpr (replaying costs no Python, retracing diffrax costs seconds each time).
        args = (phi_c, w, free, held, constants, data, weights)
        u0 = jnp.zeros_like(phi_c)
        closed, out_shape = jax.make_jaxpr(functools.partial(_value_and_jac, s), return_shape=True)(
            u0, *args
        )
        replay = jax.extend.core.jaxpr_as_fun(closed)
        out_tree = jax.tree_util.tree_structure(out_shape)

        def value_and_jac(u):
            return jax.tree_util.tree_unflatten(
                out_tree, replay(*jax.tree_util.tree_leaves((u, args)))
            )

        @jax.custom_jvp
        def fn(u):
            r, _, aux = value_and_jac(u)
            return r, aux

        @fn.defjvp
        def fn_jvp(primals, tangents):
            (u,), (du,) = primals, tangents
            r, jac_u, aux = value_and_jac(u)
            return (r, aux), (jac_u @ du, jax.tree_util.tree_map(jnp.zeros_like, aux))

        if optimizer == "lm":
            # optimistix widens the trust region only when the actual reduction is > 99 % of the
            # predicted one; in this large-residual problem that rarely holds and LM crawls along
            # correlated directions, so widen it from 50 % on (textbook values).
            solver = eqx.tree_at(
                lambda x: x.search,
                optx.LevenbergMarquardt(rtol=1e-12, atol=atol, norm=optx.rms_norm),
                optx.ClassicalTrustRegion(high_cutoff=0.5, low_cutoff=1e-4),
            )
        else:  # held parameters give zero Jacobian columns: a least-squares (SVD) step
            solver = optx.GaussNewton(
                rtol=1e-12, atol=atol, norm=optx.rms_norm, linear_solver=lx.SVD()
            )

        def optimise(_):
            sol: optx.Solution = optx.least_squares(
                lambda u, _: fn(u), solver, u0, None, has_aux=True, max_steps=max_steps, throw=False
            )
            r, jac, force, feats = sol.aux
            return {
                "u": sol.value,
                "successful": sol.result == optx.RESULTS.successful,
                "max_steps_reached": sol.result == optx.RESULTS.max_steps_reached,
                "steps": sol.stats["num_steps"],
                "r": r,
                "jac_theta": jac,
                "force": force,
                "features": feats,
            }

        return optimise(None)

    # Independent fits (starts, candidates, folds) as lanes: every argument but the data has a
    # leading lane axis (each lane its own free mask and constants).
    return jax.jit(jax.vmap(run, in_axes=(0, 0, 0, 0, 0, None, 0, 0)))


#: The per-lane arguments of the program, in its order (``data`` comes apart).
LANE_ARGS = ("phi_c", "w", "free", "held", "constants", "weights", "atol")


def run_program(
    s: Structure, optimizer: str, max_steps: int, lanes: dict, data, evaluate_only=False
) -> ProgramOutput:
    """Call the compiled program on a batch of B lanes: ``lanes`` holds each of
    :data:`LANE_ARGS` with a leading axis B (``weights`` a dict of such arrays); ``data`` is
    shared by the lanes. NumPy in, NumPy out. ``evaluate_only``: the residuals and Jacobian at
    φ_c of every lane, no optimiser step (every lane's ``atol`` is infinite; ``steps`` 0)."""
    f64 = lambda x: jnp.asarray(x, dtype=jnp.float64)  # noqa: E731
    weights = {
        k: (jnp.asarray(v, dtype=bool) if k == "fit_mask" else f64(v))
        for k, v in lanes["weights"].items()
    }
    args = (
        f64(lanes["phi_c"]),
        f64(lanes["w"]),
        jnp.asarray(lanes["free"], dtype=bool),
        f64(lanes["held"]),
        f64(lanes["constants"]),
        jax.tree_util.tree_map(f64, data),
        weights,
        f64(np.full(np.shape(lanes["atol"]), np.inf) if evaluate_only else lanes["atol"]),
    )
    fn = load_or_export(
        ("fit", s, optimizer, max_steps), lambda: compiled(s, optimizer, max_steps), args
    )
    out = {k: np.asarray(v) for k, v in fn(*args).items()}
    if evaluate_only:  # the one step evaluated at φ_c and was not taken
        out["steps"] = np.zeros_like(out["steps"])
    return ProgramOutput(**{k: out[k] for k in ProgramOutput._fields})


def run_lanes(key, lanes: dict, data) -> ProgramOutput:
    """One batch of a :class:`rbjax.fit.batching.FitBatcher`: ``key`` is (structure, optimiser,
    step budget, evaluate-only, the data's digest) (see :meth:`rbjax.fit.problem.Problem.
    run_batch`)."""
    s, optimizer, max_steps, evaluate_only = key[:4]
    return run_program(s, optimizer, max_steps, lanes, data, evaluate_only)

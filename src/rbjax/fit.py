"""Fitting the rubber's properties to measured blocked-force histories.

The paper's elastic model (Eqs. 1–10) with the literature values E = 1.6 MPa, ν = 0.5 (§4)
is too soft and too symmetric for measured pulses (§5: the measured contact is shorter and
rises faster than it falls). Here E, ν and the parameters of a damping extension are fitted
to force histories of several drop heights at once.

What is compared (the measuring chain is modelled, not inverted): for every record k the
model's floor force is sampled at the record's sample times shifted by an onset time s_k,
F_model(t_i − s_k) (``rbjax.trajectory``, differentiable), and passed through the same causal
4th-order Butterworth low-pass as the data (``rbjax.filters.sosfilt_jax``, JIS A 1418-2 /
the paper's §3 measuring chain: 1250 Hz for the shipped emulated recordings). The residual
vector is (F_pred − F_measured)/σ_k over all samples of all fitted records (σ_k: the noise
rms of record k, or its peak with ``scale="peak"``), optionally with weighted extra rows
for contact time, peak force and octave-band L_FE (paper Eq. 11).

Parameters and constraints (transforms, so that the optimiser is unconstrained):
E = exp(φ), ν = −1 + 1.5·sigmoid(φ) (−1 < ν < 0.5), damping parameters and β = exp(φ) > 0,
onset shifts s_k free, optional drop-height errors Δh_k = b·tanh(φ) with |Δh_k| < b = 1 cm.

Identifiability: E and ν enter the model only through the Reissner stiffness
k = 4Eh²/(R√(3(1−ν²))) (Eqs. 1–3, corrected); the gas force (Eq. 4) does not involve them
and the damping terms scale with k. So ∂r/∂E and ∂r/∂ν are parallel and only
E/√(1−ν²) is determined. This is detected from the Jacobian (the angle between the two
columns, the condition number of the column-scaled Jacobian) and said in
``FitResult.identifiability``; ν is then held at a stated value (default 0.5, the paper's,
§4; note 0.5 is the bound of the transform, so it is held, not fitted) or given a prior.

Optimiser: the residual function and its exact Jacobian (``jax.jacfwd`` through diffrax,
``Solver(adjoint="forward")``) are one jitted function, compiled once per model structure
and data shape (cached); the default ``optimistix.LevenbergMarquardt`` (or ``GaussNewton``)
calls it through ``jax.pure_callback`` with a ``custom_jvp`` that returns the exact
Jacobian, so the optimiser's own program stays small and cheap to compile. optax Adam and
L-BFGS are selectable. One progress line per function evaluation goes to stderr.

Uncertainties: Gauss–Newton covariance C = τ σ̂² (JᵀJ)⁻¹ in the transformed coordinates,
σ̂² = RSS/(N − p). The residuals are correlated in time (low-passed noise, and the
systematic misfit of an approximate model), so N samples carry only N_eff = N/τ
independent ones; τ = 1 + 2 Σ ρ_j is the integrated autocorrelation of the residuals
(ρ summed while positive, pooled over records). 95 % intervals are φ ± 1.96σ_φ mapped
through the transform (so they respect the bounds); standard deviations are the
delta-method values in natural units.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _x64  # noqa: F401  (float64 on)
from ._progress import progress
from .ball import JIS_RUBBER_BALL, Ball
from .forces import (
    DAMPING_MODELS,
    CubicStiffening,
    HuntCrossley,
    reissner_stiffness_N_per_m,
)
from .impact import G_N_PER_KG
from .model import Model, Solver
from .spectrum import OCTAVE_BANDS

__all__ = [
    "MODEL_NAMES",
    "OPTIMIZERS",
    "FitData",
    "FitResult",
    "ParameterEstimate",
    "prepare_data",
    "load_data",
    "fit",
    "predict",
    "Prediction",
    "model_histories",
    "parameter_names",
    "record_features",
]

#: Damping models that can be fitted (paper §2's elastic model is ``paper``); append
#: ``+stiffening`` for the cubic stiffening of the shell, F_B = kδ(1 + β(δ/h)²).
MODEL_NAMES = ("paper", "kelvin-voigt", "hunt-crossley", "zener")
STIFFENING_SUFFIX = "+stiffening"
OPTIMIZERS = ("lm", "gauss-newton", "adam", "lbfgs")
SCALES = ("noise", "peak")
#: Level (fraction of the peak) at which contact start and end are read from a history:
#: the same estimator is applied to measured and predicted (filtered) histories.
FEATURE_FRACTION = 0.05
#: Bound b of the optional drop-height errors, |Δh| < b (m).
HEIGHT_ERROR_BOUND_M = 0.01

_DAMPING_PARAMS = {
    "paper": (),
    "kelvin-voigt": ("damping_Ns_per_m",),
    "hunt-crossley": ("alpha_s_per_m",),
    "zener": ("stiffness_ratio", "relaxation_time_s"),
}
_FIXED_BALL_FIELDS = ("radius_m", "wall_m", "mass_kg")
_UNITS = {
    "youngs_Pa": "Pa",
    "poisson": "1",
    "damping_Ns_per_m": "N s/m",
    "alpha_s_per_m": "s/m",
    "stiffness_ratio": "1",
    "relaxation_time_s": "s",
    "beta": "1",
    "radius_m": "m",
    "wall_m": "m",
    "mass_kg": "kg",
}


# ----------------------------------------------------------------------------------------------
# data


@dataclasses.dataclass(frozen=True, eq=False)
class FitData:
    """Conditioned records ready for fitting: one row per record, all on one time grid.

    Attributes:
        sources: the file(s) behind each record (several for a per-height average).
        height_m: nominal drop height of each record, m.
        force_N: (n_records, n_samples) baseline-free force, onset at ``onset_s``.
        rate_Hz: sampling rate.
        onset_s: onset (5 % of the peak on the rising edge) of each record, s.
        noise_rms_N: noise rms of each record (of the average: per-drop rms / √n_drops).
        n_drops: drops behind each record.
        lowpass_Hz: cutoff of the causal 4th-order Butterworth measuring chain the records
            went through (applied to the predictions too), or None (no filter).
    """

    sources: tuple
    height_m: np.ndarray
    force_N: np.ndarray
    rate_Hz: float
    onset_s: np.ndarray
    noise_rms_N: np.ndarray
    n_drops: np.ndarray
    lowpass_Hz: float | None

    @property
    def n_records(self) -> int:
        return int(self.force_N.shape[0])

    @property
    def n_samples(self) -> int:
        return int(self.force_N.shape[1])

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_samples) / self.rate_Hz

    @property
    def heights_m(self) -> np.ndarray:
        """The distinct drop heights, ascending."""
        return np.unique(self.height_m)

    def replace(self, **changes) -> "FitData":
        return dataclasses.replace(self, **changes)


def load_data(paths_or_dir, *, lowpass_Hz="auto", **load_kwargs):
    """Read recordings with ``rbjax.data.load``; resolve the measuring chain's low-pass.

    ``lowpass_Hz="auto"``: the cutoff the recordings declare (all equal), else, for the
    shipped emulated recordings (``rbjax.data.examples_dir()``), their documented 1250 Hz;
    else none. A number or None overrides.
    """
    from . import data

    items = [paths_or_dir] if isinstance(paths_or_dir, (str, Path)) else list(paths_or_dir)
    recs = data.load(items, **load_kwargs)
    if lowpass_Hz == "auto":
        declared = {r.lowpass_Hz for r in recs}
        if declared == {None}:
            examples = data.examples_dir().resolve()
            files = [Path(p).resolve() for p in items]
            inside = all(p == examples or examples in p.parents for p in files)
            if inside:
                recs = [r.replace(lowpass_Hz=data.EXAMPLES_LOWPASS_HZ) for r in recs]
        return recs
    return [r.replace(lowpass_Hz=None if lowpass_Hz is None else float(lowpass_Hz)) for r in recs]


def prepare_data(
    recordings,
    *,
    average: bool = True,
    window_s: float = 0.03,
    pre_onset_s: float = 0.003,
    lowpass_Hz="auto",
) -> FitData:
    """Condition recordings for fitting (``rbjax.data.condition``) and stack them.

    Each record keeps ``window_s`` seconds starting ``pre_onset_s`` before its onset
    (baseline removed, sub-sample onset alignment). With ``average=True`` the drops of one
    height are averaged coherently in the frequency domain (``rbjax.data.average``, the
    paper's §3 averaging), one record per height; else every drop is a record.

    ``recordings``: Recording objects, or paths/a directory (read by :func:`load_data`).
    ``lowpass_Hz``: ``"auto"`` (as declared by the recordings), a cutoff in Hz, or None.
    """
    from . import data

    if isinstance(recordings, FitData):
        return recordings
    if isinstance(recordings, (str, Path)) or (
        isinstance(recordings, Sequence) and recordings and isinstance(recordings[0], (str, Path))
    ):
        recs = load_data(recordings, lowpass_Hz=lowpass_Hz)
    else:
        recs = list(recordings)
        if lowpass_Hz != "auto":
            recs = [r.replace(lowpass_Hz=None if lowpass_Hz is None else float(lowpass_Hz)) for r in recs]
    if not recs:
        raise data.DataError("no recordings to fit")
    _check_positive("window_s", window_s)
    _check_positive("pre_onset_s", pre_onset_s)
    for r in recs:
        if r.height_m is None:
            raise data.DataError(f"{r.source}: unknown drop height; name the file hNNN_... or pass height_m")
    cutoffs = {r.lowpass_Hz for r in recs}
    if len(cutoffs) > 1:
        listing = ", ".join(f"{r.source}: {r.lowpass_Hz}" for r in recs)
        raise data.DataError(f"recordings declare different measuring-chain low-passes ({listing})")
    cutoff = cutoffs.pop()
    noise = {id(r): r.noise_rms_N for r in recs}
    conditioned = [(data.condition(r, window_s=window_s, pre_onset_s=pre_onset_s), noise[id(r)]) for r in recs]
    rows = []
    if average:
        groups: dict[float, list] = {}
        for rec, sigma in conditioned:
            groups.setdefault(round(rec.height_m, 3), []).append((rec, sigma))
        for h in sorted(groups):
            members = groups[h]
            avg = data.average([m[0] for m in members]) if len(members) > 1 else members[0][0]
            sigma = math.sqrt(np.mean([m[1] ** 2 for m in members]) / len(members))
            rows.append((tuple(m[0].source for m in members), h, avg, sigma, len(members)))
    else:
        for rec, sigma in sorted(conditioned, key=lambda m: (m[0].height_m, m[0].source)):
            rows.append(((rec.source,), rec.height_m, rec, sigma, 1))
    n = min(r[2].n_samples for r in rows)
    return FitData(
        sources=tuple(r[0] for r in rows),
        height_m=np.array([r[1] for r in rows], dtype=float),
        force_N=np.stack([r[2].force_N[:n] for r in rows]),
        rate_Hz=float(rows[0][2].rate_Hz),
        onset_s=np.array([r[2].onset_s for r in rows], dtype=float),
        noise_rms_N=np.array([r[3] for r in rows], dtype=float),
        n_drops=np.array([r[4] for r in rows], dtype=int),
        lowpass_Hz=cutoff,
    )


def _check_positive(name, value):
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(f"{name}={value!r} must be a positive finite number (valid range: (0, inf))")


# ----------------------------------------------------------------------------------------------
# features measured the same way on data and predictions


def _features(force_N, rate_Hz: float, n_pad: int, fraction: float = FEATURE_FRACTION):
    """(t_rise, t_fall, peak, L_FE × 6 octave bands) of histories (..., n), differentiable.

    t_rise/t_fall: where the force crosses ``fraction`` × peak on the rising edge (last
    sample below the level before the peak) and the falling edge (first sample below it
    after the peak), by linear interpolation (NaN where the record has no such sample); the
    contact time is t_fall − t_rise. L_FE:
    paper Eq. 11 in octave bands (``rbjax.spectrum.lfe_octave_dB``) of the record
    zero-padded to ``n_pad`` samples (1 s, as in the paper's §2.4).
    """
    from .spectrum import lfe_octave_dB

    x = jnp.asarray(force_N)
    n = x.shape[-1]
    idx = jnp.arange(n)
    ip = jnp.argmax(x, axis=-1)[..., None]
    peak = jnp.max(x, axis=-1)
    level = fraction * peak[..., None]
    take = lambda i: jnp.take_along_axis(x, i, axis=-1)  # noqa: E731
    before = (idx < ip) & (x < level)
    i = jnp.clip(n - 1 - jnp.argmax(before[..., ::-1], axis=-1)[..., None], 0, n - 2)
    xi, xi1 = take(i), take(i + 1)
    t_rise = (i + (level - xi) / (xi1 - xi))[..., 0] / rate_Hz
    after = (idx > ip) & (x < level)
    j = jnp.clip(jnp.argmax(after, axis=-1)[..., None], 1, n - 1)
    xj, xj1 = take(j), take(j - 1)
    t_fall = (j - 1 + (xj1 - level) / (xj1 - xj))[..., 0] / rate_Hz
    # no crossing inside the record (pulse cut off at either end): NaN, not a clipped index
    t_rise = jnp.where(jnp.any(before, axis=-1), t_rise, jnp.nan)
    t_fall = jnp.where(jnp.any(after, axis=-1), t_fall, jnp.nan)
    padded = jnp.pad(x, [(0, 0)] * (x.ndim - 1) + [(0, max(0, n_pad - n))])
    lfe = lfe_octave_dB(padded, rate_Hz)
    return jnp.concatenate([t_rise[..., None], t_fall[..., None], peak[..., None], lfe], axis=-1)


@functools.lru_cache(maxsize=8)
def _features_jit(rate_Hz: float, n_pad: int):
    return jax.jit(lambda x: _features(x, rate_Hz, n_pad))


def _n_pad(rate_Hz: float) -> int:
    return int(round(rate_Hz * 1.0))


def record_features(force_N, rate_Hz: float) -> dict:
    """Contact time, peak force and octave-band L_FE of histories (..., n) as measured.

    The estimator of :func:`fit` (5 % of the peak, linear interpolation; L_FE of the record
    zero-padded to 1 s); returns NumPy arrays ``contact_time_s``, ``peak_force_N``,
    ``onset_s`` and ``lfe_octave_dB`` (..., 6).
    """
    f = np.asarray(_features_jit(float(rate_Hz), _n_pad(rate_Hz))(jnp.asarray(force_N, dtype=jnp.float64)))
    return {
        "onset_s": f[..., 0],
        "contact_time_s": f[..., 1] - f[..., 0],
        "peak_force_N": f[..., 2],
        "lfe_octave_dB": f[..., 3:],
    }


# ----------------------------------------------------------------------------------------------
# model structure and parameter layout


def _parse_model(name: str) -> tuple[str, bool]:
    if not isinstance(name, str):
        raise ValueError(f"model={name!r} must be a model name; valid: {', '.join(_all_model_names())}")
    base, stiff = (name[: -len(STIFFENING_SUFFIX)], True) if name.endswith(STIFFENING_SUFFIX) else (name, False)
    if base not in MODEL_NAMES:
        raise ValueError(f"model={name!r} is not a known model; valid: {', '.join(_all_model_names())}")
    return base, stiff


def _all_model_names():
    return MODEL_NAMES + tuple(m + STIFFENING_SUFFIX for m in MODEL_NAMES)


def parameter_names(model: str) -> tuple[str, ...]:
    """The fitted physical parameters of a model name, e.g. ``("youngs_Pa", "poisson",
    "stiffness_ratio", "relaxation_time_s")`` for ``zener``."""
    base, stiff = _parse_model(model)
    return ("youngs_Pa", "poisson") + _DAMPING_PARAMS[base] + (("beta",) if stiff else ())


def _transform_kind(name: str) -> str:
    if name == "poisson":
        return "poisson"
    if name.startswith("shift"):
        return "identity"
    if name.startswith("dh"):
        return "bounded"
    return "log"


def _to_phi(kind, theta):
    if kind == "log":
        return math.log(theta)
    if kind == "poisson":
        s = (theta + 1.0) / 1.5
        s = min(max(s, 1e-12), 1 - 1e-12)
        return math.log(s / (1 - s))
    if kind == "bounded":
        return math.atanh(max(min(theta / HEIGHT_ERROR_BOUND_M, 1 - 1e-12), -1 + 1e-12))
    return theta


def _from_phi(kind, phi):
    """(θ, dθ/dφ) for arrays φ."""
    phi = np.asarray(phi, dtype=float)
    if kind == "log":
        v = np.exp(phi)
        return v, v
    if kind == "poisson":
        s = 1.0 / (1.0 + np.exp(-phi))
        return -1.0 + 1.5 * s, 1.5 * s * (1 - s)
    if kind == "bounded":
        t = np.tanh(phi)
        return HEIGHT_ERROR_BOUND_M * t, HEIGHT_ERROR_BOUND_M * (1 - t**2)
    return phi, np.ones_like(phi)


@functools.lru_cache(maxsize=32)
def _compiled_predictor(base, stiffening, gas, blocked_force, n_records, n_samples, rate_Hz, n_sections, height_error, solver):
    """The compiled prediction + exact Jacobian for one model structure and data shape.

    θ = [E, ν, damping…, (β), s_1..s_K, (Δh_1..Δh_K)] in natural units. Returns the
    ahead-of-time compiled ``f(θ, heights, (R, h, M), sos, times) -> (F, features, dF/dθ,
    dfeatures/dθ)`` with F the (filtered) floor force of every record at its sample times.
    Compiled ahead of time so that calls from the optimiser's host callback (another thread,
    another trace context) reuse it instead of compiling again.
    """
    n_damp = len(_DAMPING_PARAMS[base])
    n_pad = _n_pad(rate_Hz)
    from . import trajectory
    from .filters import sosfilt_jax

    def predict(theta, heights, geometry, sos, times):
        radius, wall, mass = geometry
        ball = Ball(radius_m=radius, wall_m=wall, mass_kg=mass, youngs_Pa=theta[0], poisson=theta[1])
        i = 2
        damping = None
        if base != "paper":
            damping = DAMPING_MODELS[base](*[theta[i + j] for j in range(n_damp)])
            i += n_damp
        stiff = None
        if stiffening:
            stiff = CubicStiffening(theta[i])
            i += 1
        shifts = theta[i : i + n_records]
        h = heights + theta[i + n_records : i + 2 * n_records] if height_error else heights
        model = Model(gas=gas, blocked_force=blocked_force, damping=damping, stiffening=stiff)
        force = jax.vmap(lambda hk, sk: _sample_force(hk, times - sk, rate_Hz, ball, model, solver, trajectory))(h, shifts)
        if n_sections:
            force = sosfilt_jax(sos, force)
        feats = _features(force, rate_Hz, n_pad)
        return (force, feats), (force, feats)

    def run(theta, heights, geometry, sos, times):
        (jf, jfeat), (force, feats) = jax.jacfwd(predict, has_aux=True)(theta, heights, geometry, sos, times)
        return force, feats, jf, jfeat

    n_theta = 2 + n_damp + int(stiffening) + n_records * (2 if height_error else 1)
    f64 = lambda *shape: jax.ShapeDtypeStruct(shape, jnp.float64)  # noqa: E731
    example = (f64(n_theta), f64(n_records), (f64(), f64(), f64()), f64(max(n_sections, 1), 6), f64(n_samples))
    return jax.jit(run).lower(*example).compile()


def _sample_force(height_m, tau_s, rate_Hz, ball, model, solver, trajectory):
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


def _fit_solver(solver):
    if solver is None:
        return Solver(adjoint="forward")
    if not isinstance(solver, Solver):
        raise ValueError(f"solver={solver!r} must be an rbjax.Solver")
    if solver.adjoint != "forward":
        solver = dataclasses.replace(solver, adjoint="forward")
    return solver


class _Layout:
    """Names, transforms and fixed values of the full parameter vector θ."""

    def __init__(self, model_name, n_records, height_error):
        base, stiff = _parse_model(model_name)
        self.base, self.stiffening = base, stiff
        self.physical = parameter_names(model_name)
        self.n_records = n_records
        self.height_error = height_error
        self.names = list(self.physical) + [f"shift[{k}]" for k in range(n_records)]
        if height_error:
            self.names += [f"dh[{k}]" for k in range(n_records)]
        self.kinds = [_transform_kind(n) for n in self.names]
        self.shift_slice = slice(len(self.physical), len(self.physical) + n_records)
        self.dh_slice = slice(self.shift_slice.stop, self.shift_slice.stop + n_records) if height_error else None

    def index(self, name):
        return self.names.index(name)


# ----------------------------------------------------------------------------------------------
# results


@dataclasses.dataclass(frozen=True)
class ParameterEstimate:
    """A fitted (or held) parameter: value, standard deviation, 95 % interval, unit."""

    value: float
    std: float
    ci95: tuple[float, float]
    unit: str
    fixed: bool = False

    def to_dict(self) -> dict:
        return {"value": self.value, "std": self.std, "ci95": list(self.ci95), "unit": self.unit, "fixed": self.fixed}


@dataclasses.dataclass(frozen=True, eq=False)
class FitResult:
    """The outcome of :func:`fit` (frozen). ``to_dict()`` is JSON-ready; ``plot(dir)`` draws it.

    Attributes:
        model_name: ``paper``, ``kelvin-voigt``, ``hunt-crossley``, ``zener`` (+``+stiffening``).
        ball, model: the fitted ``rbjax.Ball`` and ``rbjax.Model`` (``rbjax.simulate`` them).
        parameters: name → :class:`ParameterEstimate` (held ones with ``fixed=True``, std 0),
            plus ``effective_modulus_Pa`` = E/√(1−ν²), the combination the data determine.
        correlations: (names, matrix) of the free physical parameters.
        identifiability: plain-language statement of what the data determine.
        per_height: one dict per drop height: measured and fitted contact time, peak force and
            octave-band L_FE (same estimator on both, through the measuring chain), residual rms.
        residual_rms_N: rms of F_pred − F_measured over the fitted records.
        converged, message, iterations (function evaluations), optimizer.
        n_eff_factor: τ, the samples per independent residual (N_eff = N/τ).
        aic, bic: information criteria of the history residuals (see :func:`fit`).
        time_s, measured_N, predicted_N, heights_m, in_fit: the records, for plots and checks.
        theta: the full internal parameter vector (natural units; warm starts).
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

    @property
    def name(self) -> str:
        return self.model_name

    def to_dict(self) -> dict:
        """JSON-ready dict; ``ball``/``model`` in the ``rbjax.serialize`` format
        (``rbjax simulate --params FIT.json`` reproduces the fitted model)."""
        from .serialize import ball_to_dict, model_to_dict

        names, matrix = self.correlations
        return {
            "model_name": self.model_name,
            "blocked_force": self.blocked_force,
            "gas": self.gas,
            "ball": ball_to_dict(self.ball),
            "model": model_to_dict(self.model),
            "parameters": {k: v.to_dict() for k, v in self.parameters.items()},
            "correlations": {"names": list(names), "matrix": np.asarray(matrix).tolist()},
            "identifiability": self.identifiability,
            "per_height": [_plain(row) for row in self.per_height],
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
        }

    def summary(self) -> str:
        """A short human-readable report (parameters, identifiability, per-height table)."""
        from .commands import fmt, format_table

        lines = [f"model {self.model_name} (blocked force {self.blocked_force}, gas {self.gas}): {self.message}"]
        for k, p in self.parameters.items():
            if p.fixed:
                lines.append(f"  {k:22s} {p.value:.6g} {p.unit} (held)")
            else:
                lines.append(f"  {k:22s} {p.value:.6g} ± {p.std:.2g} {p.unit}  (95 %: {p.ci95[0]:.6g} … {p.ci95[1]:.6g})")
        lines.append("identifiability: " + self.identifiability)
        bands = OCTAVE_BANDS
        header = ["h (m)", "fit", "rms (N)", "t_c meas (ms)", "t_c fit (ms)", "peak meas (N)", "peak fit (N)"] + [f"ΔL {b}" for b in bands]
        rows = []
        for r in self.per_height:
            rows.append(
                [f"{r['height_m']:.2f}", "yes" if r["in_fit"] else "no", fmt(r["residual_rms_N"], ".2f"),
                 fmt(1e3 * r["measured"]["contact_time_s"], ".2f"), fmt(1e3 * r["fitted"]["contact_time_s"], ".2f"),
                 fmt(r["measured"]["peak_force_N"], ".0f"), fmt(r["fitted"]["peak_force_N"], ".0f")]
                + [fmt(x, "+.2f") for x in r["error"]["lfe_octave_dB"]]
            )
        lines.append(format_table(header, rows))
        return "\n".join(lines)

    def plot(self, out_dir) -> list[Path]:
        """Write ``histories.png`` (measured vs fitted with residuals), ``lfe_bands.png`` and
        ``correlations.png`` into ``out_dir``; return their paths."""
        import matplotlib.pyplot as plt

        from . import plot as _plot  # noqa: F401  (selects the Agg backend without a display)

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = []
        t_ms = self.time_s * 1e3
        n = len(self.heights_m)
        fig, axes = plt.subplots(2, 1, figsize=(7.5, 6.5), sharex=True, height_ratios=(3, 1), layout="constrained")
        colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, max(n, 1)))
        for k in range(n):
            label = f"{self.heights_m[k] * 100:.0f} cm" + ("" if self.in_fit[k] else " (held out)")
            axes[0].plot(t_ms, self.measured_N[k], color=colours[k], lw=0.8, alpha=0.6)
            axes[0].plot(t_ms, self.predicted_N[k], color=colours[k], lw=1.2, ls="--", label=label)
            axes[1].plot(t_ms, self.predicted_N[k] - self.measured_N[k], color=colours[k], lw=0.8)
        axes[0].set_ylabel("force (N)")
        axes[0].set_title(f"{self.model_name}: measured (solid) and fitted (dashed)")
        axes[0].legend(fontsize=8, ncol=2)
        axes[1].set_ylabel("fitted − measured (N)")
        axes[1].set_xlabel("time (ms)")
        paths.append(out / "histories.png")
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)

        bands = OCTAVE_BANDS
        fig, ax = plt.subplots(figsize=(7.0, 4.5), layout="constrained")
        x = np.arange(len(bands))
        for k, row in enumerate(self.per_height):
            ax.plot(x, row["measured"]["lfe_octave_dB"], "o-", color=colours[k], lw=0.8, label=f"{row['height_m'] * 100:.0f} cm")
            ax.plot(x, row["fitted"]["lfe_octave_dB"], "x--", color=colours[k], lw=1.2)
        ax.set_xticks(x, bands)
        ax.set_xlabel("octave band (Hz)")
        ax.set_ylabel("L_FE (dB re 1 N, T0 = 1 s)")
        ax.set_title("octave-band L_FE (Eq. 11): measured (o) and fitted (x)")
        ax.legend(fontsize=8, ncol=2)
        paths.append(out / "lfe_bands.png")
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)

        names, matrix = self.correlations
        fig, ax = plt.subplots(figsize=(5.0, 4.2), layout="constrained")
        m = np.asarray(matrix, dtype=float).reshape(len(names), len(names))
        im = ax.imshow(m, vmin=-1, vmax=1, cmap="RdBu_r")
        ax.set_xticks(range(len(names)), names, rotation=45, ha="right", fontsize=8)
        ax.set_yticks(range(len(names)), names, fontsize=8)
        for i in range(len(names)):
            for j in range(len(names)):
                ax.text(j, i, f"{m[i, j]:.2f}", ha="center", va="center", fontsize=8)
        fig.colorbar(im, ax=ax, label="correlation")
        ax.set_title("parameter correlations")
        paths.append(out / "correlations.png")
        fig.savefig(paths[-1], dpi=120)
        plt.close(fig)
        return paths


def _plain(x):
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_plain(v) for v in np.asarray(x).tolist()] if isinstance(x, np.ndarray) else [_plain(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


# ----------------------------------------------------------------------------------------------
# the objective on the host side


class _Objective:
    """Residual vector and exact Jacobian in the optimiser's whitened coordinates u.

    θ (natural units) = transform(φ); the free entries of φ are φ_c + W u, where the frame
    (φ_c, W) is set by :meth:`recentre`: W = R⁻¹ from the QR factorisation of the Jacobian
    J_φ at φ_c, so that J_u = J_φ W has orthonormal columns there (Gauss–Newton and the
    Levenberg–Marquardt damping then see a round problem; correlated parameters such as the
    Zener pair no longer form a narrow valley). Held entries stay at their values.
    """

    def __init__(self, problem, free, theta0, progress, label):
        self.p = problem
        self.free = np.asarray(free, dtype=int)
        self.theta0 = np.asarray(theta0, dtype=float).copy()  # held entries keep these exactly
        self.phi_c = np.array([_to_phi(kind, t) for kind, t in zip(problem.kinds, self.theta0)])
        self.w = np.eye(self.free.size)
        self.progress = progress
        self.label = label
        self.evaluations = 0
        self._cache = {}

    def phi(self, u):
        phi = self.phi_c.copy()
        phi[self.free] = self.phi_c[self.free] + self.w @ np.asarray(u, dtype=float)
        return phi

    def at_phi(self, phi):
        """(r, J_φ[:, free], θ, raw outputs) at φ (cached)."""
        phi = np.asarray(phi, dtype=float)
        key = phi.tobytes()
        if key in self._cache:
            return self._cache[key]
        theta, dtheta = self.p.theta_from_phi(phi)
        held = np.ones(theta.size, dtype=bool)
        held[self.free] = False
        theta[held] = self.theta0[held]
        out = self.p.evaluate(theta)
        r, jac_theta = self.p.residuals(out, theta)
        jac_phi = jac_theta[:, self.free] * dtheta[self.free][None, :]
        self.evaluations += 1
        if self.progress:
            cost = 0.5 * float(r @ r)
            free = set(self.free.tolist())
            shown = ", ".join(f"{n}={theta[i]:.5g}" for i, n in enumerate(self.p.layout.physical) if i in free)
            progress(f"{self.label} eval {self.evaluations}: cost {cost:.9g}, rms {self.p.history_rms_N(out):.3g} N, {shown}")
        if len(self._cache) > 8:
            self._cache.pop(next(iter(self._cache)))
        self._cache[key] = (r, jac_phi, theta, out)
        return self._cache[key]

    def __call__(self, u):
        r, jac_phi, theta, out = self.at_phi(self.phi(u))
        return r, jac_phi @ self.w, theta, out

    def recentre(self, u):
        """Move the frame to φ(u) and whiten with the Jacobian there; returns u = 0."""
        phi = self.phi(u)
        _, jac_phi, _, _ = self.at_phi(phi)
        self.phi_c = phi
        self.w = _whitening(jac_phi)
        return np.zeros(self.free.size)


def _whitening(jac, full=False) -> np.ndarray:
    """Inverse column norms of J (Marquardt's scaling); with ``full`` W = R⁻¹ (J = QR)."""
    norms = np.linalg.norm(jac, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    if not full:
        return np.diag(1.0 / norms)
    r = np.linalg.qr(jac / norms, mode="r")
    d = np.abs(np.diag(r))
    if d.size == 0 or d.min() <= 1e-8 * d.max():
        return np.diag(1.0 / norms)
    return np.diag(1.0 / norms) @ np.linalg.inv(r)


class _Problem:
    """Data, compiled predictor and residual definition of one fit."""

    def __init__(self, data: FitData, layout: _Layout, ball: Ball, model_kw, solver, fit_mask, scale, decimate, extra_weights, poisson_prior):
        from .filters import butter_lowpass_sos

        self.data = data
        self.layout = layout
        self.gas = model_kw["gas"]
        self.blocked_force = model_kw["blocked_force"]
        sos = butter_lowpass_sos(4, data.lowpass_Hz, data.rate_Hz) if data.lowpass_Hz is not None else np.zeros((1, 6))
        self.sos = np.asarray(sos, dtype=np.float64)
        self.fn = _compiled_predictor(
            layout.base, layout.stiffening, self.gas, self.blocked_force, data.n_records, data.n_samples,
            float(data.rate_Hz), 0 if data.lowpass_Hz is None else int(sos.shape[0]), layout.height_error, solver,
        )
        self.heights = np.asarray(data.height_m, dtype=np.float64)
        self.geometry = tuple(np.asarray(float(getattr(ball, f)), dtype=np.float64) for f in _FIXED_BALL_FIELDS)
        self.times = np.asarray(data.time_s, dtype=np.float64)
        self.fit_mask = np.asarray(fit_mask, dtype=bool)
        self.decimate = int(decimate)
        measured = record_features(data.force_N, data.rate_Hz)
        self.measured = measured
        if scale == "noise":
            self.weights = 1.0 / np.maximum(data.noise_rms_N, 1e-12)
        else:
            self.weights = 1.0 / measured["peak_force_N"]
        self.extra = {k: float(v) for k, v in (extra_weights or {}).items() if v}
        self.poisson_prior = poisson_prior
        self.kinds = layout.kinds
        # noise correlation from the pre-contact samples (up to 1 ms before each onset)
        quiet = [data.force_N[k, : max(int((data.onset_s[k] - 1e-3) * data.rate_Hz), 0)] for k in range(data.n_records)]
        n_quiet = min(len(q) for q in quiet)
        self.tau_noise = _integrated_autocorrelation(np.stack([q[:n_quiet] for q in quiet])[:, :: self.decimate]) if n_quiet >= 16 else 1.0

    def theta_from_phi(self, phi):
        theta = np.empty_like(phi)
        dtheta = np.empty_like(phi)
        for i, kind in enumerate(self.kinds):
            theta[i], dtheta[i] = _from_phi(kind, phi[i])
        return theta, dtheta

    def evaluate(self, theta):
        force, feats, jf, jfeat = self.fn(np.asarray(theta, dtype=np.float64), self.heights, self.geometry, self.sos, self.times)
        return {"force": np.asarray(force), "feats": np.asarray(feats), "jf": np.asarray(jf), "jfeat": np.asarray(jfeat)}

    def history_rms_N(self, out, mask=None):
        mask = self.fit_mask if mask is None else mask
        if not np.any(mask):
            return float("nan")
        return float(np.sqrt(np.mean((out["force"][mask] - self.data.force_N[mask]) ** 2)))

    def tau(self, r) -> float:
        """Integrated autocorrelation of the history part of a residual vector r."""
        n_fit = int(self.fit_mask.sum())
        n_hist = n_fit * len(range(0, self.data.n_samples, self.decimate))
        return _integrated_autocorrelation(np.asarray(r[:n_hist]).reshape(n_fit, -1))

    def history_block(self, out):
        """(r, J) of the history rows of the fitted records (decimated, scaled)."""
        sl = slice(None, None, self.decimate)
        k = np.flatnonzero(self.fit_mask)
        w = self.weights[k][:, None]
        r = ((out["force"][k] - self.data.force_N[k]) * w)[:, sl].reshape(-1)
        jac = (out["jf"][k] * w[..., None])[:, sl, :].reshape(-1, out["jf"].shape[-1])
        return r, jac

    def residuals(self, out, theta):
        r, jac = self.history_block(out)
        rows, jrows = [r], [jac]
        k = np.flatnonzero(self.fit_mask)
        feats, jfeat = out["feats"][k], out["jfeat"][k]
        if self.extra.get("contact_time"):
            w = self.extra["contact_time"]
            tc_m = self.measured["contact_time_s"][k]
            tc = feats[:, 1] - feats[:, 0]
            rows.append(w * (tc / tc_m - 1.0))
            jrows.append(w * (jfeat[:, 1] - jfeat[:, 0]) / tc_m[:, None])
        if self.extra.get("peak_force"):
            w = self.extra["peak_force"]
            pk_m = self.measured["peak_force_N"][k]
            rows.append(w * (feats[:, 2] / pk_m - 1.0))
            jrows.append(w * jfeat[:, 2] / pk_m[:, None])
        if self.extra.get("lfe"):
            w = self.extra["lfe"]
            rows.append(w * (feats[:, 3:] - self.measured["lfe_octave_dB"][k]).reshape(-1))
            jrows.append(w * jfeat[:, 3:, :].reshape(-1, jfeat.shape[-1]))
        if self.poisson_prior is not None:
            # The history rows are not whitened (their scale is 1/peak or 1/noise, and the
            # noise is correlated), so the prior row is put in their units: one prior σ weighs
            # as much as one σ̂√τ of the history residuals (σ̂, τ taken as constants here).
            mean, std = self.poisson_prior
            i = self.layout.index("poisson")
            unit = math.sqrt(self.tau(r) * float(r @ r) / max(r.size, 1))
            rows.append(np.array([unit * (theta[i] - mean) / std]))
            row = np.zeros((1, len(theta)))
            row[0, i] = unit / std
            jrows.append(row)
        return np.concatenate(rows), np.concatenate(jrows, axis=0)


# ----------------------------------------------------------------------------------------------
# optimisers


def _step_in_sigma(r, jac, tau=1.0) -> float:
    """Largest Gauss–Newton step |δ_j|/σ_j still to go, σ_j² = τ σ̂² [(JᵀJ)⁻¹]_jj the
    reported variance. Below ``STEP_TOLERANCE_SIGMA`` the fit has converged."""
    if jac.size == 0:
        return 0.0
    step = np.linalg.lstsq(jac, r, rcond=None)[0]
    sigma2 = tau * float(r @ r) / max(r.size - jac.shape[1], 1)
    cov = np.linalg.pinv(jac.T @ jac, hermitian=True) * sigma2
    return float(np.max(np.abs(step) / np.sqrt(np.maximum(np.diag(cov), 1e-300))))


#: Convergence: the remaining Gauss–Newton step is below this many standard deviations.
STEP_TOLERANCE_SIGMA = 0.05


def _run_optimistix(obj, u0, n_res, optimizer, max_steps):
    """optimistix Levenberg–Marquardt / Gauss–Newton in the whitened frame of the start.

    optimistix's Cauchy test stops it when an accepted step moves u by less than
    ``STEP_TOLERANCE_SIGMA`` of a standard deviation (in the whitened frame one unit of u is
    σ_res/√τ… so the tolerance is set from the start's residual rms and τ). Then the remaining
    Gauss–Newton step is checked against the reported σ; if it is still too large (a damped
    step can be small far from the optimum) the frame is re-centred and the solve continues.
    """
    import optimistix as optx

    shapes = (jax.ShapeDtypeStruct((n_res,), jnp.float64), jax.ShapeDtypeStruct((n_res, u0.size), jnp.float64))

    def host(u):
        r, jac, _, _ = obj(np.asarray(u))
        return r, jac

    def call(u):
        return jax.pure_callback(host, shapes, u, vmap_method="sequential")

    @jax.custom_jvp
    def residual(u, args):
        return call(u)[0]

    @residual.defjvp
    def _jvp(primals, tangents):
        u, _ = primals
        du, _ = tangents
        r, jac = call(u)
        return r, jac @ du

    u = np.asarray(u0, dtype=float)
    steps, message = 0, ""
    while True:
        u = obj.recentre(u)
        r, jac, _, _ = obj(u)
        tau = obj.p.tau(r)
        remaining = _step_in_sigma(r, jac, tau)
        if remaining < STEP_TOLERANCE_SIGMA:
            return u, True, f"converged (remaining Gauss–Newton step {remaining:.1g} σ < {STEP_TOLERANCE_SIGMA:g} σ)"
        if steps >= max_steps:
            if message:
                return u, False, message
            return u, False, f"not converged after {steps} optimiser steps (remaining Gauss–Newton step {remaining:.2g} σ)"
        sigma_u = math.sqrt(tau * float(r @ r) / max(r.size - u.size, 1))
        tol = STEP_TOLERANCE_SIGMA * sigma_u
        if optimizer == "lm":
            # optimistix widens the trust region only when the actual reduction is > 99 % of the
            # predicted one; in this large-residual problem that rarely holds and LM crawls
            # along correlated directions, so widen it from 50 % on (textbook values).
            solver = eqx.tree_at(
                lambda s: s.search,
                optx.LevenbergMarquardt(rtol=1e-12, atol=tol, norm=optx.rms_norm),
                optx.ClassicalTrustRegion(high_cutoff=0.5, low_cutoff=1e-4),
            )
        else:
            solver = optx.GaussNewton(rtol=1e-12, atol=tol, norm=optx.rms_norm)
        sol = optx.least_squares(residual, solver, jnp.asarray(u), None, max_steps=max_steps - steps, throw=False)
        steps += int(sol.stats["num_steps"])
        u = np.asarray(sol.value)
        if not np.all(np.isfinite(u)):
            return u, False, "the optimiser produced non-finite parameters"
        if sol.result != optx.RESULTS.successful:
            r, jac, _, _ = obj(u)
            message = f"not converged after {steps} optimiser steps (remaining Gauss–Newton step {_step_in_sigma(r, jac, obj.p.tau(r)):.2g} σ)"


def _run_optax(obj, u0, optimizer, max_steps):
    """optax Adam (learning rate 0.05 in the scaled coordinates) or L-BFGS (zoom line search)
    on ½‖r‖², gradient Jᵀr from the exact Jacobian; same convergence test as the LM."""
    import optax

    u = jnp.asarray(obj.recentre(u0))
    # one unit of u moves the residual vector by its norm at the start (the size of a full
    # Gauss–Newton step), so that Adam's learning rate is a fraction of such a step
    obj.w = obj.w * float(np.linalg.norm(obj(np.asarray(u))[0]))

    def converged_at(r, jac):
        return _step_in_sigma(r, jac, obj.p.tau(r)) < STEP_TOLERANCE_SIGMA

    if optimizer == "adam":
        opt = optax.adam(0.05)
        extra = {}
    else:
        opt = optax.lbfgs()

        def value_host(uu):
            r, jac = obj(np.asarray(uu))[:2]
            return np.asarray(0.5 * r @ r), np.asarray(jac.T @ r)

        shapes = (jax.ShapeDtypeStruct((), jnp.float64), jax.ShapeDtypeStruct(u.shape, jnp.float64))

        @jax.custom_jvp
        def value_fn(uu):
            return jax.pure_callback(value_host, shapes, uu, vmap_method="sequential")[0]

        @value_fn.defjvp
        def _value_jvp(primals, tangents):
            # the line search differentiates the value: its gradient is Jᵀr, exact from the model
            value, grad = jax.pure_callback(value_host, shapes, primals[0], vmap_method="sequential")
            return value, grad @ tangents[0]

        extra = {"value_fn": value_fn}
    state = opt.init(u)
    for _ in range(max_steps):
        r, jac, _, _ = obj(np.asarray(u))
        if converged_at(r, jac):
            return np.asarray(u), True, f"converged (remaining Gauss–Newton step < {STEP_TOLERANCE_SIGMA:g} σ)"
        value, grad = jnp.asarray(0.5 * r @ r), jnp.asarray(jac.T @ r)
        if optimizer == "adam":
            updates, state = opt.update(grad, state, u)
        else:
            updates, state = opt.update(grad, state, u, value=value, grad=grad, **extra)
        u = optax.apply_updates(u, updates)
    r, jac, _, _ = obj(np.asarray(u))
    if converged_at(r, jac):
        return np.asarray(u), True, f"converged (remaining Gauss–Newton step < {STEP_TOLERANCE_SIGMA:g} σ)"
    return np.asarray(u), False, f"not converged after {max_steps} {optimizer} steps (remaining Gauss–Newton step {_step_in_sigma(r, jac, obj.p.tau(r)):.2g} σ)"


# ----------------------------------------------------------------------------------------------
# start values


def _start_values(problem: _Problem, layout: _Layout, ball: Ball, fixed: dict, start: dict, ref_mask):
    """A physically motivated start θ (natural units) from the measured records.

    Stiffness from the contact time of the lowest fitted height (least gas force):
    t_c ≈ π√(M/k) (a linear spring-mass half period), k → E by Eqs. 1–3; damping from the
    restitution coefficient read off the impulse, e = ∫F dt/(M v0) − 1 (Eq. 10 for v0).
    """
    d = problem.data
    meas = problem.measured
    k_idx = np.flatnonzero(ref_mask)
    lowest = k_idx[np.argmin(d.height_m[k_idx])]
    tc = meas["contact_time_s"][lowest]
    mass = float(ball.mass_kg)
    nu = fixed.get("poisson", start.get("poisson", 0.45))
    k_spring = mass * (math.pi / tc) ** 2
    e_young = k_spring * float(ball.radius_m) * math.sqrt(3 * (1 - nu**2)) / (4 * float(ball.wall_m) ** 2)
    v0 = np.sqrt(2 * G_N_PER_KG * d.height_m)
    impulse = d.force_N.sum(axis=1) / d.rate_Hz
    e = float(np.clip(np.median((impulse / (mass * v0) - 1.0)[k_idx]), 0.05, 0.99))
    values = {"youngs_Pa": e_young, "poisson": nu}
    k_shell = float(reissner_stiffness_N_per_m(ball.replace(youngs_Pa=e_young, poisson=min(nu, 0.4999))))
    zeta = -math.log(e) / math.sqrt(math.pi**2 + math.log(e) ** 2)
    values["damping_Ns_per_m"] = 2 * zeta * math.sqrt(k_shell * mass)
    values["alpha_s_per_m"] = 3 * (1 - e) / (2 * float(np.median(v0[k_idx])))
    eta = -2 * math.log(e) / math.pi
    values["stiffness_ratio"] = max(2 * eta / max(1 - eta, 0.1), 0.05)
    values["relaxation_time_s"] = tc / math.pi
    values["beta"] = 0.05
    values.update(start)
    values.update(fixed)
    theta = np.zeros(len(layout.names))
    for i, n in enumerate(layout.physical):
        theta[i] = values[n]
    # contact starts one filter group delay plus ~1.6 % of t_c (5 % of a half sine) before the onset
    delay = (2.613 / (2 * math.pi * d.lowpass_Hz) if d.lowpass_Hz else 0.0) + 0.016 * tc
    theta[layout.shift_slice] = d.onset_s - delay
    return theta


# ----------------------------------------------------------------------------------------------
# the fit


def _validate_fix(model_name, fix):
    names = set(parameter_names(model_name)) | set(_FIXED_BALL_FIELDS)
    out = {}
    for k, v in (fix or {}).items():
        if k not in names:
            raise ValueError(f"fix: unknown parameter {k!r} for model {model_name!r}; valid: {', '.join(sorted(names))}")
        try:
            value = float(v)
        except (TypeError, ValueError):
            raise ValueError(f"fix: {k}={v!r} is not a number") from None
        out[k] = value
    if "poisson" in out and not -1.0 < out["poisson"] <= 0.5:
        raise ValueError(f"fix: poisson={out['poisson']!r} is outside the valid range (-1, 0.5]")
    for k, v in out.items():
        if k != "poisson" and not (math.isfinite(v) and v > 0):
            raise ValueError(f"fix: {k}={v!r} must be positive and finite (valid range: (0, inf))")
    return out


def fit(
    data,
    model: str = "zener",
    *,
    blocked_force: str = "paper",
    gas: str = "adiabatic",
    ball: Ball = JIS_RUBBER_BALL,
    fix: Mapping[str, float] | None = None,
    start: Mapping[str, float] | FitResult | None = None,
    hold_poisson: float = 0.5,
    poisson_prior: tuple[float, float] | None = None,
    optimizer: str = "lm",
    fit_heights: Sequence[float] | None = None,
    height_error: bool = False,
    scale: str = "noise",
    decimate: int = 1,
    extra_weights: Mapping[str, float] | None = None,
    max_steps: int | None = None,
    progress: bool = True,
    solver: Solver | None = None,
) -> FitResult:
    """Fit E, ν and the damping parameters of ``model`` to force histories of all records.

    Args:
        data: a :class:`FitData`, Recording objects, or paths/a directory (see
            :func:`prepare_data`: per-height averages, 30 ms windows, measuring chain low-pass
            as declared).
        model: ``paper`` (elastic, §2), ``kelvin-voigt``, ``hunt-crossley``, ``zener``, each
            optionally ``+stiffening``.
        blocked_force: ``paper`` (F_B + F_G + F_d) or ``momentum`` (adds (M/2R)δ̇² in compression).
        gas: ``adiabatic`` (Eq. 4, corrected) or ``none``.
        ball: geometry and mass (R, h, M) and the starting E, ν for nothing else.
        fix: name → value of parameters held (E, ν, damping parameters, β, or R, h, M).
        start: name → start value, or a previous :class:`FitResult` of the same model (warm start).
        hold_poisson: value at which ν is held when the Jacobian shows E and ν are not
            separately identifiable (always, for this model: §2.1 Eqs. 1–3).
        poisson_prior: (mean, std) of a Gaussian prior on ν instead of holding it.
        optimizer: ``lm`` (optimistix Levenberg–Marquardt), ``gauss-newton`` (optimistix),
            ``adam`` or ``lbfgs`` (optax).
        fit_heights: heights (m) whose records enter the fit (default all); the others are
            predicted (onset-aligned, nothing fitted to them) and reported as held out.
        height_error: also fit each record's drop-height error, bounded by ±1 cm.
        scale: residual of record k divided by its noise rms (``noise``) or peak (``peak``).
        decimate: use every n-th sample in the residual.
        extra_weights: {"contact_time": w, "peak_force": w, "lfe": w}: extra residual rows
            w·(relative error) for contact time and peak, w·(ΔL_FE in dB) per octave band.
        max_steps: optimiser steps (default 40 for lm/gauss-newton, 300 adam, 100 lbfgs).
        progress: print one line per function evaluation to stderr.
        solver: an ``rbjax.Solver`` (forced to ``adjoint="forward"``).

    The information criteria use the history residuals, AIC = N_eff ln(RSS/N) + 2p and
    BIC = N_eff ln(RSS/N) + p ln N_eff (p: free parameters incl. onsets), with the same
    N_eff = N/τ_noise for every model fitted to the same data (τ_noise: the integrated
    autocorrelation of the pre-contact noise), so that they are comparable across models.
    """
    from ._validate import check_choice, check_range
    from .model import BLOCKED_FORCE_OPTIONS, GAS_OPTIONS

    base, stiff = _parse_model(model)
    check_choice("blocked_force", blocked_force, BLOCKED_FORCE_OPTIONS)
    check_choice("gas", gas, GAS_OPTIONS)
    check_choice("optimizer", optimizer, OPTIMIZERS)
    check_choice("scale", scale, SCALES)
    if not isinstance(ball, Ball):
        raise ValueError(f"ball={ball!r} must be an rbjax.Ball")
    if not (isinstance(decimate, int) and decimate >= 1):
        raise ValueError(f"decimate={decimate!r} must be an integer >= 1")
    if not -1.0 < hold_poisson <= 0.5:
        raise ValueError(f"hold_poisson={hold_poisson!r} is outside the valid range (-1, 0.5]")
    if poisson_prior is not None:
        mean, std = (float(x) for x in poisson_prior)
        if not (-1.0 < mean < 0.5 and std > 0):
            raise ValueError(f"poisson_prior={poisson_prior!r}: need (mean, std) with -1 < mean < 0.5 and std > 0")
        poisson_prior = (mean, std)
    for k, w in (extra_weights or {}).items():
        if k not in ("contact_time", "peak_force", "lfe"):
            raise ValueError(f"extra_weights: unknown term {k!r}; valid: contact_time, peak_force, lfe")
        check_range(f"extra_weights[{k!r}]", w, lower=0.0, lower_open=False)
    if max_steps is None:
        max_steps = {"lm": 40, "gauss-newton": 40, "adam": 300, "lbfgs": 100}[optimizer]
    elif not (isinstance(max_steps, (int, np.integer)) and max_steps >= 0):
        raise ValueError(f"max_steps={max_steps!r} is outside the valid range: an integer ≥ 0 (0: evaluate the start only)")
    fixed = _validate_fix(model, fix)
    if "poisson" in fixed and poisson_prior is not None:
        raise ValueError("poisson is both fixed and given a prior; choose one")
    data = prepare_data(data)
    ball = ball.replace(**{k: v for k, v in fixed.items() if k in _FIXED_BALL_FIELDS})
    fit_mask = _height_mask(data, fit_heights)
    solver = _fit_solver(solver)
    layout = _Layout(model, data.n_records, height_error)
    problem = _Problem(data, layout, ball, {"gas": gas, "blocked_force": blocked_force}, solver, fit_mask, scale, decimate, extra_weights, poisson_prior)

    warm = start if isinstance(start, FitResult) else None
    start_map = {} if warm is not None else dict(start or {})
    for k in start_map:
        if k not in layout.physical:
            raise ValueError(f"start: unknown parameter {k!r} for model {model!r}; valid: {', '.join(layout.physical)}")
    if poisson_prior is not None and "poisson" not in start_map:
        # E/√(1−ν²) is all the histories determine, so the optimum has ν at the prior mean:
        # start there rather than crawl along the curved E–ν valley.
        start_map["poisson"] = poisson_prior[0]
    theta = _start_values(problem, layout, ball, {k: v for k, v in fixed.items() if k in layout.physical}, start_map, fit_mask)
    auto_start = warm is None and "youngs_Pa" not in start_map and "youngs_Pa" not in fixed
    if warm is not None:
        if warm.model_name != model or warm.theta.size != theta.size:
            raise ValueError(f"start: a FitResult of model {warm.model_name!r} cannot start a {model!r} fit of this data")
        theta = warm.theta.copy()
        for k, v in fixed.items():
            if k in layout.physical:
                theta[layout.index(k)] = v
    label = f"fit {model}/{blocked_force}"

    # 1. first evaluation: align the onsets (and rescale E from the contact times)
    out = problem.evaluate(theta)
    theta = _realign(problem, layout, theta, out, np.ones(data.n_records, bool), rescale_E=auto_start)
    out = problem.evaluate(theta)

    # 2. identifiability from the Jacobian with ν free
    physical_free = [n for n in layout.physical if n not in fixed]
    prior_held = False
    ident_msg, nu_flagged, cos_e_nu = _identifiability_check(problem, layout, theta, out, physical_free)
    notes = []
    if "poisson" in physical_free and "youngs_Pa" not in physical_free:
        notes.append("E held as given; ν alone sets the stiffness and is fitted.")
    elif "poisson" in physical_free and poisson_prior is None:
        if nu_flagged:
            physical_free.remove("poisson")
            theta[layout.index("poisson")] = hold_poisson
            notes.append(
                f"E and ν are not separately identifiable: their Jacobian columns are parallel "
                f"(|cos| = {cos_e_nu:.8f}); the data determine only E/√(1−ν²) (Reissner stiffness, "
                f"Eqs. 1–3; the gas force does not involve E or ν). ν is held at {hold_poisson:g}"
                + (" (the paper's value, §4; the bound of the model's range)" if hold_poisson == 0.5 else "")
                + " and effective_modulus_Pa = E/√(1−ν²) is the fitted quantity."
            )
        else:
            notes.append(f"E and ν: |cos| of their Jacobian columns {cos_e_nu:.6f}; both fitted.")
    elif "poisson" in physical_free:
        notes.append(
            f"E and ν are not separately identifiable from the histories (|cos| = {cos_e_nu:.8f}); "
            f"ν is determined by its prior N({poisson_prior[0]:g}, {poisson_prior[1]:g}²)."
        )
        if nu_flagged:
            # The histories fix only E/√(1−ν²), so the posterior mode has ν at the prior mean
            # exactly: optimise with ν held there (the curved E–ν valley is a trap for LM) and
            # fold the prior into the covariance afterwards.
            prior_held = True
            physical_free.remove("poisson")
            theta[layout.index("poisson")] = poisson_prior[0]
    else:
        notes.append(f"ν held at {theta[layout.index('poisson')]:g} as given; E/√(1−ν²) is what the data determine.")

    free_names = physical_free + [layout.names[i] for i in np.arange(len(layout.names))[layout.shift_slice][fit_mask]]
    if height_error:
        free_names += [layout.names[i] for i in np.arange(len(layout.names))[layout.dh_slice][fit_mask]]
    free = np.array([layout.index(n) for n in free_names], dtype=int)
    obj = _Objective(problem, free, theta, progress, label)
    u0 = np.zeros(free.size)
    n_res = obj(u0)[0].size

    # 3. optimise
    if optimizer in ("lm", "gauss-newton"):
        u_hat, ok, why = _run_optimistix(obj, u0, n_res, optimizer, max_steps)
    else:
        u_hat, ok, why = _run_optax(obj, u0, optimizer, max_steps)
    r, jac_u, theta, out = obj(u_hat)
    converged, message = ok, why

    # 4. held-out records: align their onsets with the fitted model (nothing else is fitted)
    if not np.all(fit_mask):
        theta = _realign(problem, layout, theta, out, ~fit_mask, rescale_E=False)
        out = problem.evaluate(theta)

    # 5. uncertainties
    hist_r, hist_j = problem.history_block(out)
    n_hist = hist_r.size
    tau = _integrated_autocorrelation(hist_r.reshape(int(fit_mask.sum()), -1))
    phi_hat = obj.phi(u_hat)
    dtheta = problem.theta_from_phi(phi_hat)[1]
    jac_phi_hist = hist_j[:, free] * dtheta[free][None, :]
    p = free.size
    sigma2 = float(hist_r @ hist_r) / max(n_hist - p, 1)
    info = jac_phi_hist.T @ jac_phi_hist / (tau * sigma2)
    if poisson_prior is not None and "poisson" in physical_free:
        i = free_names.index("poisson")
        info[i, i] += (dtheta[layout.index("poisson")] / poisson_prior[1]) ** 2
    scale_info = np.sqrt(np.maximum(np.diag(info), 1e-300))
    cov_phi = np.linalg.pinv(info / np.outer(scale_info, scale_info), rcond=1e-13, hermitian=True) / np.outer(scale_info, scale_info)
    if prior_held:
        free_names, physical_free, cov_phi = _fold_in_poisson_prior(free_names, physical_free, cov_phi, theta, layout, poisson_prior)
        free = np.array([layout.index(n) for n in free_names], dtype=int)
    std_phi = np.sqrt(np.clip(np.diag(cov_phi), 0, None))

    parameters = {}
    phys_idx = [free_names.index(n) for n in physical_free]
    for n in layout.physical:
        i = layout.index(n)
        if n in physical_free:
            j = free_names.index(n)
            lo = float(_from_phi(layout.kinds[i], phi_hat[i] - 1.96 * std_phi[j])[0])
            hi = float(_from_phi(layout.kinds[i], phi_hat[i] + 1.96 * std_phi[j])[0])
            parameters[n] = ParameterEstimate(float(theta[i]), float(abs(dtheta[i]) * std_phi[j]), (lo, hi), _UNITS[n])
        else:
            parameters[n] = ParameterEstimate(float(theta[i]), 0.0, (float(theta[i]), float(theta[i])), _UNITS[n], fixed=True)
    nu = theta[layout.index("poisson")]
    factor = 1.0 / math.sqrt(1.0 - nu**2)
    e_est = parameters["youngs_Pa"]
    e_eff = float(theta[layout.index("youngs_Pa")] * factor)
    if "poisson" in physical_free:
        # delta method through E/√(1−ν²) with the (E, ν) covariance block
        je, jn = free_names.index("youngs_Pa"), free_names.index("poisson")
        ie, inu = layout.index("youngs_Pa"), layout.index("poisson")
        grad = np.array([factor * dtheta[ie], theta[ie] * nu * factor**3 * dtheta[inu]])
        eff_std = float(math.sqrt(max(grad @ cov_phi[np.ix_([je, jn], [je, jn])] @ grad, 0.0)))
        eff_ci = (e_eff - 1.96 * eff_std, e_eff + 1.96 * eff_std)
    else:  # ν held: E/√(1−ν²) is E times a constant
        eff_std, eff_ci = e_est.std * factor, (e_est.ci95[0] * factor, e_est.ci95[1] * factor)
    parameters["effective_modulus_Pa"] = ParameterEstimate(e_eff, eff_std, eff_ci, "Pa", fixed=e_est.fixed and "poisson" not in physical_free)
    d_std = np.sqrt(np.clip(np.diag(cov_phi)[phys_idx], 1e-300, None))
    corr = cov_phi[np.ix_(phys_idx, phys_idx)] / np.outer(d_std, d_std)
    corr = np.clip(corr, -1.0, 1.0)

    # identifiability of what was fitted
    ident = " ".join(notes) + " " + _conditioning_note(jac_phi_hist, free_names, physical_free, corr)
    if ident_msg:
        ident += " " + ident_msg

    # 6. per-height summary and information criteria
    per_height = _per_height(problem, out)
    # a common N_eff for every candidate on these data: the noise's own correlation
    n_eff = n_hist / problem.tau_noise
    loglik_term = n_eff * math.log(float(hist_r @ hist_r) / n_hist)
    aic = loglik_term + 2 * p
    bic = loglik_term + p * math.log(n_eff)

    fitted_ball = ball.replace(youngs_Pa=float(theta[layout.index("youngs_Pa")]), poisson=float(nu))
    fitted_model = _model_from_theta(layout, theta, gas, blocked_force)
    return FitResult(
        model_name=model,
        blocked_force=blocked_force,
        gas=gas,
        ball=fitted_ball,
        model=fitted_model,
        parameters=parameters,
        correlations=(tuple(physical_free), corr),
        identifiability=ident.strip(),
        per_height=tuple(per_height),
        residual_rms_N=problem.history_rms_N(out),
        converged=bool(converged),
        message=message,
        iterations=obj.evaluations,
        optimizer=optimizer,
        n_eff_factor=float(tau),
        n_residuals=int(n_hist),
        n_free=int(p),
        aic=float(aic),
        bic=float(bic),
        time_s=data.time_s,
        measured_N=data.force_N,
        predicted_N=out["force"],
        heights_m=data.height_m,
        in_fit=fit_mask,
        onset_shift_s=theta[layout.shift_slice].copy(),
        theta=theta,
    )


def _fold_in_poisson_prior(free_names, physical_free, cov_phi, theta, layout, prior):
    """Add ν ~ N(mean, std²) to a covariance fitted with ν held at the mean (in φ = (log E, logit ν, …)).

    With ν held, the fitted log E is log E_eff + ½log(1 − ν²) at ν fixed; letting ν vary
    by its prior at fixed E_eff adds a = ∂log E/∂ν = −ν/(1 − ν²) times ν's deviation to log E.
    """
    nu, std = float(theta[layout.index("poisson")]), prior[1]
    dnu_dphi = float(_from_phi("poisson", _to_phi("poisson", nu))[1])
    a = -nu / (1.0 - nu**2)
    ie = free_names.index("youngs_Pa")
    n = len(free_names)
    cov = np.zeros((n + 1, n + 1))
    order = list(range(ie + 1)) + [n] + list(range(ie + 1, n))  # ν right after E
    cov[:n, :n] = cov_phi
    cov[n, n] = (std / dnu_dphi) ** 2
    cov[ie, ie] += a**2 * std**2
    cov[ie, n] = cov[n, ie] = a * std**2 / dnu_dphi
    cov = cov[np.ix_(order, order)]
    names = free_names[: ie + 1] + ["poisson"] + free_names[ie + 1 :]
    phys = [p for p in layout.physical if p in physical_free or p == "poisson"]
    return names, phys, cov


def _height_mask(data: FitData, heights) -> np.ndarray:
    if heights is None:
        return np.ones(data.n_records, dtype=bool)
    wanted = np.atleast_1d(np.asarray(heights, dtype=float))
    mask = np.zeros(data.n_records, dtype=bool)
    for h in wanted:
        hit = np.isclose(data.height_m, h, atol=5e-4)
        if not hit.any():
            raise ValueError(f"fit_heights: no record at height {h:g} m; heights in the data: {', '.join(f'{x:g}' for x in data.heights_m)}")
        mask |= hit
    return mask


def _realign(problem, layout, theta, out, which, *, rescale_E):
    """Move the onset shifts of the records ``which`` so that the predicted onset (5 % of the
    peak, rising edge) meets the measured one; optionally rescale E so that the predicted
    contact times match on the fitted records (t_c ∝ 1/√k)."""
    theta = theta.copy()
    feats = out["feats"]
    onset_pred = feats[:, 0]
    shift = theta[layout.shift_slice]
    shift[which] += (problem.measured["onset_s"] - onset_pred)[which]
    theta[layout.shift_slice] = shift
    if rescale_E:
        mask = problem.fit_mask
        tc_pred = (feats[:, 1] - feats[:, 0])[mask]
        ratio = float(np.median(tc_pred / problem.measured["contact_time_s"][mask]))
        theta[layout.index("youngs_Pa")] *= ratio**2
    return theta


def _identifiability_check(problem, layout, theta, out, physical_free):
    """(note, E–ν flagged?, |cos(∂r/∂E, ∂r/∂ν)|) from the history Jacobian at θ."""
    _, jac = problem.history_block(out)
    ie, inu = layout.index("youngs_Pa"), layout.index("poisson")
    a, b = jac[:, ie], jac[:, inu]
    denom = np.linalg.norm(a) * np.linalg.norm(b)
    cos = float(abs(a @ b) / denom) if denom > 0 else 1.0
    cols = [layout.index(n) for n in layout.physical if n in physical_free or n in ("youngs_Pa", "poisson")]
    cols += list(np.arange(len(layout.names))[layout.shift_slice][problem.fit_mask])
    j = jac[:, cols]
    j = j / np.maximum(np.linalg.norm(j, axis=0), 1e-300)
    sv = np.linalg.svd(j, compute_uv=False)
    cond = float(sv[0] / max(sv[-1], 1e-300))
    flagged = cos > 1 - 1e-6 or cond > 1e8
    note = f"(With E and ν both free the column-scaled Jacobian has condition number {cond:.1e}.)"
    return note, flagged, cos


def _conditioning_note(jac_phi, free_names, physical_free, corr) -> str:
    j = jac_phi / np.maximum(np.linalg.norm(jac_phi, axis=0), 1e-300)
    sv = np.linalg.svd(j, compute_uv=False)
    cond = float(sv[0] / max(sv[-1], 1e-300))
    worst = ""
    if len(physical_free) > 1:
        c = np.abs(corr - np.eye(len(physical_free)))
        i, k = np.unravel_index(np.argmax(c), c.shape)
        worst = f", largest correlation {corr[i, k]:+.3f} ({physical_free[i]}–{physical_free[k]})"
        if c[i, k] > 0.99:
            worst += ": these two are poorly identifiable separately"
    return f"Fitted parameters: scaled-Jacobian condition number {cond:.2g}{worst}."


def _integrated_autocorrelation(res) -> float:
    """τ = 1 + 2 Σ_{j≥1} ρ_j of the residual series (rows: records), pooled over records,
    summed while ρ_j > 0 (the initial positive sequence); at least 1."""
    res = np.asarray(res, dtype=float)
    if res.ndim == 1:
        res = res[None, :]
    res = res - res.mean(axis=1, keepdims=True)
    n = res.shape[1]
    var = float(np.sum(res**2))
    if var <= 0:
        return 1.0
    tau = 1.0
    for lag in range(1, n // 2):
        rho = float(np.sum(res[:, :-lag] * res[:, lag:])) / var
        if rho <= 0:
            break
        tau += 2 * rho
    return max(tau, 1.0)


def _model_from_theta(layout, theta, gas, blocked_force) -> Model:
    i = 2
    damping = None
    if layout.base != "paper":
        names = _DAMPING_PARAMS[layout.base]
        damping = DAMPING_MODELS[layout.base](**{n: float(theta[i + j]) for j, n in enumerate(names)})
        i += len(names)
    stiff = CubicStiffening(float(theta[i])) if layout.stiffening else None
    return Model(gas=gas, blocked_force=blocked_force, damping=damping, stiffening=stiff)


def _per_height(problem: _Problem, out) -> list[dict]:
    d = problem.data
    meas = problem.measured
    pred = {
        "onset_s": out["feats"][:, 0],
        "contact_time_s": out["feats"][:, 1] - out["feats"][:, 0],
        "peak_force_N": out["feats"][:, 2],
        "lfe_octave_dB": out["feats"][:, 3:],
    }
    rows = []
    for h in d.heights_m:
        k = np.isclose(d.height_m, h)
        m = {q: np.mean(meas[q][k], axis=0) for q in ("contact_time_s", "peak_force_N", "lfe_octave_dB")}
        f = {q: np.mean(pred[q][k], axis=0) for q in ("contact_time_s", "peak_force_N", "lfe_octave_dB")}
        rows.append({
            "height_m": float(h),
            "n_drops": int(d.n_drops[k].sum()),
            "in_fit": bool(problem.fit_mask[k].all()),
            "residual_rms_N": float(np.sqrt(np.mean((out["force"][k] - d.force_N[k]) ** 2))),
            "measured": {q: _plain(v) for q, v in m.items()},
            "fitted": {q: _plain(v) for q, v in f.items()},
            "error": {
                "contact_time_pct": float(100 * (f["contact_time_s"] / m["contact_time_s"] - 1)),
                "peak_force_pct": float(100 * (f["peak_force_N"] / m["peak_force_N"] - 1)),
                "lfe_octave_dB": _plain(f["lfe_octave_dB"] - m["lfe_octave_dB"]),
            },
        })
    return rows


@dataclasses.dataclass(frozen=True, eq=False)
class Prediction:
    """A model's predicted records next to the measured ones (nothing fitted); see :func:`predict`."""

    per_height: tuple
    time_s: np.ndarray
    measured_N: np.ndarray
    predicted_N: np.ndarray
    heights_m: np.ndarray
    converged: bool = True


def predict(data, ball: Ball = JIS_RUBBER_BALL, model: Model | None = None, *, solver: Solver | None = None) -> Prediction:
    """Compare a given (unfitted) model with the records; nothing is fitted.

    The model's floor force goes through the records' measuring chain; each record's onset
    is aligned with the predicted one (5 % of the peak); contact time, peak and octave-band
    L_FE are read off both with the same estimator. ``per_height`` rows as in
    :class:`FitResult` (all held out). ``model``: an ``rbjax.Model`` whose damping is None,
    KelvinVoigt, HuntCrossley (n = 1) or Zener (default: the paper's elastic model).
    """
    model = Model() if model is None else model
    name = "paper" if model.damping is None else model.damping.name
    if isinstance(model.damping, HuntCrossley) and model.damping.exponent != 1.0:
        raise ValueError("predict: Hunt–Crossley with exponent != 1 is not supported here")
    if model.stiffening is not None:
        name += STIFFENING_SUFFIX
    data = prepare_data(data)
    layout = _Layout(name, data.n_records, False)
    mask = np.zeros(data.n_records, dtype=bool)
    problem = _Problem(data, layout, ball, {"gas": model.gas, "blocked_force": model.blocked_force}, _fit_solver(solver), mask, "noise", 1, None, None)
    theta = np.zeros(len(layout.names))
    theta[0], theta[1] = float(ball.youngs_Pa), float(ball.poisson)
    i = 2
    if model.damping is not None:
        for n in _DAMPING_PARAMS[layout.base]:
            theta[i] = float(getattr(model.damping, n))
            i += 1
    if model.stiffening is not None:
        theta[i] = float(model.stiffening.beta)
    delay = 2.613 / (2 * math.pi * data.lowpass_Hz) if data.lowpass_Hz else 0.0
    theta[layout.shift_slice] = data.onset_s - delay
    out = problem.evaluate(theta)
    theta = _realign(problem, layout, theta, out, np.ones(data.n_records, bool), rescale_E=False)
    out = problem.evaluate(theta)
    return Prediction(tuple(_per_height(problem, out)), data.time_s, data.force_N, out["force"], data.height_m)


def model_histories(
    data,
    model: str,
    params: Mapping[str, float],
    onset_shift_s,
    *,
    blocked_force: str = "paper",
    gas: str = "adiabatic",
    ball: Ball = JIS_RUBBER_BALL,
    solver: Solver | None = None,
):
    """The predicted records of :func:`fit` and their exact Jacobian, for given parameters.

    ``params``: every name of :func:`parameter_names` (``model``); ``onset_shift_s``: the
    contact start of each record in its time axis (s). Returns ``(force_N, jacobian, names)``:
    the filtered floor force (n_records, n_samples), d force/d parameter
    (n_records, n_samples, n_parameters) by forward-mode differentiation through the solver,
    and the parameter names (the physical ones, then ``shift[k]``).
    """
    data = prepare_data(data)
    layout = _Layout(model, data.n_records, False)
    missing = [n for n in layout.physical if n not in params]
    if missing:
        raise ValueError(f"params: missing {missing} for model {model!r}")
    shifts = np.broadcast_to(np.asarray(onset_shift_s, dtype=float), (data.n_records,))
    problem = _Problem(data, layout, ball, {"gas": gas, "blocked_force": blocked_force}, _fit_solver(solver), np.ones(data.n_records, bool), "noise", 1, None, None)
    theta = np.array([float(params[n]) for n in layout.physical] + list(shifts))
    out = problem.evaluate(theta)
    return out["force"], out["jf"], tuple(layout.names)

"""Batched impact evaluation on the fastest exact path, sharded over every JAX device (the engine
of sweeps and sensitivities).

A sweep evaluates the impact model (paper §2, Eq. 7) for N parameter samples: drop height,
ball parameters (§2.1–2.2) and damping/stiffening parameters; :func:`evaluate` gives the
outputs, :func:`evaluate_jacobian` the outputs and their exact derivatives with respect to the
varied parameters (``jax.jacfwd`` per sample, vmapped). The batches are split over the local
devices of an :class:`rbjax.Parallel` by :func:`rbjax.solve.devices.device_map`, each device
running its own program (its docstrings say how to run on several CPU devices, GPUs or hosts).

Only the varied parameters travel as columns; the others are scalars shared by every row.

Paths, as ``rbjax.simulate`` chooses them (``path="auto"``, no ``solver`` given):

* scalar outputs (contact time, peak force, restitution, maximum deflection, status): the
  quadrature in δ (``rbjax.solve.quadrature``) for models without damping on the rigid floor,
  the phase-angle integration (``rbjax.solve.angle``) for damped rigid-floor models, the
  diffrax ODE (``rbjax.solve.ode``) otherwise. Impacts a fast path flags ``solver_failed`` are
  solved again by the ODE.
* the octave-band force exposure levels L_FE (§2.4, JIS A 1418-2) from the blocked force on the
  paper's 44.1 kHz × 1 s grid: only the contact window is integrated, by fixed RK4 steps sampled
  inside the solve (``rbjax.solve.sampled``) on the rigid floor, by the ODE's dense output
  otherwise (a history the sampled path flags is computed again by the ODE), and
  ``rbjax.spectrum.levels.lfe_octave_dB`` turns the contact samples into bands (``n_record``:
  the zeros after contact add nothing).

``path="ode"`` or a ``Solver`` asks for the diffrax ODE throughout (as ``simulate``). Flagged
solves (status ≠ 0) give NaN outputs.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .._validate import check_range
from .._x64 import require_x64
from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.levels import lfe_octave_dB
from ..terms import parameters as params
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.model import Model
from .angle import impact_angle
from .devices import device_map
from .inputs import PAPER_RATE_Hz, padded_rows
from .ode import impact_ode, ode_trajectory
from .options import EvaluationSpec, spec_or_default
from .outcome import STATUS_CODES, nan_where
from .parallel import Parallel, parallel_or_default
from .path import resolve_path
from .quadrature import impact_quadrature
from .sampled import sampled_history_unsupported, sampled_impact, substeps_for_contact
from .solver import Solver

BALL_PARAMETERS = tuple(Ball.PARAMETERS)
SCALAR_OUTPUTS = ("contact_time_s", "peak_force_N", "restitution", "max_deflection_m")
#: The history window is rounded up to a multiple of this many samples, so that sweeps with
#: slightly different longest contact times share one compiled program.
HISTORY_BLOCK = 128

__all__ = [
    "BALL_PARAMETERS",
    "SCALAR_OUTPUTS",
    "canonical_name",
    "assemble",
    "nominal_parameters",
    "lfe_output_names",
    "evaluation_paths",
    "evaluate",
    "evaluate_jacobian",
]


# ----------------------------------------------------------------------------------------------
# Parameters: names, and a (height, ball, model) with some of them replaced.


def canonical_name(name: str, model: Model | None = None) -> str:
    """The parameter called ``name`` in any letter case (``youngs_pa`` → ``youngs_Pa``)."""
    return params.canonical_name(name, JIS_RUBBER_BALL, model)


def assemble(values: Mapping, height_m, ball: Ball, model: Model):
    """(height, ball, model) with the named parameters of ``values`` replaced (arrays or
    tracers)."""
    return params.replace(values, height_m, ball, model)


def nominal_parameters(height_m, ball: Ball, model: Model) -> dict[str, float]:
    """Every parameter of ``rbjax.parameter_names(model=model)`` with its nominal value."""
    return {row.name: row.value for row in params.parameter_table(float(height_m), ball, model)}


def lfe_output_names() -> tuple[str, ...]:
    """Output names of the octave-band levels: ``lfe_31.5_dB`` … ``lfe_1000_dB`` (JIS A 1418-2)."""

    return tuple(f"lfe_{band}_dB" for band in OCTAVE_BANDS)


def evaluation_paths(
    model: Model, solver: Solver | None = None, path: str = "auto"
) -> tuple[str, str]:
    """(scalar path, history path) of ``evaluate``: ``"quadrature"``, ``"angle"`` or ``"ode"``
    (``rbjax.solve.path.resolve_path``), and ``"sampled"`` or ``"ode"``."""
    scalar = resolve_path(path, model, solver)
    history = "sampled" if scalar != "ode" and sampled_history_unsupported(model) is None else "ode"
    return scalar, history


# ----------------------------------------------------------------------------------------------
# One impact, and its batched (and differentiated) programs.


class _Spec(NamedTuple):
    """What one compiled program computes (hashable: the programs are cached on it)."""

    path: str  # scalars: "quadrature", "angle", "ode"; histories: "sampled", "ode"
    solver: Solver
    n_times: int = 0  # history samples integrated (0: the scalar outputs)
    n_total: int = 0  # samples of the record (the rest are zero)
    rate_Hz: float = PAPER_RATE_Hz
    substeps: int = 1


def _one_impact(row: Mapping, model: Model, spec: _Spec) -> dict:
    """The outputs of ONE impact whose parameters are ``row`` (scalars or tracers)."""
    height, ball, model = assemble(row, None, JIS_RUBBER_BALL, model)
    if spec.n_times:  # L_FE per octave band from the contact samples of the record (§2.4)
        if spec.path == "sampled":
            *_, force, _, status = sampled_impact(
                height, ball, model, spec.rate_Hz, spec.n_times, spec.substeps
            )
        else:
            traj = ode_trajectory(
                height, ball, model, spec.solver, jnp.arange(spec.n_times) / spec.rate_Hz
            )
            force, status = traj.force_N, traj.status
        lfe = lfe_octave_dB(force, spec.rate_Hz, n_record=spec.n_total)
        return {"lfe_dB": nan_where(status != 0, lfe), "history_status": status}
    if spec.path == "quadrature":
        out = impact_quadrature(height, ball, model)
    elif spec.path == "angle":
        out = impact_angle(height, ball, model)
    else:
        out = impact_ode(height, ball, model, spec.solver)
    return {"status": out.status, **{k: getattr(out, k) for k in SCALAR_OUTPUTS}}


@functools.lru_cache(maxsize=64)
def _impact_fn(spec: _Spec, wrt: tuple[str, ...]) -> Callable:
    """The per-device function of ``evaluate`` (cached: one compile per configuration and
    device): the outputs of a batch, and with ``wrt`` their derivatives ``d:<output>`` with
    respect to those parameters (forward mode, one ``jax.jacfwd`` per sample).

    ``fn(batch, (nominal, model))``: ``batch`` holds a column per varied parameter, ``nominal``
    the value of every other parameter of ``rbjax.parameter_names(model=model)`` (a scalar
    each, shared by the rows), so the program does not depend on the nominal values.
    """

    def one(row, shared):
        nominal, model = shared
        row = nominal | row
        if not wrt:
            return _one_impact(row, model, spec)

        def outputs(theta):
            out = _one_impact(row | dict(zip(wrt, theta)), model, spec)
            return {k: v for k, v in out.items() if jnp.issubdtype(v.dtype, jnp.floating)}, out

        jac, out = jax.jacfwd(outputs, has_aux=True)(jnp.stack([row[k] for k in wrt]))
        return out | {f"d:{k}": v for k, v in jac.items()}

    return jax.vmap(one, in_axes=(0, None))


def _redo(out: dict, rows: np.ndarray, fn: Callable, batch: dict, shared, run: Callable) -> None:
    """Compute the ``rows`` of ``out`` again with ``fn`` (the batch padded by
    ``inputs.padded_rows``, so that few shapes compile, in one chunk) and write them in place;
    ``run`` is called as :func:`rbjax.solve.devices.device_map`."""
    if rows.size == 0:
        return
    padded = padded_rows(rows)
    again = run(
        fn,
        {k: v[padded] for k, v in batch.items()},
        shared,
        desc="ODE for flagged impacts",
        parallel=Parallel(chunk_size=len(padded)),
    )
    for k in out:
        out[k][rows] = again[k][: rows.size]


def _evaluate(
    samples, wrt, *, height_m, ball, model, lfe, spec: EvaluationSpec, parallel: Parallel
) -> dict:
    require_x64()
    solver, path, rate_Hz, duration_s = spec.solver, spec.path, spec.rate_Hz, spec.duration_s
    progress = spec.progress
    model = Model() if model is None else model
    if not samples:
        raise ValueError("samples is empty: give at least one parameter with an array of values")
    named = {
        canonical_name(k, model): np.asarray(v, dtype=np.float64).reshape(-1)
        for k, v in samples.items()
    }
    n = {v.shape[0] for v in named.values()}
    if len(n) != 1:
        raise ValueError(
            "samples must all have the same length; got "
            f"{dict((k, v.shape[0]) for k, v in named.items())}"
        )
    # the constructors validate concrete values (jointly: e.g. wall < radius) and name the parameter
    assemble(named, height_m, ball, model)
    check_range("height_m", named.get("height_m", height_m), lower=0.0)
    wrt = tuple(canonical_name(k, model) for k in wrt)
    scalar_path, history_path = evaluation_paths(model, solver, path)
    ode_solver = Solver() if solver is None else solver
    if wrt and ode_solver.adjoint != "forward":  # jax.jacfwd through diffrax needs it
        ode_solver = dataclasses.replace(ode_solver, adjoint="forward")
    # a column per varied parameter; every other parameter a scalar shared by the rows
    batch = named
    nominal = {
        k: np.float64(v)
        for k, v in nominal_parameters(height_m, ball, model).items()
        if k not in named
    }
    shared = (nominal, model)

    def run(path: str, fn: Callable, rows: dict, desc: str, chunk: int | None = None) -> dict:
        """``fn`` over ``rows`` split over the devices, in chunks sized for ``path`` (or of
        ``chunk`` rows)."""
        where = parallel if chunk is None else parallel.replace(chunk_size=chunk)
        width = 1 + len(wrt)  # a forward Jacobian carries a tangent per parameter
        return device_map(
            fn, rows, shared, parallel=where, path=path, width=width, progress=progress, desc=desc
        )

    def redo_ode(fn, rows, _shared, *, desc, parallel):  # _redo's runner: the ODE's rows
        return run("ode", fn, rows, desc, parallel.chunk_size)

    out = run(scalar_path, _impact_fn(_Spec(scalar_path, ode_solver), wrt), batch, "impacts")
    if scalar_path != "ode":
        failed = np.flatnonzero(out["status"] == STATUS_CODES["solver_failed"])
        _redo(out, failed, _impact_fn(_Spec("ode", ode_solver), wrt), batch, shared, redo_ode)
    flagged = out["status"] != 0
    for k in SCALAR_OUTPUTS if wrt else ():  # jnp.where gives a flagged output's derivative 0
        out[f"d:{k}"][flagged] = np.nan
    if not lfe:
        return out
    check_range("rate_Hz", rate_Hz, lower=0.0)
    check_range("duration_s", duration_s, lower=0.0)
    n_total = max(1, int(round(rate_Hz * duration_s)))
    tc = out["contact_time_s"]
    longest = float(np.nanmax(tc)) if np.any(np.isfinite(tc)) else 0.0
    n_times = min(
        n_total, HISTORY_BLOCK * math.ceil((math.ceil(longest * rate_Hz) + 2) / HISTORY_BLOCK)
    )
    history = _Spec(
        history_path,
        ode_solver,
        n_times,
        n_total,
        float(rate_Hz),
        substeps_for_contact(tc, rate_Hz),
    )
    hist = run(history_path, _impact_fn(history, wrt), batch, "L_FE")
    if history_path == "sampled":  # a history the sampled path flags: the ODE's dense output
        again = np.flatnonzero((hist["history_status"] != 0) & (out["status"] == 0))
        _redo(
            hist,
            again,
            _impact_fn(history._replace(path="ode", substeps=1), wrt),
            batch,
            shared,
            redo_ode,
        )
    for i, name in enumerate(lfe_output_names()):
        out[name] = np.where(flagged, np.nan, hist["lfe_dB"][:, i])
        if wrt:
            out[f"d:{name}"] = np.where(flagged[:, None], np.nan, hist["d:lfe_dB"][:, i])
    return out


def evaluate(
    samples: Mapping,
    *,
    height_m=1.0,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    lfe: bool = False,
    evaluation: EvaluationSpec | None = None,
    parallel: Parallel | None = None,
) -> dict[str, np.ndarray]:
    """Impact outputs for N parameter samples, sharded over the devices.

    ``samples`` maps parameter names (``rbjax.parameter_names(model=model)``, any case) to
    arrays of length N; the other parameters keep the values of ``height_m``, ``ball`` and
    ``model``. Returns NumPy arrays of length N: ``contact_time_s``, ``peak_force_N``,
    ``restitution``, ``max_deflection_m``, ``status`` and, with ``lfe=True``, ``lfe_<band>_dB``
    per octave band
    (of the record ``evaluation.rate_Hz`` × ``evaluation.duration_s``). Outputs of flagged
    solves (status ≠ 0) are NaN.

    ``evaluation`` (an ``rbjax.EvaluationSpec``, default ``EvaluationSpec()``) says how: its
    ``path`` (``"auto"``, ``"ode"``, ``"quadrature"``, ``"angle"``) and ``solver`` choose the
    path as ``path`` and ``solver`` of ``rbjax.simulate`` (see the module docstring).
    ``parallel`` (an ``rbjax.Parallel``, default ``Parallel()``) says where: the samples are
    cut into chunks of its ``chunk_size`` impacts (default: sized for the path and the
    platform, ``rbjax.solve.parallel.default_chunk_size``; on a CPU 16 384 for the fast
    paths) and the chunks split over its ``devices`` (default: all local devices; see
    ``rbjax.solve.devices`` for how to give JAX one CPU device per core), each device running
    its own program: the results are those of a one-device run, bit for bit.
    """
    spec, where = spec_or_default(evaluation), parallel_or_default(parallel)
    return _evaluate(
        samples, (), height_m=height_m, ball=ball, model=model, lfe=lfe, spec=spec, parallel=where
    )


def evaluate_jacobian(
    samples: Mapping,
    wrt=None,
    *,
    height_m=1.0,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    lfe: bool = False,
    evaluation: EvaluationSpec | None = None,
    parallel: Parallel | None = None,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """``evaluate`` and the exact derivatives of every float output with respect to ``wrt``
    (default: the parameters of ``samples``), by ``jax.jacfwd`` per sample, vmapped and sharded.

    Returns ``(values, jacobian)``: ``values`` as ``evaluate``; ``jacobian`` maps each output to
    an (N, len(wrt)) array of ∂output/∂parameter in output units per parameter unit (NaN where
    the solve was flagged). The ODE path runs with ``Solver(adjoint="forward")``. ``evaluation``
    and ``parallel`` as in ``evaluate``.
    """
    spec, where = spec_or_default(evaluation), parallel_or_default(parallel)
    wrt = tuple(samples) if wrt is None else tuple(wrt)
    if not wrt:
        raise ValueError("wrt=() names no parameter; give the parameters to differentiate against")
    out = _evaluate(
        samples, wrt, height_m=height_m, ball=ball, model=model, lfe=lfe, spec=spec, parallel=where
    )
    jacobian = {k[2:]: out.pop(k) for k in [k for k in out if k.startswith("d:")]}
    jacobian.pop("lfe_dB", None)
    return out, jacobian

"""The public forward model: ``simulate``, ``trajectory`` and the frozen result of ``simulate``.

:func:`simulate` checks its inputs, takes the path :func:`~rbjax.solve.path.resolve_path`
chooses and has :mod:`rbjax.solve.path_runner` run it; :class:`ImpactResult` holds the scalar
outputs and computes the force histories (:func:`force_history`) and their band levels on request.
"""

from __future__ import annotations

import math
from typing import Unpack

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .._validate import check_choice, check_range, is_traced
from ..spectrum.levels import lfe_octave_dB, lfe_third_octave_dB
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.model import Model
from .inputs import PAPER_DURATION_S, PAPER_RATE_Hz, broadcast_inputs, check_inputs
from .ode import trajectory_batch
from .options import ModelShortcuts, model_from_shortcuts
from .outcome import STATUS_CODES, STATUS_NAMES, Trajectory
from .parallel import Parallel, parallel_or_default
from .path import resolve_path
from .path_runner import scalar_outputs
from .sampled import pad_record, sampled_history_unsupported, sampled_solve, substeps_for_contact
from .solver import Solver


class ImpactResult(eqx.Module):
    """Scalar outputs of ``simulate`` per drop height; the force history is computed on request.

    Every scalar field has the broadcast shape of the inputs. Where ``status != 0`` the scalar
    outputs are NaN and ``status_name`` says why (``step_limit``, ``mass_singularity``,
    ``deflection_limit``, ``solver_failed``, ``recontact``).

    Attributes:
        height_m: the drop heights h_D (m), broadcast to the shape of the outputs.
        contact_time_s: duration of the contact (s).
        peak_force_N: largest floor force (N).
        peak_time_s: time of the force peak after first contact (s).
        restitution: coefficient of restitution, rebound momentum over impact momentum.
        max_deflection_m: largest deflection δ of the shell (m).
        status: status code per impact (int32; ``rbjax.STATUS_NAMES``, 0: ok).
        num_steps: the path's count of steps per impact (see ``path``).
        ball: the :class:`~rbjax.terms.ball.Ball` simulated.
        model: the :class:`~rbjax.terms.model.Model` simulated.
        solver: the :class:`~rbjax.solve.solver.Solver` of the ODE (and of ``history()``).
        rate_Hz: sample rate of the force record (Hz) of ``force_N``, ``history()`` and the L_FE.
        duration_s: length of that record (s).
        path: the path that computed the scalars: ``"ode"`` (diffrax, ``num_steps`` = solver
            steps), ``"quadrature"`` (``rbjax.solve.quadrature``, ``num_steps`` = force
            evaluations), ``"angle"`` (``rbjax.solve.angle``, ``num_steps`` = fixed steps in the
            phase angle), or ``"quadrature+ode"`` / ``"angle+ode"`` (that path, with the ODE for
            the impacts it flagged ``solver_failed``).
    """

    height_m: jax.Array
    contact_time_s: jax.Array
    peak_force_N: jax.Array
    peak_time_s: jax.Array
    restitution: jax.Array
    max_deflection_m: jax.Array
    status: jax.Array
    num_steps: jax.Array
    ball: Ball
    model: Model
    solver: Solver = eqx.field(static=True)
    rate_Hz: float = eqx.field(static=True, default=PAPER_RATE_Hz)
    duration_s: float = eqx.field(static=True, default=PAPER_DURATION_S)
    path: str = eqx.field(static=True, default="ode")

    @property
    def ok(self):
        return self.status == 0

    @property
    def status_name(self):
        """Status names with the shape of ``status`` (a str for a single impact)."""
        codes = np.asarray(self.status)
        names = np.vectorize(STATUS_NAMES.get, otypes=[object])(codes)
        return str(names) if codes.ndim == 0 else names

    def raise_for_status(self) -> ImpactResult:
        """Raise ``RuntimeError`` naming the heights whose solve failed; return self otherwise."""
        codes = np.asarray(self.status).reshape(-1)
        if np.any(codes != 0):
            heights = np.broadcast_to(np.asarray(self.height_m), np.shape(self.status)).reshape(-1)
            bad = [
                f"height_m={h:g}: {STATUS_NAMES[int(c)]}" for h, c in zip(heights, codes) if c != 0
            ]
            raise RuntimeError("impact solve failed: " + "; ".join(bad[:10]))
        return self

    @property
    def time_s(self) -> np.ndarray:
        """The history grid: ``rate_Hz`` samples per second over ``duration_s``."""
        return np.arange(int(round(self.rate_Hz * self.duration_s))) / self.rate_Hz

    @property
    def force_N(self) -> jax.Array:
        """Blocked-force histories on ``time_s`` (computed on access by ``history()``; zero after
        contact)."""
        return self.history().force_N

    def history(
        self, rate_Hz: float | None = None, duration_s: float | None = None, *, pad: bool = True
    ) -> Trajectory:
        """Deflection, velocity and floor force sampled at ``rate_Hz`` over ``duration_s``.

        Only the samples during contact are integrated; the rest of the record is zero (with
        ``pad=False``: left out, the history ends a sample or two after the longest contact). The
        rigid-floor models (no ball mode, no moving floor) are integrated by fixed RK4 steps
        sampled inside the solve (``rbjax.solve.sampled``) unless a ``Solver`` other than the
        default was given, which asks for the diffrax ODE with it (as the coupled models
        always are); see ``force_history``.
        """
        rate = self.rate_Hz if rate_Hz is None else rate_Hz
        duration = self.duration_s if duration_s is None else duration_s
        return force_history(
            self.height_m,
            self.ball,
            self.model,
            self.solver,
            rate_Hz=rate,
            duration_s=duration,
            contact_time_s=self.contact_time_s,
            pad=pad,
        )

    def lfe_octave_dB(self) -> jax.Array:
        """Octave-band L_FE (paper Eq. 11; ``rbjax.spectrum.levels.lfe_octave_dB``) of the force
        record of ``rate_Hz`` over ``duration_s``, from its contact samples (exact: the rest is
        zero); shape (..., 6), NaN where the solve failed."""

        return lfe_octave_dB(
            self.history(pad=False).force_N,
            self.rate_Hz,
            n_record=int(round(self.rate_Hz * self.duration_s)),
        )

    def lfe_third_octave_dB(self) -> jax.Array:
        """One-third-octave-band L_FE of the force record, as ``lfe_octave_dB``; shape (..., 18)."""

        return lfe_third_octave_dB(
            self.history(pad=False).force_N,
            self.rate_Hz,
            n_record=int(round(self.rate_Hz * self.duration_s)),
        )

    def plot(self, ax=None, *, rate_Hz: float | None = None):
        """Plot the force histories over the contact (one line per height)."""
        # lazy: rbjax.plot imports matplotlib (0.1–0.2 s; pyplot ~1 s)
        from ..plot import plot_histories

        return plot_histories(self, ax=ax, rate_Hz=rate_Hz)


def simulate(
    height_m: ArrayLike,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    *,
    solver: Solver | None = None,
    path: str = "auto",
    rate_Hz: float = PAPER_RATE_Hz,
    duration_s: float = PAPER_DURATION_S,
    parallel: Parallel | None = None,
    **shortcuts: Unpack[ModelShortcuts],
) -> ImpactResult:
    """Impact of ``ball`` dropped from ``height_m`` on a rigid floor (paper §2), or on the
    ``floor`` given (``rbjax.terms.floors.kinds``; the force is then the force that floor receives).

    The model is a :class:`~rbjax.terms.model.Model`, the one calling convention of rbjax
    (``trajectory``, ``fit``, ``batch``, the studies take the same): ``simulate(h, fit.ball,
    fit.model)`` runs a fitted model. The keywords ``gas``, ``blocked_force``, ``damping``,
    ``stiffening``, ``max_deflection_ratio``, ``ball_mode``, ``series`` and ``floor``
    (``rbjax.solve.options.ModelShortcuts``) are a thin shortcut that builds the ``Model``
    (``Model(**shortcuts)``) when no ``model`` is given; giving both is a ``ValueError`` naming
    them (a term's ``None`` is its default, not a shortcut). Only ``simulate`` has them: every
    other function takes a ``Model``.

    ``height_m`` may be a scalar or an array (the solve is vmapped); ball and damping fields
    may be arrays too and broadcast against it. Works inside ``jax.jit``, ``jax.vmap`` and
    ``jax.grad``; ``jax.jacfwd`` works on the quadrature path, and on the ODE path with
    ``Solver(adjoint="forward")``.

    ``path`` picks the path of the scalar outputs (``result.path`` records it):

    * ``"auto"`` (default), when no ``solver`` is given: the quadrature (``rbjax.solve.quadrature``:
      Eq. 7 integrated in δ, ~1e-12, no time stepping) for models without damping on the rigid
      floor; the phase-angle integration (``rbjax.solve.angle``: fixed 8th-order steps in the phase
      angle, ~1e-8) for damped models on the rigid floor; the diffrax ODE otherwise (ball mode,
      series element, moving floors) or when a ``solver`` is given. Impacts the quadrature or the
      phase-angle path flags ``solver_failed`` (its error estimate too large) are solved again by
      the ODE when the inputs are concrete (``"quadrature+ode"``, ``"angle+ode"``).
    * ``"ode"``: the diffrax ODE with ``solver`` (default ``Solver()``).
    * ``"quadrature"``, ``"angle"``: that path only (``ValueError`` for models it cannot solve).

    Every core: concrete inputs (outside ``jax.jit``) are solved as one batch of impacts, cut in
    chunks sized for the device and split over the local devices, each device running its own
    program (``rbjax.solve.devices``; ``parallel`` chooses the devices and the chunks); the
    results are those of one device, bit for bit. JAX
    gives a Python process one CPU device, so set the count before JAX starts to use them all:
    ``JAX_NUM_CPU_DEVICES=16 python script.py``, or first thing in the script
    ``jax.config.update("jax_num_cpu_devices", 16)`` (``rbjax.commands.use_cpu_devices()``: one
    per usable core). The command line does it for you.

    Args:
        height_m: drop height h_D (m), a scalar or an array.
        ball: the :class:`~rbjax.terms.ball.Ball` (default ``JIS_RUBBER_BALL``); its fields may
            be arrays that broadcast against ``height_m``.
        model: the :class:`~rbjax.terms.model.Model` (default: built from ``shortcuts``, else
            ``Model()``).
        solver: a :class:`~rbjax.solve.solver.Solver`: asks for the diffrax ODE with it (default:
            none, ``Solver()`` where the ODE runs).
        path: the path of the scalar outputs, ``"auto"``, ``"ode"``, ``"quadrature"`` or
            ``"angle"`` (see above).
        rate_Hz: sample rate (Hz) of the force record of ``force_N``, ``history()`` and the L_FE
            (default the paper's 44.1 kHz).
        duration_s: length of that record (s; default 1 s).
        parallel: where a concrete batch runs: an ``rbjax.Parallel`` (its ``devices`` and
            ``chunk_size``; default ``Parallel()``: every local device, chunks sized per path).
        **shortcuts: the keyword shortcuts that build the ``Model`` when ``model`` is not given
            (see above).

    Returns:
        An :class:`ImpactResult`: contact time, peak force, restitution, status per height;
            ``.force_N`` / ``.history()`` compute the histories on request
            (``rbjax.solve.sampled`` on the rigid floor, the ODE otherwise); ``.lfe_octave_dB()``
            the band levels from the contact samples.

    Raises:
        ValueError: ``height_m``, ``rate_Hz`` or ``duration_s`` not finite and > 0, or a record
            of no sample; ``ball`` not a ``Ball`` or ``model`` not a ``Model``; ``model`` and
            shortcuts both given; an unknown ``path``, or a path that cannot solve the model;
            an invalid shortcut value (as ``Model`` raises). The message names the argument.
        TypeError: a keyword that is neither an argument nor a field of ``Model``.
        RuntimeError: float64 (``jax_enable_x64``) switched off after importing rbjax.
    """
    check_inputs(height_m, ball, rate_Hz, duration_s)
    model = model_from_shortcuts("simulate", model, shortcuts)
    chosen = resolve_path(path, model, solver)
    solver = Solver() if solver is None else solver
    return simulate_model(
        height_m,
        ball,
        model,
        solver,
        rate_Hz=rate_Hz,
        duration_s=duration_s,
        path=chosen,
        fallback=path == "auto",
        parallel=parallel_or_default(parallel),
    )


def simulate_model(
    height_m,
    ball,
    model,
    solver,
    *,
    rate_Hz=PAPER_RATE_Hz,
    duration_s=PAPER_DURATION_S,
    path="ode",
    fallback=False,
    parallel: Parallel | None = None,
) -> ImpactResult:
    height, out, path = scalar_outputs(path, height_m, ball, model, solver, fallback, parallel)
    return ImpactResult(
        height_m=height,
        contact_time_s=out.contact_time_s,
        peak_force_N=out.peak_force_N,
        peak_time_s=out.peak_time_s,
        restitution=out.restitution,
        max_deflection_m=out.max_deflection_m,
        status=out.status,
        num_steps=out.num_steps,
        ball=ball,
        model=model,
        solver=solver,
        rate_Hz=float(rate_Hz),
        duration_s=float(duration_s),
        path=path,
    )


def trajectory(
    height_m: ArrayLike,
    times_s: ArrayLike,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    solver: Solver | None = None,
) -> Trajectory:
    """State and floor force at the given times (1-D, shared by all heights); differentiable.

    The building block for fitting: ``times_s`` is static in shape, so this jits and goes
    through ``jax.jacfwd`` (with ``Solver(adjoint="forward")``).

    Args:
        height_m: drop height h_D (m), a scalar or an array; ball and model fields may be arrays
            too and broadcast against it.
        times_s: the sample times after first contact (s), a 1-D array.
        ball: the :class:`~rbjax.terms.ball.Ball` (default ``JIS_RUBBER_BALL``).
        model: the :class:`~rbjax.terms.model.Model` (default ``Model()``).
        solver: the :class:`~rbjax.solve.solver.Solver` of the diffrax ODE (default ``Solver()``).

    Returns:
        A :class:`~rbjax.solve.outcome.Trajectory` whose samples have the broadcast shape of
            the inputs followed by ``len(times_s)`` (zero after contact, NaN where the solve
            failed).

    Raises:
        ValueError: ``times_s`` not 1-D or not finite; ``height_m`` not finite and > 0,
            ``ball`` not a ``Ball`` or ``model`` not a ``Model`` (the argument named in the
            message).
        RuntimeError: float64 (``jax_enable_x64``) switched off after importing rbjax.
    """
    check_inputs(height_m, ball)
    if np.ndim(times_s) != 1:
        raise ValueError(f"times_s has shape {np.shape(times_s)}; expected a 1-D array of times")
    check_range("times_s", times_s)
    model = model_from_shortcuts("trajectory", model, {})
    solver = Solver() if solver is None else solver
    shape, height, flat_ball, flat_model = broadcast_inputs(height_m, ball, model)
    times = jnp.asarray(times_s, dtype=jnp.float64)
    traj = trajectory_batch(height, flat_ball, flat_model, solver, times)
    return jax.tree_util.tree_map(lambda x: x.reshape(shape + x.shape[1:]), traj)


def force_history(
    height_m,
    ball,
    model,
    solver,
    *,
    rate_Hz=PAPER_RATE_Hz,
    duration_s=PAPER_DURATION_S,
    contact_time_s=None,
    path="auto",
    pad=True,
) -> Trajectory:
    """Histories on a ``rate_Hz`` grid over ``duration_s``, zero-padded after the contact.

    Only the first ⌈t_c·rate⌉ + 2 samples are integrated (t_c: the longest contact time of the
    batch, computed first if not given); the rest of the record is zeros. With ``pad=False`` the
    computed samples are returned as they are (every non-zero sample of the record: pass
    ``n_record=round(rate_Hz·duration_s)`` to the ``rbjax.spectrum`` functions).

    ``path``: ``"auto"`` integrates the rigid-floor models (no ball mode, no moving floor) by
    fixed Runge–Kutta steps sampled inside the solve (``rbjax.solve.sampled``; sub-steps where
    the shortest contact spans few samples) when no ``solver`` other than the default
    ``Solver()`` is given and the contact times are concrete and shorter than the record; it
    solves the diffrax ODE with ``solver`` otherwise, as ``"ode"`` always does.
    """

    check_choice("path", path, ("auto", "ode"))
    check_inputs(height_m, ball, rate_Hz, duration_s)
    n_total = int(round(rate_Hz * duration_s))
    if contact_time_s is None:
        contact_time_s = simulate_model(
            height_m, ball, model, solver, path=resolve_path("auto", model), fallback=True
        ).contact_time_s
    tc = None if is_traced(contact_time_s) else np.asarray(contact_time_s, dtype=float)
    if tc is None:
        n_contact = n_total
    else:
        longest = np.nanmax(tc) if np.any(np.isfinite(tc)) else 0.0
        n_contact = min(n_total, int(math.ceil(longest * rate_Hz)) + 2)
    default_solver = solver is None or solver == Solver()
    sampled = (
        path == "auto"
        and n_contact < n_total
        and default_solver
        and sampled_history_unsupported(model) is None
    )

    def solve(n):
        if sampled:
            return sampled_solve(
                height_m, ball, model, rate_Hz, n, substeps_for_contact(tc, rate_Hz)
            )
        return trajectory(height_m, jnp.arange(n) / rate_Hz, ball, model, solver)

    def outlasts(traj):
        """The contact goes on after the last sample computed (the ODE: is in contact there)."""
        return np.asarray(
            traj.status == STATUS_CODES["step_limit"] if sampled else traj.in_contact[..., -1]
        )

    traj = solve(n_contact)
    if n_contact < n_total and not is_traced(traj.status) and np.any(outlasts(traj)):
        # a contact outlasts the window (its contact time was not known: a failed scalar solve
        # whose history succeeds): integrate the whole record instead of truncating it
        n_contact = n_total
        traj = solve(n_total)
    return pad_record(traj, n_total, float(rate_Hz)) if pad else traj

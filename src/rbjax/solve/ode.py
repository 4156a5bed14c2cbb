"""The equation of motion (paper Eq. 7) as a diffrax ODE, solved to the exact end of contact.

State y = (δ, δ̇[, internal states]) from first contact, δ(0) = 0, δ̇(0) = √(2 g h_D) (Eq. 10).

    (M − M_c(δ)) δ̈ − (M/2R) δ̇² H(−δ̇) = −F(δ, δ̇, ...)                     (Eq. 7)

The printed Eq. 7 writes H(δ̇); Eqs. 8–9 and the text make the flux term act in restitution
only (δ̇ < 0), as here. The solve is split in phases at events located by a root finder on
the solver's dense interpolant, never by a sign change on a sample grid:

1. compression, from first contact to the peak of the floor force (dF/dt = 0); for the
   elastic models this is maximum compression δ̇ = 0 (F increases with δ);
2. (damped models only) from the force peak to maximum compression δ̇ = 0;
3. restitution (flux term on) to the end of contact: δ = 0 for the elastic models, the
   contact force returning to zero (or δ = 0) for damped ones.

The contact time is the time of the last event; the peak force is the floor force at the
end of phase 1 (with a ball mode, a moving floor or an arrest law, which can make several local
maxima, the largest over every step, refined); the restitution coefficient is the rebound
momentum over the impact momentum. Whether the free motion after separation recontacts:
:mod:`rbjax.solve.recontact`.
The vector field and the state at first contact are :mod:`rbjax.solve.vector_field`.
"""

from __future__ import annotations

from collections.abc import Callable

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from ..terms.forces import dynamic_mass_kg, reissner_stiffness_N_per_m, singular_deflection_m
from ..terms.model import Model
from .outcome import (
    SINGULAR_FRACTION,
    STATUS_CODES,
    ImpactScalars,
    Trajectory,
    impact_velocity_m_per_s,
    nan_where,
)
from .recontact import recontacts
from .solver import Solver
from .vector_field import (
    COMPRESSION_ENERGY_FIELD,
    COMPRESSION_FIELD,
    RESTITUTION_ENERGY_FIELD,
    RESTITUTION_FIELD,
    body_velocity_m_per_s,
    contact_force,
    floor_force_N,
    initial_state,
)


def _force_rate(y, args):
    """dF/dt of the floor force along the compression trajectory (a directional derivative)."""
    ball, model = args
    _, rate = jax.jvp(
        lambda yy: floor_force_N(yy, ball, model), (y,), (COMPRESSION_FIELD(0.0, y, args),)
    )
    return rate


def _solve(
    rhs,
    t0,
    y0,
    args,
    conds,
    directions,
    solver: Solver,
    *,
    t1=jnp.inf,
    dense=False,
    steps=False,
    max_steps=None,
    root_finder=None,
    dtmax=None,
):
    root_finder = solver.root_finder() if root_finder is None else root_finder
    event = dfx.Event(conds, root_finder, direction=directions)
    controller = solver.controller()
    if dtmax is not None and isinstance(controller, dfx.PIDController):
        controller = dfx.PIDController(rtol=solver.rtol, atol=solver.atol, dtmax=dtmax)
    return dfx.diffeqsolve(
        dfx.ODETerm(rhs),
        solver.diffrax_solver(),
        t0,
        t1,
        solver.dt0(),
        y0,
        args,
        saveat=_saveat(dense, steps),
        stepsize_controller=controller,
        adjoint=solver.diffrax_adjoint(),
        event=event,
        max_steps=solver.max_steps if max_steps is None else max_steps,
        throw=False,
    )


def _with_force(t, y, args):
    return jnp.concatenate([y, jnp.reshape(floor_force_N(y, *args), (1,))])


def _saveat(dense: bool, steps: bool):
    """The end of the solve; with ``steps`` also every step's (y, floor force) in a second
    sub-save (the force computed at the steps taken only, not over the padded buffer)."""
    if not steps:
        return dfx.SaveAt(t1=True, dense=dense)
    return dfx.SaveAt(
        subs=[dfx.SubSaveAt(t1=True), dfx.SubSaveAt(steps=True, fn=_with_force)], dense=dense
    )


def final_state(sol):
    """(t, y) at the end of a solve."""
    if isinstance(sol.ts, (list, tuple)):
        return sol.ts[0][-1], sol.ys[0][-1]
    return sol.ts[-1], sol.ys[-1]


def _ok(sol):
    return (sol.result == dfx.RESULTS.successful) | (sol.result == dfx.RESULTS.event_occurred)


def solve_phases(
    height_m,
    ball,
    model: Model,
    solver: Solver,
    dense: bool,
    *,
    peak: bool = True,
    energy: bool = False,
    steps: bool = False,
):
    """Solve the phases of one impact; return the diffrax solutions and the phase ends.

    With ``peak`` (and a velocity-dependent model) compression stops at the force peak (an
    event on dF/dt) and goes on to maximum compression in a second solve, so that the peak is
    exact; without it (histories) compression is one solve and the "peak" is its end.
    """
    args = (ball, model)
    v0 = impact_velocity_m_per_s(height_m)
    y0 = initial_state(v0, ball, model, energy)
    compression, restitution = (
        (COMPRESSION_ENERGY_FIELD, RESTITUTION_ENERGY_FIELD)
        if energy
        else (COMPRESSION_FIELD, RESTITUTION_FIELD)
    )
    singular = SINGULAR_FRACTION * singular_deflection_m(ball, model)

    # Event functions are scaled to O(1) so that the root finder's tolerances (which also
    # bound |cond| at the root) sit above round-off for every one of them.
    force_scale = reissner_stiffness_N_per_m(ball) * ball.wall_m

    def velocity(t, y, args, **kw):
        return y[1] / v0

    def singularity(t, y, args, **kw):
        return (y[0] - singular) / ball.radius_m

    def force_rate(t, y, args, **kw):
        return _force_rate(y, args) / (force_scale * v0 / ball.wall_m)

    conds: tuple[Callable, ...]
    dirs: tuple[bool, ...]
    split = model.velocity_dependent and peak
    if split:
        conds, dirs = (force_rate, velocity, singularity), (False, False, True)
    else:
        conds, dirs = (velocity, singularity), (False, True)
    sol1 = _solve(compression, 0.0, y0, args, conds, dirs, solver, dense=dense, steps=steps)
    t_peak, y_peak = final_state(sol1)

    if split:
        # From the force peak on to maximum compression (zero length if they coincide).
        t1 = jnp.where(y_peak[1] > 0.0, jnp.inf, t_peak)
        sol2 = _solve(
            compression,
            t_peak,
            y_peak,
            args,
            (velocity, singularity),
            (False, True),
            solver,
            t1=t1,
            dense=dense,
            steps=steps,
        )
        t_max, y_max = final_state(sol2)
    else:
        sol2, t_max, y_max = None, t_peak, y_peak

    def deflection(t, y, args, **kw):
        return y[0] / ball.wall_m

    conds3: Callable | tuple[Callable, ...]
    dirs3: bool | tuple[bool, ...]
    end_root_finder: optx.AbstractRootFinder | None = None
    if model.velocity_dependent:

        def contact(t, y, args, **kw):
            return contact_force(y, *args) / force_scale

        conds3, dirs3 = (contact, deflection), (False, False)
        if model.layer is not None:
            # With a contact layer (F ≈ Kδ^p near δ = 0) a damping law that vanishes with δ
            # (Hunt–Crossley's αkδδ̇) ends the contact at δ* > 0, where Kδ^(p−1) = αk|δ̇|, and
            # the force touches 0 again at δ = 0 from below: a step across both would ask the
            # root finder for both events' roots at once, and a Newton step from the step's end
            # (near that turn, where the slope is small) can leave the step. The contact event
            # alone (the force is negative for δ < 0, the shell's law continued) and bisection
            # on the step, which keeps the sign change from + to −, find δ*.
            conds3, dirs3 = contact, False
            end_root_finder = optx.Bisection(rtol=1e-12, atol=1e-13)  # type: ignore[call-arg]
    else:
        conds3, dirs3 = deflection, False
    # Restitution starts from rest; a tiny negative velocity keeps the Heaviside side exact.
    y_start = y_max.at[1].set(jnp.minimum(y_max[1], 0.0))
    sol3 = _solve(
        restitution,
        t_max,
        y_start,
        args,
        conds3,
        dirs3,
        solver,
        dense=dense,
        steps=steps,
        root_finder=end_root_finder,
    )
    return v0, (sol1, sol2, sol3), (t_peak, y_peak), (t_max, y_max)


def impact_status(sols, y_max, outputs, ball, model: Model):
    """The status code of one impact from its phase solutions and outputs (see STATUS_NAMES)."""
    solved = [s for s in sols if s is not None]
    step_limit = jnp.any(jnp.stack([s.result == dfx.RESULTS.max_steps_reached for s in solved]))
    failed = ~jnp.all(jnp.stack([_ok(s) for s in solved]))
    singular = y_max[0] >= SINGULAR_FRACTION * singular_deflection_m(ball, model) * (1.0 - 1e-9)
    nonfinite = ~jnp.all(jnp.isfinite(outputs))
    too_deep = y_max[0] > model.max_deflection_ratio * ball.wall_m
    return jnp.select(
        [step_limit, singular, failed | nonfinite, too_deep],
        [
            STATUS_CODES["step_limit"],
            STATUS_CODES["mass_singularity"],
            STATUS_CODES["solver_failed"],
            STATUS_CODES["deflection_limit"],
        ],
        STATUS_CODES["ok"],
    ).astype(jnp.int32)


#: Step budget of the short solves that locate a global maximum between two saved steps.
REFINE_MAX_STEPS = 64


#: A refinement on a steep rate (an arrest law's share): its root by bisection, which keeps
#: the sign change where Newton can cycle (the rate falls through 0: ``flip``; times to 1 ns,
#: |rate| below 1e-9 of its O(1) scale), and steps of at most 1/``STEEP_SUBSTEPS`` of the
#: bracket (the floor's flux is no state of the motion, so the step control does not see it: a
#: maximum and a minimum of the floor force can lie within one step of the motion).
STEEP_ROOT_FINDER: optx.AbstractRootFinder
STEEP_ROOT_FINDER = optx.Bisection(rtol=1e-12, atol=1e-9, flip=True)  # type: ignore[call-arg]
STEEP_SUBSTEPS = 16


def _refine(start, t_end, value_of, rate_of, args, solver: Solver, *, steep: bool = False):
    """The maximum of ``value_of(y)`` on [t_start, t_end], where it has one interior maximum
    or none: a short solve from ``start`` = (t_start, y_start) with an event where ``rate_of``
    (its rate along the flow, scaled to O(1)) falls through 0; (value, time) at the event, or
    ``value_of`` at t_start if no event occurs. ``steep``: ``STEEP_ROOT_FINDER`` and
    ``STEEP_SUBSTEPS``."""
    t0, y0 = start
    sol = _solve(
        RESTITUTION_FIELD,
        t0,
        y0,
        args,
        lambda t, y, args, **kw: rate_of(y),
        False,
        solver,
        t1=t_end,
        max_steps=REFINE_MAX_STEPS,
        root_finder=STEEP_ROOT_FINDER if steep else None,
        dtmax=jnp.maximum(t_end - t0, 1e-12) / STEEP_SUBSTEPS if steep else None,
    )
    t, y = final_state(sol)
    hit = sol.result == dfx.RESULTS.event_occurred
    return jnp.where(hit, value_of(y), value_of(y0)), jnp.where(hit, t, t0)


def _coupled_maxima(sols, v0, args, solver: Solver, *, steep: bool = False):
    """Global maxima of the floor force (and its time) and of δ over the contact.

    A ball mode or a moving floor can give several local maxima, and the phase events find
    the first one only. Every step of every phase is saved (``solve_phases(steps=True)``); the
    largest value over the step ends and the step ends either side of it bracket the global
    maximum, located exactly by a short solve to the event dF/dt = 0 (or δ̇ = 0) between them.
    The restitution vector field is valid in every phase (its thrust acts only where δ̇ < 0).

    With ``steep`` (an arrest law, whose share falls within a fraction of a millisecond as δ̇
    passes the arrest speed) the force can also peak narrowly inside one step, above every
    step end: the first step over which dF/dt turns from positive to negative is refined too,
    and both refinements are ``steep`` (bisection on sub-steps: see ``_refine``).
    """
    ball, model = args
    ts = jnp.concatenate([s.ts[1] for s in sols if s is not None])
    rows = jnp.concatenate([s.ys[1] for s in sols if s is not None])
    valid = jnp.isfinite(ts)
    rows = jnp.where(
        valid[:, None], rows, rows[0]
    )  # padding (inf) never reaches an output or a gradient
    ys, forces = rows[:, :-1], rows[:, -1]
    ts_safe = jnp.where(valid, ts, 0.0)
    force_scale = reissner_stiffness_N_per_m(ball) * ball.wall_m

    def force(y):
        return floor_force_N(y, ball, model)

    def force_rate(y):
        _, rate = jax.jvp(force, (y,), (RESTITUTION_FIELD(0.0, y, args),))
        return rate / (force_scale * v0 / ball.wall_m)

    def deflection(y):
        return y[0]

    def velocity(y):
        return y[1] / v0

    def best(values):
        values = jnp.where(valid, values, -jnp.inf)
        i = jnp.argmax(values)
        before = jnp.argmax(jnp.where(valid & (ts_safe < ts_safe[i]), ts_safe, -jnp.inf))
        after = jnp.argmin(jnp.where(valid & (ts_safe > ts_safe[i]), ts_safe, jnp.inf))
        first = ~jnp.any(valid & (ts_safe < ts_safe[i]))
        last = ~jnp.any(valid & (ts_safe > ts_safe[i]))
        start = (jnp.where(first, ts_safe[i], ts_safe[before]), jnp.where(first, ys[i], ys[before]))
        end = jnp.where(last, ts_safe[i], ts_safe[after])
        return values[i], ts_safe[i], start, end

    f_best, t_best, start, end = best(forces)
    f_ref, t_ref = _refine(start, end, force, force_rate, args, solver, steep=steep)
    peak = jnp.maximum(f_best, f_ref)
    peak_time = jnp.where(f_ref > f_best, t_ref, t_best)
    if steep:
        order = jnp.argsort(jnp.where(valid, ts_safe, jnp.inf))
        rate = jax.vmap(force_rate)(ys)[order]
        ok = valid[order]
        turns = ok[:-1] & ok[1:] & (rate[:-1] > 0.0) & (rate[1:] <= 0.0)
        k = jnp.argmax(turns)  # the first turn (0 where there is none: not used then)
        i, j = order[k], order[k + 1]
        f_turn, t_turn = _refine(
            (ts_safe[i], ys[i]), ts_safe[j], force, force_rate, args, solver, steep=True
        )
        f_turn = jnp.where(jnp.any(turns), f_turn, -jnp.inf)
        peak_time = jnp.where(f_turn > peak, t_turn, peak_time)
        peak = jnp.maximum(peak, f_turn)
    d_best, _, start, end = best(ys[:, 0])
    d_ref, _ = _refine(start, end, deflection, velocity, args, solver)
    return peak, peak_time, jnp.maximum(d_best, d_ref)


def impact_ode(height_m, ball, model: Model, solver: Solver) -> ImpactScalars:
    # An arrest law's floor force falls steeply where δ̇ passes its arrest speed, which can make
    # a first, narrow local maximum of the floor force before the largest one, so the peak is
    # the largest of both over the saved steps (``_coupled_maxima(steep=True)``), and
    # compression is one solve: an event on dF/dt there asked Newton for a root where the
    # force's rate turns within a step, and Newton can cycle there without converging (the
    # impact then failed).
    arrest = model.arrest is not None
    v0, sols, (t_peak, y_peak), (t_max, y_max) = solve_phases(
        height_m, ball, model, solver, dense=False, peak=not arrest, steps=model.coupled or arrest
    )
    sol3 = sols[2]
    t_end, y_end = final_state(sol3)
    args = (ball, model)

    peak = floor_force_N(y_peak, *args)
    first = floor_force_N(initial_state(v0, ball, model), *args)
    max_deflection = y_max[0]
    recontact = jnp.asarray(False)
    if model.coupled:
        peak, t_peak, max_deflection = _coupled_maxima(sols, v0, args, solver)
        recontact = recontacts(y_end, args)
    elif arrest:
        # the largest of the force at maximum compression and the maxima over the saved
        # steps, refined: each is a value the force takes, the largest the peak
        global_peak, t_global, _ = _coupled_maxima(sols, v0, args, solver, steep=True)
        t_peak = jnp.where(global_peak > peak, t_global, t_peak)
        peak = jnp.maximum(peak, global_peak)
    peak_force = jnp.maximum(peak, first)
    peak_time = jnp.where(peak >= first, t_peak, 0.0)
    momentum_out = -dynamic_mass_kg(y_end[0], ball, model) * body_velocity_m_per_s(y_end, *args)
    restitution = momentum_out / (ball.mass_kg * v0)

    solved = [s for s in sols if s is not None]
    steps = sum(s.stats["num_steps"] for s in solved)
    status = impact_status(
        sols,
        y_max.at[0].set(max_deflection),
        jnp.stack([t_end, peak_force, restitution, max_deflection, t_max, peak_time]),
        ball,
        model,
    )
    status = jnp.where((status == 0) & recontact, STATUS_CODES["recontact"], status).astype(
        jnp.int32
    )
    return ImpactScalars.flagged(
        status,
        steps,
        contact_time_s=t_end,
        peak_force_N=peak_force,
        peak_time_s=peak_time,
        restitution=restitution,
        max_deflection_m=max_deflection,
        max_compression_time_s=t_max,
    )


def ode_trajectory(height_m, ball, model: Model, solver: Solver, times_s) -> Trajectory:
    # compression in one solve: the force peak needs no exact time here
    v0, (sol1, _, sol3), _, (t_max, y_max) = solve_phases(
        height_m, ball, model, solver, dense=True, peak=False
    )
    t_end = sol3.ts[-1]
    args = (ball, model)
    status = impact_status((sol1, sol3), y_max, jnp.stack([t_end, t_max, y_max[0]]), ball, model)
    failed = status != 0

    def at(t):
        # Each phase's interpolant is evaluated inside its own interval only (clipped), so an
        # unused branch can never feed NaN into values or gradients.
        y = sol1.evaluate(jnp.clip(t, 0.0, t_max))
        y3 = sol3.evaluate(jnp.clip(t, t_max, t_end))
        y = jnp.where(t > t_max, y3, y)
        inside = (t >= 0.0) & (t < t_end)
        y = jnp.where(inside, y, jnp.zeros_like(y))
        force = jnp.where(inside, floor_force_N(y, *args), 0.0)
        # a failed solve gives NaN, never a plausible-looking history
        return (
            nan_where(failed, y[0]),
            nan_where(failed, y[1]),
            nan_where(failed, force),
            inside & ~failed,
        )

    d, v, f, inside = jax.vmap(at)(times_s)
    return Trajectory(
        time_s=times_s,
        deflection_m=d,
        velocity_m_per_s=v,
        force_N=f,
        in_contact=inside,
        status=status,
    )


impact_batch = eqx.filter_jit(eqx.filter_vmap(impact_ode, in_axes=(0, 0, 0, None)))
trajectory_batch = eqx.filter_jit(eqx.filter_vmap(ode_trajectory, in_axes=(0, 0, 0, None, None)))

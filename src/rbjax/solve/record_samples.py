"""The floor force at a record's own sample times, for a contact that starts at any time s on
the record's time axis: fixed steps from sample to sample, the onset as a partial first step.

A force-plate record samples t_i = i/rate; the model's contact starts at t = s (the onset
shift, fitted). The fit compares the model with the record sample by sample, so it needs
F(t_i − s) at every sample, continuous in s and in the parameters. Here (Δ = 1/rate):

* the sample n₀ = ⌊s/Δ + ½⌋ is the one whose interval [t − Δ/2, t + Δ/2] holds the contact
  start. Damped models and the ``momentum`` blocked force jump at first contact (c·v0,
  (M/2R)v0²), so that sample takes the in-contact fraction a = n₀ + ½ − s/Δ ∈ (0, 1] of its
  interval times the force at the midpoint of the in-contact part, τ = aΔ/2 (the box average
  of the jump; the rule of ``rbjax.fit.program.sample_force`` and of the records made for the
  tests), and every later sample n₀ + j is the point value F(τ_j), τ_j = (a + j − ½)Δ;
* the state is stepped by classic fourth-order Runge–Kutta (``substeps`` steps per interval):
  0 → aΔ/2 → (a + ½)Δ, then Δ at a time, on the restitution vector field of ``ode.py`` (its
  momentum-flux thrust acts only while δ̇ < 0, so one field serves both phases, and the ball
  mode's states ride along);
* the contact ends at the first sample where δ ≤ 0 or (damped models) the contact force ≤ 0;
  from there the force is 0. At the true end the force is 0 (δ = 0 or F_c = 0), so a sample
  leaving the contact as the parameters move changes the residual continuously;
* with the force, each sample carries dF/ds = −Ḟ(τ) (Ḟ = ∂F/∂y · ẏ along the solution; for the
  first sample −F(aΔ/2)/Δ − a Ḟ(aΔ/2)/2): the onset-shift columns of the fit's Jacobian come
  from the model's own time derivative, not from tangents carried through the solve.

Statuses as the other paths (``outcome.STATUS_CODES``): ``solver_failed`` for a non-finite
state, ``mass_singularity`` for δ ≥ 0.999·2R; a failed impact gives NaN samples. A contact
still going at the end of the record is not a failure here (the record is a window).

The number of samples is static; ``substeps`` is a Python int or a traced integer (the fit's
count for the parameters of the moment, :func:`substeps_at`); everything else is a runtime value,
and the function works under ``jax.jit``, ``jax.vmap`` and ``jax.jacfwd``. Moving floors are not
handled (``record_samples_unsupported``).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp

from ..terms.forces import reissner_stiffness_N_per_m, singular_deflection_m
from ..terms.model import Model
from .outcome import SINGULAR_FRACTION, STATUS_CODES, impact_velocity_m_per_s, nan_where
from .vector_field import RESTITUTION_FIELD, contact_force, floor_force_N, initial_state

#: The largest |λ|·h of a Runge–Kutta step the sub-steps allow for the fastest rate λ of the
#: model (a ball mode's damping ηω, up to η = 4, f = 2.5 kHz at its fit range's corner; a Zener
#: relaxation 1/τ): inside RK4's stability limit |λh| ≈ 2.8 with a margin of ~5, and one step
#: that fast stays within 1e-6 of the peak force (4.9e-7 measured just under 0.5, the ball mode
#: at μ = 100, η = 4). The contact's own motion, ~1/100 of that rate, is resolved to ~1e-10 of
#: the peak force in one step a sample at 44.1 kHz (tests/fit/test_record_forces.py).
MAX_RATE_STEP = 0.5

#: The impact speed at which the fastest rate is taken (first contact at 5 m/s, a drop of
#: 1.27 m; the rate there differs by < 3 % from that of a 1.6 m drop, 5.6 m/s, and by < 1 %
#: with the ball mode: inside ``MAX_RATE_STEP``'s margin).
RATE_SPEED_M_PER_S = 5.0


def record_samples_unsupported(model: Model) -> str | None:
    """Why ``record_samples`` cannot solve ``model``; None if it can (rigid floor, any damping
    law, the ball mode included)."""
    if not model.floor.rigid:
        return (
            f"the floor ({model.floor.name}) moves under the force: its states need the ODE's "
            "events"
        )
    return None


def substeps_for_rate(fastest_rate_per_s: float, rate_Hz: float) -> int:
    """Runge–Kutta steps per sample so that |λ|·h ≤ ``MAX_RATE_STEP`` for the fastest rate λ
    (at least one: the contact's own oscillation then has ≥ 800 steps per period at 44.1 kHz,
    ~1e-10 of the peak force)."""
    if not (math.isfinite(fastest_rate_per_s) and fastest_rate_per_s > 0):
        return 1
    return max(1, math.ceil(fastest_rate_per_s / (MAX_RATE_STEP * rate_Hz)))


def first_contact_jacobian(ball, model: Model):
    """The restitution vector field's Jacobian at first contact from ``RATE_SPEED_M_PER_S``:
    its spectral radius is the fastest rate of the model's motion."""
    state = initial_state(impact_velocity_m_per_s(RATE_SPEED_M_PER_S), ball, model)
    return jax.jacfwd(lambda y: RESTITUTION_FIELD(0.0, y, (ball, model)))(state)


def spectral_radius_bound(matrix, squarings: int = 10):
    """An upper bound of the spectral radius ρ(A) of a small square matrix that any backend
    computes (no nonsymmetric eigensolver): Gelfand's ‖A^k‖^{1/k} ≥ ρ(A) at k = 2^squarings,
    by repeated squaring with the scale carried as a logarithm (within a factor
    κ(V)^{1/1024} of ρ for a diagonalisable A with eigenvectors V: 2 % for κ = 1e10)."""
    a = jnp.asarray(matrix)
    log_scale = jnp.zeros((), a.dtype)
    tiny = jnp.finfo(a.dtype).tiny
    for _ in range(squarings):
        norm = jnp.maximum(jnp.linalg.norm(a), tiny)
        a = a / norm
        log_scale = 2.0 * (log_scale + jnp.log(norm))
        a = a @ a
    norm = jnp.maximum(jnp.linalg.norm(a), tiny)
    return jnp.exp((log_scale + jnp.log(norm)) / 2.0**squarings)


def substeps_at(ball, model: Model, rate_Hz: float, most: int):
    """The Runge–Kutta steps per sample for the model's values of the moment (traced): the
    ``substeps_for_rate`` rule on :func:`spectral_radius_bound` of the first-contact Jacobian,
    at most ``most`` (the count for the fastest values the caller allows: a fit's range
    corners), at least one. Not differentiated (a count)."""
    ball, model = jax.lax.stop_gradient((ball, model))
    fastest = spectral_radius_bound(first_contact_jacobian(ball, model))
    count = jnp.ceil(fastest / (MAX_RATE_STEP * rate_Hz))
    count = jnp.where(jnp.isfinite(count), count, most)
    return jnp.clip(count, 1, most).astype(jnp.int32)


def _rk4(y, k1, h, args, substeps):
    """``substeps`` classic Runge–Kutta steps of h/substeps from y, with k1 = dy/dt at y given;
    returns the new state and dy/dt there (the next step's k1, and ẏ for Ḟ at the sample: the
    vector field is evaluated four times a substep, never twice at one state). A loop: one copy
    of the vector field in the compiled program, whatever ``substeps`` (a Python int, or a
    traced count: then a loop of that many turns)."""

    def f(yy):
        return RESTITUTION_FIELD(0.0, yy, args)

    step = h / substeps

    def one(_, carry):
        y, k1 = carry
        k2 = f(y + 0.5 * step * k1)
        k3 = f(y + 0.5 * step * k2)
        k4 = f(y + step * k3)
        y = y + (step / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        return y, f(y)

    if isinstance(substeps, int) and substeps == 1:
        return one(0, (y, k1))
    return jax.lax.fori_loop(0, substeps, one, (y, k1))


def _force_and_rate(y, ydot, ball, model):
    """(F, Ḟ, in contact) at state y with ẏ given: Ḟ = ∂F/∂y · ẏ (one forward-mode pass)."""
    force, rate = jax.jvp(lambda yy: floor_force_N(yy, ball, model), (y,), (ydot,))
    inside = y[0] > 0.0
    if model.velocity_dependent:
        inside = inside & (contact_force(y, ball, model) > 0.0)
    return force, rate, inside


class StiffnessKnown:
    """A ball whose Reissner stiffness is computed once, before the sample loop: every field
    reads through to ``ball``, and :func:`rbjax.terms.forces.reissner_stiffness_N_per_m` gives
    ``known_stiffness_N_per_m``. The force laws ask for k in every call (the shell, the damping
    laws that scale with it), so each of the loop's calls of the vector field computed it again
    with its tangents: a third of the fit program's operations, which made its trace and compile
    longer (hunt-crossley+ball-mode: 10 340 → 6 560 StableHLO operations, compile 4.6 → 4.0 s;
    the series element: 8.1 → 6.6 s; a cold ``rbjax fit`` 28.3 → 25.6 s; the outputs to
    round-off, 1.4e-12 at most over a selection's). Only closed over, never a JAX argument."""

    def __init__(self, ball):
        self.ball = ball
        self.known_stiffness_N_per_m = reissner_stiffness_N_per_m(ball)

    def __getattr__(self, name):
        return getattr(self.ball, name)


def record_samples(
    height_m, shift_s, ball, model: Model, rate_Hz: float, num_samples: int, substeps
):
    """(force (N,), dforce/dshift (N,), status) of one impact at the record's samples
    t_i = i/rate_Hz, i < ``num_samples``, the contact starting at ``shift_s`` (see the module
    docstring)."""
    ball = StiffnessKnown(ball)
    dt = 1.0 / rate_Hz
    x = shift_s * rate_Hz + 0.5
    n0 = jnp.floor(x)
    a = n0 + 1.0 - x  # in-contact fraction of the first sample's interval, (0, 1]
    args = (ball, model)
    y0 = initial_state(impact_velocity_m_per_s(height_m), ball, model)
    singular = SINGULAR_FRACTION * singular_deflection_m(ball, model)
    # Sample j of the contact is reached by a step of h_j from the previous one: aΔ/2 to the
    # first sample's in-contact midpoint, (a + 1)Δ/2 to the second sample, Δ after that. The
    # first sample's value is a·F and its shift derivative −F/Δ − (a/2)Ḟ; the others' F and −Ḟ.
    # One loop for all of them: one copy of the vector field in the compiled program.
    j = jnp.arange(num_samples)
    h = jnp.where(j == 0, 0.5 * a * dt, jnp.where(j == 1, 0.5 * (a + 1.0) * dt, dt))
    scale = jnp.where(j == 0, a, 1.0)
    value_rate = jnp.where(j == 0, 1.0 / dt, 0.0)
    rate_rate = jnp.where(j == 0, 0.5 * a, 1.0)

    def step(carry, x):
        y, k, going, bad, singular_hit = carry
        h_j, c_j, d_j, e_j = x
        y_new, k_new = _rk4(y, k, h_j, args, substeps)
        f, r, inside = _force_and_rate(y_new, k_new, ball, model)
        too_close = y_new[0] >= singular
        broken = ~(jnp.all(jnp.isfinite(y_new)) & jnp.isfinite(f) & jnp.isfinite(r)) | too_close
        singular_hit = singular_hit | (going & too_close)
        bad = bad | (going & broken)
        going = going & inside & ~broken
        out = (jnp.where(going, c_j * f, 0.0), jnp.where(going, -(d_j * f + e_j * r), 0.0))
        return (
            jnp.where(going, y_new, y),
            jnp.where(going, k_new, k),
            going,
            bad,
            singular_hit,
        ), out

    false = jnp.asarray(False)
    k0 = RESTITUTION_FIELD(0.0, y0, args)
    (_, _, _, bad, singular_hit), (hist_f, hist_d) = jax.lax.scan(
        step, (y0, k0, jnp.asarray(True), false, false), (h, scale, value_rate, rate_rate)
    )

    # place the contact-relative samples j at record samples n0 + j
    i = jnp.arange(num_samples)
    j = i - n0.astype(jnp.int32)
    valid = (j >= 0) & (j < num_samples)
    jj = jnp.clip(j, 0, num_samples - 1)
    force = jnp.where(valid, hist_f[jj], 0.0)
    d_shift = jnp.where(valid, hist_d[jj], 0.0)
    status = jnp.where(
        singular_hit,
        STATUS_CODES["mass_singularity"],
        jnp.where(bad, STATUS_CODES["solver_failed"], STATUS_CODES["ok"]),
    ).astype(jnp.int32)
    failed = status != 0
    return nan_where(failed, force), nan_where(failed, d_shift), status

"""The predicted force of every record at its own samples, with the fit's Jacobian built from
its structure (the sampled path of the fit; :func:`rbjax.solve.record_samples.record_samples`).

θ = (physical parameters p, one onset shift per record, [one height error per record]). Record
k depends on the physical parameters, on its own shift s_k and on its own height error only, so
of the p + 2K columns of dF/dθ only p + 1 are carried through the solve, and at once for every
record (vmapped over the records, each lane carrying the tangent of its own height): the
physical columns and the record's own height column. The shift columns are not carried at all:
dF(t − s)/ds = −Ḟ, which the solve records beside the force.

:func:`record_forces` is a ``jax.custom_jvp`` whose tangent rule computes that Jacobian once and
returns J·dθ; under ``jax.jacfwd`` (which batches the tangent rule over the columns of θ) the
solve and its p + 1 tangents run once, not once per column.

The Runge–Kutta steps per sample are those the physical parameters of the moment need
(:func:`~rbjax.solve.record_samples.substeps_at`, a count, not differentiated), up to the
structure's ``max_substeps`` (its fit range's fastest corner): a fit spends the steps of the
values it is at, not those of the fastest values it could reach.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from ..solve.record_samples import record_samples, substeps_at


def ball_and_model(s, physical, constants):
    """The (ball, model) of the structure ``s`` with the physical values given."""
    n_all = len(s.physical_positions) + len(s.constant_positions) + 1
    values = jnp.zeros(n_all)
    values = values.at[jnp.array(s.physical_positions)].set(physical)
    if s.constant_positions:
        values = values.at[jnp.array(s.constant_positions)].set(constants)
    _, ball, model = jax.tree_util.tree_unflatten(s.treedef, [values[i] for i in range(n_all)])
    return ball, model


def record_forces(s, theta, constants, heights_m):
    """Forces (K, N) of the K records at their N samples (before the measuring chain)."""
    p, k = len(s.physical_positions), s.n_records

    def substeps(physical):
        if s.max_substeps == 1:
            return 1
        ball, model = ball_and_model(s, physical, constants)
        return substeps_at(ball, model, s.rate_Hz, s.max_substeps)

    def one(physical, height, shift, count):
        ball, model = ball_and_model(s, physical, constants)
        force, d_shift, _ = record_samples(
            height, shift, ball, model, s.rate_Hz, s.n_samples, count
        )
        return force, d_shift

    def split(th):
        dh = th[p + k : p + 2 * k] if s.height_error else jnp.zeros(k)
        return th[:p], th[p : p + k], dh

    @jax.custom_jvp
    def forces(th):
        physical, shifts, dh = split(th)
        count = substeps(physical)
        return jax.vmap(lambda h, sh: one(physical, h, sh, count)[0])(heights_m + dh, shifts)

    @forces.defjvp
    def forces_jvp(primals, tangents):
        (th,), (dth,) = primals, tangents
        physical, shifts, dh = split(th)
        d_physical, d_shifts, d_dh = split(dth)
        count = substeps(physical)

        def per_record(height, shift):
            def g(x):
                force, d_shift = one(
                    x[:p], height + (x[p] if s.height_error else 0.0), shift, count
                )
                return force, (force, d_shift)

            x = jnp.concatenate([physical, jnp.zeros(1)]) if s.height_error else physical
            return jax.jacfwd(g, has_aux=True)(x)

        jac, (force, d_shift) = jax.vmap(per_record)(heights_m + dh, shifts)
        d_force = jac[..., :p] @ d_physical + d_shift * d_shifts[:, None]
        if s.height_error:
            d_force = d_force + jac[..., p] * d_dh[:, None]
        return force, d_force

    return forces(theta)

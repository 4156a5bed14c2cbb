"""What every solve path returns and shares: the status table (codes and names), the per-impact
scalars (:class:`ImpactScalars`), the sampled :class:`Trajectory`, the impact speed √(2 g h_D)
(Eq. 10) and the mass fraction beyond which the dynamic mass counts as singular."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike

G_N_PER_KG = 9.80665  # standard gravity (m/s²), Eq. 10


#: Status codes of an impact; every non-zero status comes with NaN outputs.
STATUS_NAMES = {
    0: "ok",
    1: "step_limit",
    2: "mass_singularity",
    3: "deflection_limit",
    4: "solver_failed",
    5: "recontact",
}


STATUS_CODES = {v: k for k, v in STATUS_NAMES.items()}


#: Fraction of the deflection at which the dynamic mass vanishes (2R for the paper's M(1 − δ/2R);
#: ``rbjax.terms.forces.singular_deflection_m``) at which it is taken as singular.
SINGULAR_FRACTION = 0.999


def impact_velocity_m_per_s(height_m: ArrayLike) -> jax.Array:
    """v0 = √(2 g h_D), the speed at first contact after a free fall from h_D (Eq. 10).

    Args:
        height_m: drop height h_D (m), a scalar or an array.

    Returns:
        The impact speed v0 (m/s), with the shape of ``height_m`` (g = 9.80665 m/s²).
    """
    return jnp.sqrt(2.0 * G_N_PER_KG * height_m)


def nan_where(failed, value):
    """``value`` where ``failed`` is False and NaN where it is True, for the value and for every
    derivative of it: ``value · (1 or NaN)``. (``jnp.where(failed, nan, value)`` would give NaN
    values but derivatives of 0 where the solve failed: a plausible-looking gradient.) Where
    ``failed`` is False the value and its derivatives are the same bits."""
    return value * jnp.where(failed, jnp.nan, 1.0)


class ImpactScalars(eqx.Module):
    """The scalar outputs of one impact (or a batch: every field shares the batch shape).

    Where ``status != 0`` the six float fields are NaN.

    Attributes:
        contact_time_s: duration of the contact (s), first contact to the end of contact.
        peak_force_N: largest floor force (N).
        peak_time_s: time of the force peak after first contact (s).
        restitution: coefficient of restitution, rebound momentum over impact momentum.
        max_deflection_m: largest deflection δ of the shell (m).
        max_compression_time_s: time of the maximum compression after first contact (s).
        status: status code (int32; ``STATUS_NAMES``, 0: ok).
        num_steps: the solve path's count of steps (int32): solver steps of the ODE, force
            evaluations of the quadrature, fixed steps of the phase-angle path.
    """

    contact_time_s: jax.Array
    peak_force_N: jax.Array
    peak_time_s: jax.Array
    restitution: jax.Array
    max_deflection_m: jax.Array
    max_compression_time_s: jax.Array
    status: jax.Array
    num_steps: jax.Array

    @classmethod
    def flagged(cls, status, num_steps, **outputs) -> ImpactScalars:
        """The outputs where ``status`` is 0 (ok) and NaN elsewhere: a failed solve never
        returns plausible-looking numbers. ``outputs``: the six float fields by name."""
        ok = status == 0
        masked = {name: nan_where(~ok, value) for name, value in outputs.items()}
        return cls(
            **masked,
            status=jnp.asarray(status, dtype=jnp.int32),
            num_steps=jnp.asarray(num_steps, dtype=jnp.int32),
        )


class Trajectory(eqx.Module):
    """State and floor force of one impact (or a batch) sampled at given times (0 after contact).

    Where ``status != 0`` (see ``STATUS_NAMES``) the solve failed and the samples are NaN.

    Attributes:
        time_s: the sample times after first contact (s).
        deflection_m: deflection δ of the shell (m) at each time.
        velocity_m_per_s: its rate δ̇ (m/s) at each time.
        force_N: the force on the floor (N) at each time.
        in_contact: True at the samples during contact (False where the solve failed).
        status: status code per impact (int32; 0: ok), with the batch shape.
    """

    time_s: jax.Array
    deflection_m: jax.Array
    velocity_m_per_s: jax.Array
    force_N: jax.Array
    in_contact: jax.Array
    status: jax.Array

"""Where the impact energy goes: the energy balance of one impact (on any floor).

From the equations of motion (``rbjax.solve.ode``) with E′ = ½(M − M_c)Ẋ² + ∫F_c δ̇ dt,

    dE′/dt + F u̇ = −½(M/2R)|δ̇|³ − ½(M/2R)δ̇ u̇² − (1 − w)(M/2R)δ̇² H(δ̇) u̇,

so over the contact ½Mv0² = ½(M − M_c)Ẋ_end² + W_floor + D_flux + W_contact + W_cap with

- W_floor = ∫F u̇ dt, the energy injected into the floor;
- D_flux = ∫½(M/2R)|δ̇|³ dt, lost as mass joins the cap and leaves it again at the relative
  speed δ̇ (inelastic, §2.3);
- W_contact = ∫F_c δ̇ dt: 0 for an elastic ball (the shell and gas forces are conservative
  and δ returns to 0), the damping's loss for a damped one;
- W_cap: the work of the stopped cap's inertia on a moving floor, which the model leaves out
  (the cap moves with the floor, its mass M_c is not added to the floor's), and of the share
  1 − w of the flux the floor force leaves out; 0 on the rigid floor, and for w = 1 of the
  order of (M/2R)v0/Z of W_floor on a floor of impedance Z.

Each integral is an extra state of the ODE, so the balance closes to the solver's tolerance.
M/2R stands for the cap's mass per unit deflection throughout: the wall column μ where the model
has an arrest law (``rbjax.terms.forces.cap_mass_rate_kg_per_m``).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike

from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.forces import dynamic_mass_kg
from ..terms.model import Model
from .inputs import broadcast_inputs, check_inputs
from .ode import final_state, impact_status, solve_phases
from .options import model_from_shortcuts
from .outcome import nan_where
from .solver import Solver
from .vector_field import body_velocity_m_per_s, split_energy


class EnergyBalance(eqx.Module):
    """The terms of the energy balance of an impact (J); ``residual_J`` should be ~0.

    Every field has the broadcast shape of the inputs of :func:`energy_balance`; where
    ``status != 0`` every term but ``impact_energy_J`` is NaN.

    Attributes:
        impact_energy_J: ½Mv0², the kinetic energy at first contact.
        rebound_energy_J: ½(M − M_c)Ẋ², the kinetic energy of the moving part at the end of
            contact.
        floor_energy_J: W_floor = ∫F u̇ dt, the energy injected into the floor (0 on the rigid
            floor).
        flux_loss_J: D_flux = ∫½(M/2R)|δ̇|³ dt, lost as mass joins and leaves the cap.
        contact_work_J: W_contact = ∫F_c δ̇ dt, the damping's loss (0 for an elastic ball).
        cap_work_J: W_cap, the work the model leaves out on a moving floor (0 on the rigid
            floor).
        status: status code per impact (``rbjax.STATUS_NAMES``; 0: ok).
    """

    impact_energy_J: jax.Array
    rebound_energy_J: jax.Array
    floor_energy_J: jax.Array
    flux_loss_J: jax.Array
    contact_work_J: jax.Array
    cap_work_J: jax.Array
    status: jax.Array

    @property
    def residual_J(self):
        """Impact energy less every term it went to."""
        return self.impact_energy_J - (
            self.rebound_energy_J
            + self.floor_energy_J
            + self.flux_loss_J
            + self.contact_work_J
            + self.cap_work_J
        )


def _balance(height_m, ball, model, solver) -> EnergyBalance:
    v0, sols, _, (t_max, y_max) = solve_phases(
        height_m, ball, model, solver, dense=False, peak=False, energy=True
    )
    sol1, _, sol3 = sols
    t_end, y_end = final_state(sol3)
    y_end, acc = split_energy(y_end, model)
    speed = body_velocity_m_per_s(y_end, ball, model)
    rebound = 0.5 * dynamic_mass_kg(y_end[0], ball, model) * speed**2
    status = impact_status((sol1, sol3), y_max[:2], jnp.stack([t_end, rebound, *acc]), ball, model)
    failed = status != 0
    return EnergyBalance(
        impact_energy_J=0.5 * ball.mass_kg * v0**2,
        rebound_energy_J=nan_where(failed, rebound),
        floor_energy_J=nan_where(failed, acc[0]),
        flux_loss_J=nan_where(failed, acc[1]),
        contact_work_J=nan_where(failed, acc[2]),
        cap_work_J=nan_where(failed, acc[3]),
        status=status,
    )


_balance_batch = eqx.filter_jit(eqx.filter_vmap(_balance, in_axes=(0, 0, 0, None)))


def energy_balance(
    height_m: ArrayLike,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    solver: Solver | None = None,
) -> EnergyBalance:
    """The energy balance of the impact from ``height_m`` (see the module docstring).

    Models with elements in series with the shell (``BallMode``, ``SeriesKelvinVoigt``, any
    ``AbstractSeriesElement``) are not covered (their own energy is not accounted for): a
    ``ValueError`` naming them.

    Args:
        height_m: drop height h_D (m), a scalar or an array; ball and model fields may be
            arrays too and broadcast against it.
        ball: the :class:`~rbjax.terms.ball.Ball` (default ``JIS_RUBBER_BALL``).
        model: the :class:`~rbjax.terms.model.Model` (default ``Model()``), without elements in
            series with the shell.
        solver: the :class:`~rbjax.solve.solver.Solver` of the diffrax ODE (default ``Solver()``).

    Returns:
        An :class:`EnergyBalance` with the broadcast shape of the inputs.

    Raises:
        ValueError: a model with elements in series with the shell (named in the message);
            ``height_m`` not finite and > 0, ``ball`` not a ``Ball`` or ``model`` not a
            ``Model`` (the argument named in the message).
        RuntimeError: float64 (``jax_enable_x64``) switched off after importing rbjax.
    """

    check_inputs(height_m, ball)
    model = model_from_shortcuts("energy_balance", model, {})
    if model.series_elements:
        names = ", ".join(f"{e.description()} ({e.name})" for e in model.series_elements)
        raise ValueError(
            f"energy_balance: models with elements in series with the shell are not covered "
            f"(got {names}); valid: none (ball_mode=None, series=None, series_elements=())"
        )
    solver = Solver() if solver is None else solver
    shape, height, flat_ball, flat_model = broadcast_inputs(height_m, ball, model)
    out = _balance_batch(height, flat_ball, flat_model, solver)
    return jax.tree_util.tree_map(lambda x: x.reshape(shape), out)

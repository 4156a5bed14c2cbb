"""Solving one impact, batched: what every path shares (:mod:`~rbjax.solve.outcome`: statuses,
scalars, trajectories; :mod:`~rbjax.solve.inputs`: the checks and the broadcast at the API
edge), the paths as siblings — the diffrax ODE with its events (:mod:`~rbjax.solve.ode`, the
general path and the reference), the quadrature of the undamped rigid-floor impact
(:mod:`~rbjax.solve.quadrature`, histories in :mod:`~rbjax.solve.quadrature_history`), the
phase-angle integration of damped rigid-floor impacts (:mod:`~rbjax.solve.angle`) and histories
sampled inside a fixed-step solve (:mod:`~rbjax.solve.sampled`) — with
:func:`~rbjax.solve.simulate.simulate` choosing among them (:mod:`~rbjax.solve.path`) and
running the path chosen (:mod:`~rbjax.solve.path_runner`), the energy balance
(:mod:`~rbjax.solve.energy`) and batched evaluation on the fastest path
(:mod:`~rbjax.solve.batch`); how the ODE is integrated is a
:class:`~rbjax.solve.solver.Solver`. Concrete batches of both are cut in chunks split over the
local devices, each device running its own program (:mod:`~rbjax.solve.devices`), where an
:class:`~rbjax.solve.parallel.Parallel` says (:mod:`~rbjax.solve.parallel`: where work runs,
and the one planner that cuts rows into device chunks, tasks and job-array parts)."""

from .angle import impact_angle
from .batch import evaluate, evaluate_jacobian
from .energy import EnergyBalance, energy_balance
from .inputs import PAPER_DURATION_S, PAPER_RATE_Hz, check_inputs
from .ode import impact_batch, trajectory_batch
from .options import PATHS, EvaluationSpec, ModelShortcuts
from .outcome import (
    STATUS_CODES,
    STATUS_NAMES,
    ImpactScalars,
    Trajectory,
    impact_velocity_m_per_s,
)
from .parallel import Parallel
from .quadrature import impact_quadrature, impact_quadrature_batch
from .quadrature_history import force_history_quadrature
from .recontact import recontact_horizon_s
from .sampled import sampled_history
from .simulate import ImpactResult, force_history, simulate, trajectory
from .solver import Solver

__all__ = [
    "impact_angle",
    "evaluate",
    "evaluate_jacobian",
    "EvaluationSpec",
    "Parallel",
    "ModelShortcuts",
    "EnergyBalance",
    "energy_balance",
    "PAPER_DURATION_S",
    "PAPER_RATE_Hz",
    "check_inputs",
    "impact_batch",
    "recontact_horizon_s",
    "trajectory_batch",
    "STATUS_CODES",
    "STATUS_NAMES",
    "ImpactScalars",
    "Trajectory",
    "impact_velocity_m_per_s",
    "impact_quadrature",
    "impact_quadrature_batch",
    "force_history_quadrature",
    "sampled_history",
    "PATHS",
    "ImpactResult",
    "force_history",
    "simulate",
    "Solver",
    "trajectory",
]

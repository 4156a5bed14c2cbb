"""rbjax: the blocked force of the JIS/ISO rubber-ball heavy impact source, in JAX.

Importing rbjax switches on float64 in JAX (``jax_enable_x64``); see ``rbjax._x64``.
"""

from . import _x64  # noqa: F401  (float64 before anything else touches JAX)
from .solve.energy import EnergyBalance, energy_balance
from .solve.options import EvaluationSpec
from .solve.outcome import (
    STATUS_CODES,
    STATUS_NAMES,
    ImpactScalars,
    Trajectory,
    impact_velocity_m_per_s,
)
from .solve.simulate import ImpactResult, simulate, trajectory
from .terms.ball import JIS_RUBBER_BALL, Ball
from .terms.ball_mode import BallMode
from .terms.damping import DAMPING_MODELS, AbstractDamping, HuntCrossley, KelvinVoigt, Zener
from .terms.declare import Parameter
from .terms.floors.kinds import Dashpot, InfinitePlate, ModalFloor, Rigid, plate_impedance_Ns_per_m
from .terms.forces import (
    CubicStiffening,
    contact_area_m2,
    gas_force_N,
    reissner_stiffness_N_per_m,
    shell_force_N,
)
from .terms.model import Model, Solver
from .terms.parameters import parameter_names, parameter_table
from .terms.series_kelvin_voigt import SeriesKelvinVoigt

__version__ = "0.1.0"

__all__ = [
    "Ball",
    "JIS_RUBBER_BALL",
    "AbstractDamping",
    "DAMPING_MODELS",
    "CubicStiffening",
    "Parameter",
    "parameter_names",
    "parameter_table",
    "HuntCrossley",
    "KelvinVoigt",
    "Zener",
    "BallMode",
    "SeriesKelvinVoigt",
    "Rigid",
    "Dashpot",
    "InfinitePlate",
    "ModalFloor",
    "plate_impedance_Ns_per_m",
    "EnergyBalance",
    "energy_balance",
    "Model",
    "Solver",
    "EvaluationSpec",
    "ImpactResult",
    "ImpactScalars",
    "Trajectory",
    "STATUS_CODES",
    "STATUS_NAMES",
    "simulate",
    "trajectory",
    "impact_velocity_m_per_s",
    "reissner_stiffness_N_per_m",
    "gas_force_N",
    "shell_force_N",
    "contact_area_m2",
]

"""rbjax: the blocked force of the JIS/ISO rubber-ball heavy impact source, in JAX.

Importing rbjax switches on float64 in JAX (``jax_enable_x64``); see ``rbjax._x64``.
"""

from . import _x64  # noqa: F401  (float64 before anything else touches JAX)
from .ball import JIS_RUBBER_BALL, Ball
from .ball_mode import BallMode
from .damping import DAMPING_MODELS, AbstractDamping, HuntCrossley, KelvinVoigt, Zener
from .energy import EnergyBalance, energy_balance
from .floor import Dashpot, InfinitePlate, ModalFloor, Rigid, plate_impedance_Ns_per_m
from .forces import (
    CubicStiffening,
    contact_area_m2,
    gas_force_N,
    reissner_stiffness_N_per_m,
    shell_force_N,
)
from .impact import (
    STATUS_CODES,
    STATUS_NAMES,
    ImpactScalars,
    Trajectory,
    impact_velocity_m_per_s,
)
from .model import Model, Solver
from .parameters import Parameter, parameter_names, parameter_table
from .simulate import ImpactResult, simulate, trajectory

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
    "Rigid",
    "Dashpot",
    "InfinitePlate",
    "ModalFloor",
    "plate_impedance_Ns_per_m",
    "EnergyBalance",
    "energy_balance",
    "Model",
    "Solver",
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

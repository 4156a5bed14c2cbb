"""rbjax: the blocked force of the JIS/ISO rubber-ball heavy impact source, in JAX.

Importing rbjax switches on float64 in JAX (``jax_enable_x64``), here, once; see ``rbjax._x64``.

The names below load on first use (PEP 562 ``__getattr__``): ``import rbjax`` itself imports
neither JAX nor SciPy, so that the command line answers ``rbjax --help`` at once; the first
``rbjax.simulate`` (or any other name, or ``import rbjax.fit``) imports what it needs.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import TYPE_CHECKING

__version__ = "0.2.0"

# float64 before anything touches JAX, here and only here (every rbjax module relies on it;
# entry points check it with rbjax._x64.require_x64): JAX reads JAX_ENABLE_X64 when it is first
# imported, and where it already is, the flag is set now. (Not by importing JAX always: JAX
# costs ~1 s at import, which `rbjax --help` does not need.)
if "jax" in sys.modules:
    sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    os.environ["JAX_ENABLE_X64"] = "1"

if TYPE_CHECKING:
    from .solve.energy import EnergyBalance, energy_balance
    from .solve.options import EvaluationSpec
    from .solve.outcome import (
        STATUS_CODES,
        STATUS_NAMES,
        ImpactScalars,
        Trajectory,
        impact_velocity_m_per_s,
    )
    from .solve.parallel import Parallel
    from .solve.simulate import ImpactResult, simulate, trajectory
    from .solve.solver import Solver
    from .terms.arrest import WaveLimitedArrest
    from .terms.ball import JIS_RUBBER_BALL, Ball
    from .terms.ball_mode import BallMode
    from .terms.contact_layer import ContactLayer
    from .terms.damping import DAMPING_MODELS, AbstractDamping, HuntCrossley, KelvinVoigt, Zener
    from .terms.declare import Parameter
    from .terms.floors.kinds import (
        Dashpot,
        InfinitePlate,
        ModalFloor,
        Rigid,
        plate_impedance_Ns_per_m,
    )
    from .terms.forces import (
        CubicStiffening,
        contact_area_m2,
        gas_force_N,
        reissner_stiffness_N_per_m,
        shell_force_N,
    )
    from .terms.model import Model
    from .terms.parameters import parameter_names, parameter_table
    from .terms.series_kelvin_voigt import SeriesKelvinVoigt

#: The module of each public name (imported on first use).
_WHERE = {
    "solve.energy": ("EnergyBalance", "energy_balance"),
    "solve.options": ("EvaluationSpec",),
    "solve.outcome": (
        "STATUS_CODES",
        "STATUS_NAMES",
        "ImpactScalars",
        "Trajectory",
        "impact_velocity_m_per_s",
    ),
    "solve.parallel": ("Parallel",),
    "solve.simulate": ("ImpactResult", "simulate", "trajectory"),
    "solve.solver": ("Solver",),
    "terms.arrest": ("WaveLimitedArrest",),
    "terms.ball": ("JIS_RUBBER_BALL", "Ball"),
    "terms.ball_mode": ("BallMode",),
    "terms.contact_layer": ("ContactLayer",),
    "terms.damping": ("DAMPING_MODELS", "AbstractDamping", "HuntCrossley", "KelvinVoigt", "Zener"),
    "terms.declare": ("Parameter",),
    "terms.floors.kinds": (
        "Dashpot",
        "InfinitePlate",
        "ModalFloor",
        "Rigid",
        "plate_impedance_Ns_per_m",
    ),
    "terms.forces": (
        "CubicStiffening",
        "contact_area_m2",
        "gas_force_N",
        "reissner_stiffness_N_per_m",
        "shell_force_N",
    ),
    "terms.model": ("Model",),
    "terms.parameters": ("parameter_names", "parameter_table"),
    "terms.series_kelvin_voigt": ("SeriesKelvinVoigt",),
}
_MODULE_OF = {name: module for module, names in _WHERE.items() for name in names}
#: The packages and helper modules, importable as attributes (``rbjax.fit``) as well.
_SUBMODULES = frozenset(
    ("terms", "spectrum", "solve", "room", "data", "fit", "studies", "report", "plot", "text")
)

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
    "ContactLayer",
    "WaveLimitedArrest",
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
    "Parallel",
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


def __getattr__(name: str) -> object:
    if name in _MODULE_OF:
        value = getattr(importlib.import_module(f".{_MODULE_OF[name]}", __name__), name)
        globals()[name] = value  # the next look-up is an ordinary attribute
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_MODULE_OF, *_SUBMODULES})

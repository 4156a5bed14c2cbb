"""The physics of the impact, one term a module (paper §2): the ball and its shell stiffness
(:mod:`~rbjax.terms.ball`, :mod:`~rbjax.terms.forces`: Reissner stiffness, gas force, dynamic
mass, momentum flux), the damping laws (:mod:`~rbjax.terms.damping`), the ball's own mode
(:mod:`~rbjax.terms.ball_mode`) and its overdamped limit
(:mod:`~rbjax.terms.series_kelvin_voigt`), both elements in series with the shell
(:mod:`~rbjax.terms.series_element`: a new one is one class), the floors and their builders
(:mod:`rbjax.terms.floors`), the model that assembles them (:mod:`~rbjax.terms.model`), and the
parameter layer: each term's declarations (:mod:`~rbjax.terms.declare`) and the walker over a
whole impact (:mod:`~rbjax.terms.parameters`). :mod:`~rbjax.terms.serialize` writes and reads
them; :mod:`~rbjax.terms.shell_modes` holds the free shell's eigenfrequencies.

Nothing here solves an impact: the solvers are :mod:`rbjax.solve`.
"""

from .arrest import ARREST_LAWS, AbstractArrest, WaveLimitedArrest, column_mass_rate_kg_per_m
from .ball import JIS_RUBBER_BALL, Ball, validate_ball
from .ball_mode import BallMode, from_modal_mass
from .contact_layer import ContactLayer
from .damping import (
    DAMPING_MODELS,
    AbstractDamping,
    HuntCrossley,
    KelvinVoigt,
    Zener,
    damping_ratio,
)
from .declare import Parameter, check_declared, declarations
from .floors import (
    FLOOR_MODELS,
    MATERIALS,
    AbstractFloor,
    Dashpot,
    FloatingFloor,
    InfinitePlate,
    Material,
    ModalFloor,
    Rigid,
    floating_floor,
    floor_from_mapping,
    floor_preset,
    load_floor,
    load_named_floor,
    material,
    plate,
    plate_impedance_Ns_per_m,
    simply_supported_plate_modes,
)
from .forces import (
    CubicStiffening,
    cap_volume_m3,
    contact_area_m2,
    contact_force_N,
    dynamic_mass_kg,
    gas_force_N,
    momentum_flux_N,
    reissner_stiffness_N_per_m,
    shell_force_N,
)
from .model import Model, structure_model
from .parameters import (
    ParameterInfo,
    canonical_name,
    from_vector,
    parameter_names,
    parameter_table,
    replace,
    to_vector,
)
from .serialize import load_params, model_from_dict, model_to_dict, save_params
from .series_element import SERIES_ELEMENTS, AbstractSeriesElement
from .series_kelvin_voigt import SeriesKelvinVoigt
from .shell_modes import ShellModes, shell_frequencies_Hz

__all__ = [
    "ARREST_LAWS",
    "AbstractArrest",
    "WaveLimitedArrest",
    "column_mass_rate_kg_per_m",
    "ContactLayer",
    "JIS_RUBBER_BALL",
    "Ball",
    "validate_ball",
    "BallMode",
    "from_modal_mass",
    "SeriesKelvinVoigt",
    "SERIES_ELEMENTS",
    "AbstractSeriesElement",
    "DAMPING_MODELS",
    "AbstractDamping",
    "HuntCrossley",
    "KelvinVoigt",
    "Zener",
    "damping_ratio",
    "Parameter",
    "check_declared",
    "declarations",
    "FLOOR_MODELS",
    "MATERIALS",
    "AbstractFloor",
    "Dashpot",
    "FloatingFloor",
    "InfinitePlate",
    "Material",
    "ModalFloor",
    "Rigid",
    "floating_floor",
    "floor_from_mapping",
    "floor_preset",
    "load_floor",
    "load_named_floor",
    "material",
    "plate",
    "plate_impedance_Ns_per_m",
    "simply_supported_plate_modes",
    "CubicStiffening",
    "cap_volume_m3",
    "contact_area_m2",
    "contact_force_N",
    "dynamic_mass_kg",
    "gas_force_N",
    "momentum_flux_N",
    "reissner_stiffness_N_per_m",
    "shell_force_N",
    "Model",
    "structure_model",
    "ParameterInfo",
    "canonical_name",
    "from_vector",
    "parameter_names",
    "parameter_table",
    "replace",
    "to_vector",
    "load_params",
    "model_from_dict",
    "model_to_dict",
    "save_params",
    "ShellModes",
    "shell_frequencies_Hz",
]

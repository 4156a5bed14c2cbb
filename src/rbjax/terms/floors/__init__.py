"""Floors, a family of terms like the damping laws: the kinds of floor the ball can strike
(:mod:`~rbjax.terms.floors.kinds`: rigid, a dashpot, an infinite plate, modes at the drive
point, and a floating floor of declared parameters: :mod:`~rbjax.terms.floors.floating`), the
building materials (:mod:`~rbjax.terms.floors.materials`), the modal builders
(:mod:`~rbjax.terms.floors.modes`: a simply supported plate, a floating floor) and the named
presets and floor files (:mod:`~rbjax.terms.floors.presets`)."""

from .floating import FloatingFloor
from .kinds import (
    FLOOR_MODELS,
    AbstractFloor,
    AbstractModalFloor,
    Dashpot,
    InfinitePlate,
    ModalFloor,
    Rigid,
    plate_impedance_Ns_per_m,
)
from .materials import MATERIALS, Material, cross_laminated_youngs_Pa, material
from .modes import floating_floor, simply_supported_plate_modes
from .presets import (
    FLOOR_PRESETS,
    PLATE_PRESETS,
    floor_from_mapping,
    floor_preset,
    load_floor,
    load_named_floor,
    plate,
)

__all__ = [
    "FLOOR_MODELS",
    "AbstractFloor",
    "AbstractModalFloor",
    "Dashpot",
    "FloatingFloor",
    "InfinitePlate",
    "ModalFloor",
    "Rigid",
    "plate_impedance_Ns_per_m",
    "MATERIALS",
    "Material",
    "cross_laminated_youngs_Pa",
    "material",
    "floating_floor",
    "simply_supported_plate_modes",
    "FLOOR_PRESETS",
    "PLATE_PRESETS",
    "floor_from_mapping",
    "floor_preset",
    "load_floor",
    "load_named_floor",
    "plate",
]

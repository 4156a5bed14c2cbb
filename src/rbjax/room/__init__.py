"""From the ball's force to the rating in the room below (docs/guides/room.md): the floor's
injected energy (:mod:`~rbjax.room.injection`), radiation (:mod:`~rbjax.room.radiation`), the finite
slab's modes at low frequencies (:mod:`~rbjax.room.finite_slab`, :mod:`~rbjax.room.mode_radiation`),
the receiving room and the Fast detector (:mod:`~rbjax.room.detector`), chained in
:mod:`~rbjax.room.chain` (scene terms in :mod:`~rbjax.room.scene`), the standards' arithmetic
(:mod:`~rbjax.room.standards`: ISO 16283-2 normalisation, ISO 717-2 Annex D rating),
``impact_sound`` (:mod:`~rbjax.room.result`) and its energy average over several drop
positions, ``position_average`` (:mod:`~rbjax.room.positions`).

Layer: above ``solve`` (it simulates the impact) and ``spectrum``; below ``data``."""

from .chain import (
    RoomLevels,
    contact_samples,
    fast_levels_dB,
    rating_unrounded_dB,
    room_levels,
    slab_mode_orders,
)
from .positions import PositionAverage, energy_average_dB, position_average
from .result import ImpactSound, impact_sound
from .scene import Chain, ReceivingRoom, RoomChainError, Slab
from .standards import (
    FAST_TIME_CONSTANT_s,
    REFERENCE_REVERBERATION_s,
    REFERENCE_VOLUME_m3,
    a_weighted_sum_dB,
    fast_correction_dB,
    fast_max_of_decay,
    normalised_level_dB,
    rating_dB,
    round_rating,
)

__all__ = [
    "RoomLevels",
    "contact_samples",
    "fast_levels_dB",
    "rating_unrounded_dB",
    "room_levels",
    "slab_mode_orders",
    "ImpactSound",
    "impact_sound",
    "PositionAverage",
    "energy_average_dB",
    "position_average",
    "Chain",
    "ReceivingRoom",
    "RoomChainError",
    "Slab",
    "FAST_TIME_CONSTANT_s",
    "REFERENCE_REVERBERATION_s",
    "REFERENCE_VOLUME_m3",
    "a_weighted_sum_dB",
    "fast_correction_dB",
    "fast_max_of_decay",
    "normalised_level_dB",
    "rating_dB",
    "round_rating",
]

"""The ball dropped at several positions on the slab, as a measurement does: the band levels
L_i,Fmax of each position averaged in energy, L = 10 lg((1/n) Σ_j 10^{L_j/10}), and the rating
of the average (ISO 717-2:2020 Annex D).

JIS A 1418-2 and ISO 16283-2 drop the ball at several impact points spread over the floor
(ISO 16283-2: four or more; on a joisted lightweight floor one of them over a joist and one at
the centre) and average the maximum levels L_i,Fmax,j of the m points in energy before rating
(as summarised by Sonora srl, "La palla in gomma per misurare il livello massimo standardizzato
di pressione sonora da impatto", sonorasrl.com; the standard's text was not reachable here);
one drive point (the centre, the default
of ``Slab``) hears the slab's modes through their shapes there (a mode with a node at the
centre is not driven), so a rating of a bare slab moves with the point. Which points, and how
many, is the caller's choice: ``positions_m`` takes them as (x, y) from a corner of the slab.
The normalised levels are averaged the same way (the normalisation is the same offset for
every position).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .chain import rating_levels
from .figure import plot_position_average
from .result import ImpactSound, impact_sound
from .scene import ReceivingRoom, Slab
from .standards import a_weighted_sum_dB, round_rating


def energy_average_dB(levels_dB, axis: int = 0) -> np.ndarray:
    """10 lg((1/n) Σ 10^{L/10}) along ``axis`` (−inf levels, silent bands, add nothing).

    Args:
        levels_dB: the levels, dB (an array; ``axis`` holds the positions).
        axis: the axis to average over.

    Returns:
        The energy-average levels, dB, a numpy array without ``axis``.
    """
    levels = np.asarray(levels_dB, dtype=float)
    return 10.0 * np.log10(np.mean(10.0 ** (levels / 10.0), axis=axis))


@dataclasses.dataclass(frozen=True)
class PositionAverage:
    """The ball dropped at each of ``positions_m``: the band levels averaged in energy and the
    ratings of the average (module docstring).

    Attributes:
        bands: the nominal mid-band frequencies, Hz (labels such as ``"63"``).
        positions_m: the drop positions (x, y), m from a corner of the slab.
        level_dB: L_i,Fmax per band averaged in energy over the positions, dB.
        normalised_dB: the normalised levels averaged the same way, dB.
        LiA_Fmax_dB: the rating L_iA,Fmax of ``level_dB``, whole dB.
        LiA_Fmax_normalised_dB: the rating of ``normalised_dB``, whole dB.
        LiA_Fmax_unrounded_dB: the rating of ``level_dB`` before rounding, dB.
        results: the :class:`~rbjax.room.result.ImpactSound` of each position, in order.
        warnings: the positions' warnings, each once, in order of first appearance.
    """

    bands: tuple[str, ...]
    positions_m: tuple[tuple[float, float], ...]
    level_dB: tuple[float, ...]
    normalised_dB: tuple[float, ...]
    LiA_Fmax_dB: int
    LiA_Fmax_normalised_dB: int
    LiA_Fmax_unrounded_dB: float
    results: tuple[ImpactSound, ...] = dataclasses.field(repr=False, compare=False)
    warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        return {
            "bands_Hz": list(self.bands),
            "positions_m": [list(p) for p in self.positions_m],
            "Li_Fmax_dB": list(self.level_dB),
            "Li_Fmax_normalised_dB": list(self.normalised_dB),
            "LiA_Fmax_dB": self.LiA_Fmax_dB,
            "LiA_Fmax_normalised_dB": self.LiA_Fmax_normalised_dB,
            "LiA_Fmax_unrounded_dB": self.LiA_Fmax_unrounded_dB,
            "positions": [r.to_dict() for r in self.results],
            "warnings": list(self.warnings),
        }

    def plot(self, path=None):
        """The band levels of each position (thin) and their energy average (thick); saved to
        ``path`` when given; returns the figure."""
        return plot_position_average(self, path)


def _point(index: int, position) -> tuple[float, float]:
    """``position`` as (x, y) floats (the named error otherwise)."""
    try:
        x, y = (float(v) for v in position)
    except (TypeError, ValueError):
        raise ValueError(
            f"positions_m[{index}]={position!r} is not a pair (x, y) of numbers, m"
        ) from None
    return x, y


def _at(slab: Slab, index: int, point: tuple[float, float]) -> Slab:
    """The slab driven at ``point`` (its other fields kept)."""
    fields = {f.name: getattr(slab, f.name) for f in dataclasses.fields(slab)}
    try:
        return Slab(**(fields | {"drive_x_m": point[0], "drive_y_m": point[1]}))
    except ValueError as err:
        raise ValueError(f"positions_m[{index}]=({point[0]:g}, {point[1]:g}): {err}") from None


def position_average(slab: Slab, room: ReceivingRoom, positions_m, **kwargs) -> PositionAverage:
    """The ball dropped at each of ``positions_m`` on ``slab``: :func:`impact_sound` at each,
    the band levels averaged in energy and rated (module docstring).

    Args:
        slab: the :class:`~rbjax.room.scene.Slab` (its own drive point is replaced by each
            position).
        room: the :class:`~rbjax.room.scene.ReceivingRoom`.
        positions_m: the drop positions, a sequence of (x, y), m from a corner; at least one,
            each strictly inside the slab.
        **kwargs: the other arguments of :func:`~rbjax.room.result.impact_sound` (``floor``,
            ``height_m``, ``ball``, ``chain``, ``fraction``, ``rate_Hz``, ``name``).

    Returns:
        The :class:`PositionAverage`.

    Raises:
        ValueError: no position, a position that is not a pair of numbers or not strictly
            inside the slab (named by its index), or an error of :func:`impact_sound`.
    """
    points = [_point(i, p) for i, p in enumerate(positions_m)]
    if not points:
        raise ValueError("positions_m=[] holds no position; give at least one (x, y), m")
    slabs = [_at(slab, i, p) for i, p in enumerate(points)]
    results = tuple(impact_sound(s, room, **kwargs) for s in slabs)
    fraction = kwargs.get("fraction", 1)
    level = energy_average_dB([r.level_dB for r in results])
    normalised = energy_average_dB([r.normalised_dB for r in results])
    rating = float(a_weighted_sum_dB(rating_levels(level, fraction), fraction))
    return PositionAverage(
        bands=results[0].bands,
        positions_m=tuple(points),
        level_dB=tuple(level.tolist()),
        normalised_dB=tuple(normalised.tolist()),
        LiA_Fmax_dB=round_rating(rating),
        LiA_Fmax_normalised_dB=round_rating(
            a_weighted_sum_dB(rating_levels(normalised, fraction), fraction)
        ),
        LiA_Fmax_unrounded_dB=rating,
        results=results,
        warnings=tuple(dict.fromkeys(w for r in results for w in r.warnings)),
    )

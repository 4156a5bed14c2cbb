"""``impact_sound``: the room chain on concrete inputs, with the rating, the validity warnings
and a frozen result that prints, writes JSON and draws itself."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._validate import as_float
from ..solve.outcome import STATUS_NAMES
from ..solve.simulate import simulate, trajectory
from ..solve.solver import Solver
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.floors.floating import FloatingFloor
from ..terms.floors.kinds import AbstractModalFloor
from ..terms.model import Model
from .chain import (
    RoomLevels,
    bands,
    fast_levels_dB,
    modal_bands,
    rating_unrounded_dB,
    room_levels,
)
from .figure import plot_impact_sound
from .finite_slab import bending_speed_constant
from .scene import Chain, ReceivingRoom, Slab
from .standards import round_rating

#: A floor decay counts as short against the room's when its 60 dB decay time is below this
#: share of T (where ``Chain(floor_decay=False)`` is used).
SHORT_DECAY_SHARE = 0.3


@dataclasses.dataclass(frozen=True)
class ImpactSound:
    """L_i,Fmax per band, normalised, and the ratings L_iA,Fmax (ISO 717-2:2020 Annex D).

    ``warnings`` lists where the prediction is outside the chain's validity
    (``rbjax.room.chain``).

    Attributes:
        bands: the nominal mid-band frequencies, Hz (labels such as ``"63"``).
        level_dB: L_i,Fmax per band in the receiving room, dB.
        normalised_dB: the levels normalised to V0 = 50 m³, T0 = 0.5 s, dB.
        peak_time_s: the time of each band's maximum after the impact, s.
        LiA_Fmax_dB: the rating L_iA,Fmax of ``level_dB``, whole dB.
        LiA_Fmax_normalised_dB: the rating of ``normalised_dB``, whole dB.
        LiA_Fmax_unrounded_dB: the rating of ``level_dB`` before rounding, dB.
        volume_m3: the room's volume, m³.
        reverberation_s: the room's reverberation time per band, s.
        height_m: the drop height, m.
        floor: the name of the floor (``name`` of :func:`impact_sound`).
        injected_energy_J: the energy injected into the floor, summed over its sources, J.
        radiated_energy_J: the share of it radiated into the room, J.
        warnings: where the prediction is outside the chain's validity.
        levels: the :class:`~rbjax.room.chain.RoomLevels` behind the result.
        force_N: the force history of the impact, N.
        rate_Hz: its sampling rate, Hz.
        chain: the :class:`~rbjax.room.scene.Chain` of the result.
    """

    bands: tuple[str, ...]
    level_dB: tuple[float, ...]
    normalised_dB: tuple[float, ...]
    peak_time_s: tuple[float, ...]
    LiA_Fmax_dB: int
    LiA_Fmax_normalised_dB: int
    LiA_Fmax_unrounded_dB: float
    volume_m3: float
    reverberation_s: tuple[float, ...]
    height_m: float
    floor: str
    injected_energy_J: float
    radiated_energy_J: float
    warnings: tuple[str, ...]
    levels: RoomLevels = dataclasses.field(repr=False, compare=False)
    force_N: np.ndarray = dataclasses.field(
        repr=False, compare=False, default_factory=lambda: np.zeros(0)
    )
    rate_Hz: float = 44100.0
    chain: Chain = Chain()

    def to_dict(self) -> dict:
        return {
            "floor": self.floor, "height_m": self.height_m, "volume_m3": self.volume_m3,
            "reverberation_s": list(self.reverberation_s), "bands_Hz": list(self.bands),
            "Li_Fmax_dB": list(self.level_dB), "Li_Fmax_normalised_dB": list(self.normalised_dB),
            "peak_time_s": list(self.peak_time_s), "LiA_Fmax_dB": self.LiA_Fmax_dB,
            "LiA_Fmax_normalised_dB": self.LiA_Fmax_normalised_dB,
            "LiA_Fmax_unrounded_dB": self.LiA_Fmax_unrounded_dB,
            "injected_energy_J": self.injected_energy_J,
            "radiated_energy_J": self.radiated_energy_J,
            "warnings": list(self.warnings),
        }  # fmt: skip

    def fast_levels_dB(self, times_s) -> np.ndarray:
        """The Fast-weighted level of each band at ``times_s`` (bands × times;
        ``rbjax.room.chain.fast_levels_dB``)."""
        return np.asarray(fast_levels_dB(self.levels, self.chain, times_s))

    def plot(self, path=None):
        """Band levels (measured-room and normalised) and the Fast level against time."""
        return plot_impact_sound(self, path)


def _contact_samples(height_m, ball, slab, floor, rate_Hz) -> int:
    """Samples over the contact: twice the rigid-floor contact time (the cheap quadrature),
    doubled while the ball is still in contact at the last sample."""
    model = Model(floor=slab.plate if floor is None else floor)
    n = (
        int(math.ceil(2.0 * float(np.asarray(simulate(height_m, ball).contact_time_s)) * rate_Hz))
        + 2
    )
    for _ in range(8):
        traj = trajectory(height_m, np.arange(n) / rate_Hz, ball, model)
        status = int(np.asarray(traj.status))
        if status != 0:
            raise RuntimeError(f"the impact on the floor failed: {STATUS_NAMES[status]}")
        if not bool(np.asarray(traj.in_contact)[-1]):
            return n
        n *= 2
    raise RuntimeError(f"the contact lasts longer than {n / rate_Hz:.3g} s")


def impact_sound(
    slab: Slab,
    room: ReceivingRoom,
    *,
    floor: AbstractModalFloor | None = None,
    height_m: float = 1.0,
    ball=JIS_RUBBER_BALL,
    chain: Chain = Chain(),
    fraction: int = 1,
    rate_Hz: float = 44100.0,
    name: str = "slab",
) -> ImpactSound:
    """L_i,Fmax, normalised levels and L_iA,Fmax of the ball dropped from ``height_m`` on the
    bare ``slab`` (``floor=None``) or on a modal ``floor`` radiating through ``slab`` into
    ``room`` (``rbjax.room.chain``).

    Args:
        slab: the :class:`~rbjax.room.scene.Slab` that radiates into the room.
        room: the :class:`~rbjax.room.scene.ReceivingRoom`.
        floor: a modal floor over the slab that the ball strikes (``ModalFloor``,
            ``FloatingFloor``); ``None``: the bare slab.
        height_m: the drop height, m.
        ball: the ball (default: ``JIS_RUBBER_BALL``).
        chain: the steps of the chain taken (:class:`~rbjax.room.scene.Chain`).
        fraction: 1 (octaves 31.5 Hz–1 kHz) or 3 (one-third octaves 25 Hz–1.25 kHz).
        rate_Hz: the sampling rate of the force, Hz.
        name: the floor's name in the result (``ImpactSound.floor``).

    Returns:
        The :class:`ImpactSound`.

    Raises:
        RuntimeError: the impact's solve failed, or the contact lasts beyond the samples tried.
        RoomChainError: a floor the chain cannot follow, ``fraction`` not 1 or 3, or a
            reverberation time per band whose length is not the bands'.
        ValueError: a non-finite level in a rating band (a band without a source, e.g. of a
            modal floor without a mode in it).
    """
    n = _contact_samples(height_m, ball, slab, floor, rate_Hz)
    lv = room_levels(
        slab,
        room,
        floor=floor,
        height_m=height_m,
        ball=ball,
        chain=chain,
        fraction=fraction,
        rate_Hz=rate_Hz,
        n_samples=n,
        solver=Solver(),
    )
    labels, _, edges = bands(fraction)
    t_band = np.asarray(room.reverberation_per_band(labels))
    warnings = _warnings(lv, labels, edges, room, chain, floor, t_band)
    if floor is None:
        warnings += _modal_overlap_warnings(slab, fraction, chain)
    injected = np.asarray(lv.injected_J)
    return ImpactSound(
        bands=tuple(labels),
        level_dB=tuple(np.asarray(lv.level_dB).tolist()),
        normalised_dB=tuple(np.asarray(lv.normalised_dB).tolist()),
        peak_time_s=tuple(np.asarray(lv.peak_time_s).tolist()),
        LiA_Fmax_dB=round_rating(rating_unrounded_dB(lv, fraction)),
        LiA_Fmax_normalised_dB=round_rating(rating_unrounded_dB(lv, fraction, normalised=True)),
        LiA_Fmax_unrounded_dB=float(rating_unrounded_dB(lv, fraction)),
        volume_m3=as_float(room.volume_m3),
        reverberation_s=tuple(t_band.tolist()),
        height_m=float(height_m),
        floor=name,
        injected_energy_J=float(np.sum(injected)),
        radiated_energy_J=float(np.sum(injected * np.asarray(lv.radiated_fraction))),
        warnings=tuple(warnings),
        levels=lv,
        force_N=np.asarray(
            trajectory(
                height_m,
                np.arange(n) / rate_Hz,
                ball,
                Model(floor=slab.plate if floor is None else floor),
            ).force_N
        ),
        rate_Hz=float(rate_Hz),
        chain=chain,
    )


def _modal_overlap_warnings(slab: Slab, fraction: int, chain: Chain) -> list[str]:
    """The bands the infinite plate follows where the slab's modal overlap M = f η_s n(f) is
    below 1 (n(f) = (l_x l_y/2)√(m″/B′), the plate's modal density: Cremer, Heckl & Petersson
    §5.5): there the infinite plate is the frequency average of a response that scatters about
    it from slab to slab and from point to point."""
    labels, centres, _ = bands(fraction)
    plate = ~modal_bands(fraction) if chain.slab == "modal" else np.ones(len(labels), dtype=bool)
    density = (
        as_float(slab.length_x_m)
        * as_float(slab.length_y_m)
        / (2.0 * float(np.asarray(bending_speed_constant(slab))))
    )
    overlap = centres * np.asarray(slab.structural_loss(centres)) * density
    few = [lab for lab, m, p in zip(labels, overlap, plate) if p and m < 1.0]
    if not few:
        return []
    return [
        f"bands {', '.join(few)} Hz follow the infinite plate where the slab's modal overlap is "
        "below 1: their levels are a frequency average that a given slab and drive point scatter "
        "about"
    ]


def _warnings(
    lv: RoomLevels, labels, edges, room: ReceivingRoom, chain: Chain, floor, t_band
) -> list[str]:
    out = []
    fs = room.schroeder_frequency_Hz()
    if fs is not None:
        below = [
            lab
            for lab, hi, f in zip(labels, edges[1], np.broadcast_to(fs, (len(labels),)))
            if hi < f
        ]
        if below:
            out.append(
                f"bands {', '.join(below)} Hz lie below the room's Schroeder frequency: the "
                "diffuse-field level is a room average there"
            )
    floor_t60 = 6.0 * math.log(10.0) / np.asarray(lv.floor_decay_per_s)
    # the slowest source of each band (its bands' sources: a band, or the finite slab's modes)
    heard = (np.asarray(lv.membership) > 0.0) & (np.asarray(lv.injected_J) > 0.0)[None, :]
    band_t60 = np.max(np.where(heard, floor_t60[None, :], 0.0), axis=1)
    if not chain.floor_decay and floor is None and np.any(band_t60 > SHORT_DECAY_SHARE * t_band):
        slow = [lab for lab, tf, tr in zip(labels, band_t60, t_band) if tf > SHORT_DECAY_SHARE * tr]
        out.append(
            f"the floor's decay is not short against T in bands {', '.join(slow)} Hz: use "
            "Chain(floor_decay=True)"
        )
    if not chain.floor_decay and floor is not None:
        t_room = float(np.min(t_band))
        if np.any(floor_t60 > SHORT_DECAY_SHARE * t_room):
            out.append(
                "modes of the floor decay slower than 0.3 T: the diffuse-field step "
                "(floor_decay=False) is outside its validity"
            )
    if isinstance(floor, FloatingFloor) and chain.floating == "insertion":
        f0 = float(floor.layer_resonance_Hz)
        above = [lab for lab, lo in zip(labels, edges[0]) if lo > 2.0 * f0]
        if above:
            out.append(
                "the floating floor passes T = 1/(1 − (f/f0)²/(1 + jη)) to the slab "
                f"(f0 = {f0:.1f} Hz; a locally reacting screed, 40 lg(f/f0)): a wet screed gains "
                f"≈ 30 lg(f/f0) (EN 12354-2 Annex C), so bands {', '.join(above)} Hz may be "
                "optimistic by up to 10 lg(f/f0) dB"
            )
    if isinstance(floor, FloatingFloor) and chain.floating == "modes":
        out.append(
            "floating='modes': the screed's modes radiate with the slab's η_rad, each in its own "
            "band only; a rough check, not a prediction (use floating='insertion')"
        )
    if np.any(np.asarray(lv.radiated_fraction) > 1.0):
        out.append(
            "a mode radiates more than its loss factor allows (η_rad > η_k): give the modes "
            "their radiation loss"
        )
    return out

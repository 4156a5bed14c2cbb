"""What a heavy-impact scene holds beyond the ball and the floor under it: the radiating slab
seen from the room below (``Slab``), the receiving room (``ReceivingRoom``) and which steps of
the chain are taken (``Chain``: each one a term the scene can leave out).

The named error ``RoomChainError`` (a ``ValueError``) is raised for a floor the chain cannot
follow (a rigid floor or a dashpot: no structure that radiates) and for a reverberation time
per band that does not match the bands.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import ArrayLike

from .._validate import as_float, check_choice, check_range, is_traced
from ..terms.floors.kinds import InfinitePlate
from ..terms.floors.materials import material
from .finite_slab import EDGE_CONDITIONS

#: A thin plate: each side at least this many thicknesses.
THIN_PLATE_RATIO = 10.0


class RoomChainError(ValueError):
    """A scene the room chain cannot follow (the message names the parameter and what is valid)."""


class Slab(eqx.Module):
    """The floor slab that radiates into the room below: a rectangular thin plate.

    Attributes:
        thickness_m, youngs_Pa, density_kg_per_m3, poisson: the plate (as ``InfinitePlate``).
        length_x_m, length_y_m: its sides (the radiating area S = l_x l_y and the radiation
            efficiency, ``rbjax.room.radiation``).
        loss_factor: the structural loss factor η_s of the slab in place (internal and edge
            losses; radiation is added by the chain). ``None`` (default): the empirical in-situ
            value of heavy (concrete, masonry) structures η_s = f^{-1/2} (f in Hz; Craik,
            *Sound Transmission through Buildings using SEA*, 1996, §4: 0.13 at 63 Hz, 0.045
            at 500 Hz).
        drive_x_m, drive_y_m: where the ball strikes, measured from a corner (``None``: the
            centre): the drive point of the finite slab's modes (``rbjax.room.finite_slab``);
            strictly inside the slab.
        edge: the edge condition of the finite slab's modes (``rbjax.room.finite_slab
            .EDGE_CONDITIONS``): ``"clamped"`` (default: a slab cast in place, continuous with
            the walls and the bays around it, restrains the rotation of its edges; Warburton's
            modes, ``rbjax.room.clamped_slab``) or ``"simply-supported"`` (edges free to
            rotate: the lower bound of its frequencies). Static.

    The slab must be thin: 0 < thickness ≤ min(l_x, l_y)/10 (Kirchhoff plate theory; a thicker
    one is outside every model here). The other fields are JAX leaves: the levels are
    differentiable in each of them.

    Raises:
        ValueError: a thickness, Young's modulus, density, side or loss factor not finite and
            > 0; a Poisson ratio outside (−1, 0.5]; an ``edge`` not offered; a slab thicker
            than a tenth of its shorter side; a drive point not strictly inside the slab
            (values checked where they are concrete, not under tracing).
    """

    thickness_m: ArrayLike
    youngs_Pa: ArrayLike
    density_kg_per_m3: ArrayLike
    poisson: ArrayLike
    length_x_m: ArrayLike = 4.0
    length_y_m: ArrayLike = 5.0
    loss_factor: ArrayLike | None = None
    drive_x_m: ArrayLike | None = None
    drive_y_m: ArrayLike | None = None
    edge: str = eqx.field(static=True, default="clamped")

    def __check_init__(self):
        for name in ("thickness_m", "youngs_Pa", "density_kg_per_m3", "length_x_m", "length_y_m"):
            check_range(name, getattr(self, name), lower=0.0)
        check_range("poisson", self.poisson, lower=-1.0, upper=0.5, upper_open=False)
        if self.loss_factor is not None:
            check_range("loss_factor", self.loss_factor, lower=0.0)
        check_choice("edge", self.edge, EDGE_CONDITIONS)
        sides = (self.length_x_m, self.length_y_m)
        if not is_traced((self.thickness_m, sides)):
            thinnest = min(as_float(x) for x in sides) / THIN_PLATE_RATIO
            check_range(
                "thickness_m", self.thickness_m, lower=0.0, upper=thinnest, upper_open=False
            )
        for name, side in (("drive_x_m", self.length_x_m), ("drive_y_m", self.length_y_m)):
            value = getattr(self, name)
            if value is not None and not is_traced((value, side)):
                check_range(name, value, lower=0.0, upper=as_float(side))

    @property
    def drive_point_m(self):
        """(x₀, y₀): the drive point (the centre where not given)."""
        return (
            0.5 * jnp.asarray(self.length_x_m) if self.drive_x_m is None else self.drive_x_m,
            0.5 * jnp.asarray(self.length_y_m) if self.drive_y_m is None else self.drive_y_m,
        )

    @classmethod
    def of_material(cls, name: str, thickness_m, **sides) -> Slab:
        """The slab of a material of ``rbjax.terms.floors.materials`` (``sides``: the other
        fields); a concrete thickness outside the material's plausible range is refused
        (``Material.check_thickness``)."""
        m = material(name)
        if not is_traced(thickness_m):
            m.check_thickness(thickness_m)
        return cls(thickness_m, m.youngs_Pa, m.density_kg_per_m3, m.poisson, **sides)

    @classmethod
    def of_plate(cls, plate: InfinitePlate, **sides) -> Slab:
        """The slab of an ``InfinitePlate`` floor (``sides``: the other fields)."""
        return cls(
            plate.plate_thickness_m,
            plate.plate_youngs_Pa,
            plate.plate_density_kg_per_m3,
            plate.plate_poisson,
            **sides,
        )

    @property
    def mass_per_area_kg_per_m2(self):
        return self.density_kg_per_m3 * self.thickness_m

    @property
    def plate(self) -> InfinitePlate:
        """The infinite plate of the slab's section (its drive-point impedance Z = 8√(B′m″))."""
        return InfinitePlate(self.thickness_m, self.youngs_Pa, self.density_kg_per_m3, self.poisson)

    def structural_loss(self, freq_Hz):
        """η_s at ``freq_Hz`` (the given value, or f^{-1/2})."""
        if self.loss_factor is None:
            return 1.0 / jnp.sqrt(jnp.asarray(freq_Hz))
        return jnp.asarray(self.loss_factor) * jnp.ones_like(jnp.asarray(freq_Hz))


class ReceivingRoom(eqx.Module):
    """The room below: volume V (m³) and reverberation time T (s), one value or one per band.

    Attributes:
        volume_m3: the volume V, m³ (> 0): one value.
        reverberation_s: the reverberation time T, s (> 0): one value, or one per band of the
            chain (a 1-D array; its length is checked against the bands where they are used).

    Raises:
        ValueError: a volume or reverberation time not finite and > 0 (not checked under
            tracing).
        RoomChainError: a volume that is not one value, or a reverberation time with more than
            one axis.
    """

    volume_m3: ArrayLike
    reverberation_s: ArrayLike

    def __check_init__(self):
        check_range("volume_m3", self.volume_m3, lower=0.0)
        check_range("reverberation_s", self.reverberation_s, lower=0.0)
        if np.ndim(self.volume_m3) != 0:
            raise RoomChainError(
                f"volume_m3 has shape {np.shape(self.volume_m3)}; valid: one value"
            )
        if np.ndim(self.reverberation_s) > 1:
            raise RoomChainError(
                f"reverberation_s has shape {np.shape(self.reverberation_s)}; valid: one value or "
                "one per band"
            )

    def reverberation_per_band(self, labels) -> jnp.ndarray:
        """T per band of ``labels`` (a scalar T broadcast); ``RoomChainError`` on a mismatch."""
        t = jnp.asarray(self.reverberation_s, dtype=jnp.float64)
        if t.ndim == 1 and t.shape[0] != len(labels):
            raise RoomChainError(
                f"reverberation_s has {t.shape[0]} values; valid: one value or one per band, "
                f"{len(labels)} for the bands {', '.join(labels)} Hz"
            )
        return jnp.broadcast_to(t, (len(labels),))

    def schroeder_frequency_Hz(self) -> np.ndarray | None:
        """f_S = 2000 √(T/V) (Schroeder 1962; T, V in s, m³): below it the room is modal and the
        diffuse-field level is a room average only; ``None`` under tracing."""
        if is_traced((self.volume_m3, self.reverberation_s)):
            return None
        return 2000.0 * np.sqrt(np.asarray(self.reverberation_s, float) / as_float(self.volume_m3))


@dataclasses.dataclass(frozen=True)
class Chain:
    """Which steps of the room chain are taken (each can be left out).

    Attributes:
        radiation: ``"iso12354"`` (σ of ``rbjax.room.radiation``) or ``"unity"`` (σ = 1).
        floor_decay: True: the floor's energy decays with its loss factor while it radiates
            (transient SEA of floor and room); False: the radiated energy enters the room at
            once (the diffuse field built up at t = 0 and decaying), valid where the floor's
            decay is short against T (the result says where it is not).
        detector: ``"fast"`` (τ = 0.125 s) or ``None`` (the peak of p² itself).
        floating: how a ``FloatingFloor`` over the slab is followed: ``"insertion"`` (default:
            the slab's resonant field driven by the force the layer passes,
            ``rbjax.room.injection.floating_band_energies_J``) or ``"modes"`` (its two
            drive-point modes radiate as the slab would, each in its own band only: a rough
            check, not a prediction; the result warns).
        slab: how the bare slab under the ball is followed in the bands of nominal frequency
            ≤ 100 Hz (the 31.5 and 63 Hz octaves, the thirds 25–100 Hz), where a slab of
            ordinary size has few modes: ``"modal"`` (default: the modes of the finite slab,
            ``rbjax.room.finite_slab``, each radiating with its own σ) or ``"infinite"`` (the
            infinite plate's band energy and ISO 12354-1's σ, as in the bands above). A
            floating floor's insertion always drives the slab's infinite-plate field.

    Raises:
        ValueError: a field outside its choices (the message names it and the valid ones).
    """

    radiation: str = "iso12354"
    floor_decay: bool = True
    detector: str | None = "fast"
    floating: str = "insertion"
    slab: str = "modal"

    def __post_init__(self):
        check_choice("radiation", self.radiation, ("iso12354", "unity"))
        check_choice("floor_decay", self.floor_decay, (True, False))
        check_choice("detector", self.detector, ("fast", None))
        check_choice("floating", self.floating, ("insertion", "modes"))
        check_choice("slab", self.slab, ("modal", "infinite"))

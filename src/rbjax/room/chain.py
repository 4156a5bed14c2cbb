"""From the ball to the room below: the maximum Fast-weighted band level L_i,Fmax, its
normalisation and the rating L_iA,Fmax, differentiable end to end.

The chain, per band (octaves 31.5 Hz–1 kHz or one-third octaves 25 Hz–1.25 kHz), each step a
term of ``Chain`` that can be left out:

1. **force** (``rbjax.solve``): the ball dropped from ``height_m`` on the floor; its force
   history at ``rate_Hz`` over the contact.
2. **floor** (``rbjax.room.injection``): the energy it injects, W, and how the floor holds it:
   a resonant slab (``floor=None``: the ball on the bare ``Slab``, point impedance
   Z = 8√(B′m″); SEA) holds the band energy W_b = E_F,b/Z, decaying at
   a_b = ω_b(η_s + 2η_rad); in the bands of nominal frequency ≤ 100 Hz (``Chain(slab="modal")``,
   the default) the finite slab's modes instead (``rbjax.room.finite_slab``: the edge condition
   and the drive point of the ``Slab``), one source per mode and band holding W_kb, decaying
   at ω_kη_k and radiating with the mode's own σ_k; a floating floor over the slab
   (``FloatingFloor``, ``Chain(floating="insertion")``, the default) is an insertion: the ball
   strikes the screed (its force from the two-mode floor), the layer passes F_slab = T F to the
   slab (its infinite-plate field in every band),
   T = 1/(1 − (f/f₀)²/(1 + jη)) (a locally reacting screed: EN 12354-2 Annex C's
   ΔL = 40 lg(f/f₀) above f₀, amplification (1 + η²)/η² at f₀), and the slab holds
   W_b = Σ_b E_F|T|²Δf/Z, decaying and radiating as the bare slab's field; a modal floor
   (``ModalFloor``; a ``FloatingFloor`` with ``floating="modes"``) holds W_k in each mode k,
   decaying at a_k = ω_kη_k (its own loss factor, radiation included), the mode counted in the
   band of its frequency only (right for the modes of the radiating slab itself; for a
   floating floor it is a rough check: the screed's mode would radiate with the slab's η_rad
   and the other bands stay silent, so the result warns).
3. **radiation** (``rbjax.room.radiation``): the floor radiates into the room below the power
   P = ω η_rad E (η_rad = ρ₀c₀σ/(ωm″), σ by ISO 12354-1 Annex B or 1).
4. **room**: a diffuse field of energy E_r, V dE_r/dt… in energy: dE_r/dt = P − bE_r with
   b = 6 ln 10/T (Sabine decay, T per band), p² = ρ₀c₀²E_r/V (spatial average).
5. **detector** (``rbjax.room.detector``): y = Fast-weighted p², τ = 0.125 s; L_i,Fmax =
   10 lg(max_t y/p₀²), p₀ = 20 µPa.

Steps 2–5 are a cascade of first-order stages driven by the injected energy at t = 0 (the
contact, ~20 ms, is short against τ and T: an impulse), so y(t) is a sum of closed forms
(``detector.cascade``): ρ₀c₀²/(Vτ) Σ_k ω_kη_rad,k W_k · conv(e^{−a_k t}, e^{−bt}, e^{−t/τ}).
With ``floor_decay=False`` the floor stage is left out: the radiated share W η_rad/η_floor
enters the room at t = 0 (valid where the floor's decay is short against T). Then
L_n = L + 10 lg(V/V0) − Fast correction (``rbjax.room.standards``) and L_iA,Fmax by
ISO 717-2 Annex D.

Validity (stated in ``ImpactSound.warnings``): bands below the room's Schroeder frequency
(modal room: the diffuse level is a room average), a floor decay not short against T where it
is left out, a mode whose radiation loss exceeds its loss factor; for a floating floor, the
locally reacting T (a wet screed that bends gains ≈ 30 lg(f/f₀) rather than 40 lg(f/f₀) in
EN 12354-2 Annex C: the bands above f₀ optimistic by up to 10 lg(f/f₀) dB), the screed's own
radiation and the layer's coupling through the air in it left out. Not modelled: the forced
(non-resonant) radiation near the drive point, flanking transmission, the band filters' own
response time (≈1/B ≤ 23 ms ≪ τ for the 63 Hz octave and above).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..solve.inputs import as_arrays
from ..solve.simulate import simulate, trajectory
from ..solve.solver import Solver
from ..spectrum.bands import band_centres_Hz, band_edges_Hz, nominal_centres_Hz
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.floors.floating import FloatingFloor
from ..terms.floors.kinds import AbstractFloor, AbstractModalFloor
from ..terms.model import Model
from .detector import cascade, maximum_over_time
from .finite_slab import modal_band_energies_J, mode_orders, slab_modes
from .injection import (
    floating_band_energies_J,
    modal_energies_J,
    modal_grid_size,
    plate_band_energies_J,
)
from .radiation import (
    AIR_DENSITY_kg_per_m3,
    SPEED_OF_SOUND_m_per_s,
    critical_frequency_Hz,
    radiation_efficiency,
    radiation_loss_factor,
)
from .scene import Chain, ReceivingRoom, RoomChainError, Slab
from .standards import (
    RATING_BANDS,
    FAST_TIME_CONSTANT_s,
    a_weighted_sum_dB,
    decay_rate_per_s,
    normalised_level_dB,
)

#: Reference sound pressure, Pa.
REFERENCE_PRESSURE_Pa = 20e-6
#: The band range of each fraction (nominal mid-band frequencies, Hz).
BAND_RANGES_Hz = {1: (31.5, 1000.0), 3: (25.0, 1250.0)}
#: The bands of nominal frequency up to this follow the finite slab's modes (``Chain.slab``).
MODAL_BANDS_UP_TO_Hz = 100.0


class RoomLevels(eqx.Module):
    """The arrays of the chain (differentiable): per band the maximum Fast level, its time and
    the normalised level; per source (band or mode) the injected energy and its radiated share.

    Attributes:
        level_dB: L_i,Fmax per band, dB re (20 µPa)² (−inf in a band without a source).
        peak_time_s: the time of each band's maximum after the impact, s.
        normalised_dB: the normalised level per band, dB (``normalised_level_dB``).
        injected_J: the energy W injected into each source (band or mode), J.
        radiated_fraction: the share of each source's energy that it radiates into the room,
            ω η_rad / a.
        floor_decay_per_s: the decay rate a of each source, 1/s.
        room_decay_per_s: the room's decay rate b = 6 ln 10/T per band, 1/s.
        radiation_per_s: the radiation rate ω η_rad of each source, 1/s.
        membership: (bands × sources), 1 where a source is heard in a band, else 0.
        pressure_scale: ρ₀c₀²/V, Pa²/J (p² = ρ₀c₀²E_r/V).
    """

    level_dB: jax.Array
    peak_time_s: jax.Array
    normalised_dB: jax.Array
    injected_J: jax.Array
    radiated_fraction: jax.Array
    floor_decay_per_s: jax.Array
    room_decay_per_s: jax.Array
    radiation_per_s: jax.Array
    membership: jax.Array
    pressure_scale: jax.Array


def bands(fraction: int) -> tuple[list[str], np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """(labels, exact centres, (lower, upper) edges) of the chain's bands for ``fraction``."""
    if fraction not in BAND_RANGES_Hz:
        raise RoomChainError(
            f"fraction={fraction!r} is not a band fraction; valid: 1 (octave), 3 (one-third octave)"
        )
    lo, hi = BAND_RANGES_Hz[fraction]
    return (
        nominal_centres_Hz(fraction, lo, hi),
        band_centres_Hz(fraction, lo, hi),
        band_edges_Hz(fraction, lo, hi),
    )


def modal_bands(fraction: int) -> np.ndarray:
    """Which of the chain's bands follow the finite slab's modes (``Chain(slab="modal")``):
    those of nominal frequency ≤ ``MODAL_BANDS_UP_TO_Hz``."""
    labels, _, _ = bands(fraction)
    return np.array([float(x) <= MODAL_BANDS_UP_TO_Hz for x in labels])


def slab_mode_orders(slab: Slab, fraction: int) -> tuple[int, int]:
    """The mode set of the finite slab in the modal bands of ``fraction``
    (``rbjax.room.finite_slab.mode_orders`` at their highest edge): give it as ``orders=`` to
    ``room_levels`` where the slab's values are traced.

    Args:
        slab: the :class:`Slab`, with concrete values.
        fraction: 1 (octave bands) or 3 (one-third-octave bands).

    Returns:
        (M, N): the highest mode orders along x and y, ints ≥ 1.

    Raises:
        RoomChainError: ``fraction`` not 1 or 3.
        ValueError: the slab's values are traced.
    """
    _, _, edges = bands(fraction)
    return mode_orders(slab, float(np.max(edges[1][modal_bands(fraction)])))


def _check_floor(floor: AbstractFloor | None, slab: Slab | None) -> None:
    if floor is None:
        if slab is None:
            raise RoomChainError(
                "give slab= (the radiating slab; the ball then strikes it) or a modal floor with "
                "slab="
            )
        return
    if isinstance(floor, AbstractModalFloor):
        if slab is None:
            raise RoomChainError(
                "floor=modal needs slab= (the plate that radiates: its mass per area and "
                "critical frequency)"
            )
        return
    kind = getattr(floor, "name", type(floor).__name__)
    raise RoomChainError(
        f"floor={kind!r} has no structure that radiates into a room below; valid: floor=None (the "
        "ball on the bare slab=), a modal floor (ModalFloor, FloatingFloor) with slab=, or an "
        "infinite-plate floor turned into a slab with Slab.of_plate"
    )


def contact_samples(height_m, ball, model: Model, rate_Hz: float, solver: Solver) -> int:
    """How many force samples cover the contact (a concrete pre-solve).

    Args:
        height_m: the drop height, m (or several: the longest contact counts).
        ball: the :class:`~rbjax.terms.ball.Ball`.
        model: the impact :class:`~rbjax.terms.model.Model` (its floor is the one struck).
        rate_Hz: the sampling rate of the force, Hz.
        solver: the :class:`~rbjax.solve.solver.Solver` of the pre-solve.

    Returns:
        ⌈t_c · rate_Hz⌉ + 2 samples (t_c: the contact time), an ``int``: the ``n_samples`` of
        :func:`room_levels`.

    Raises:
        RuntimeError: the pre-solve failed (``ImpactResult.raise_for_status``).
    """
    res = simulate(height_m, ball, model, solver=solver).raise_for_status()
    return int(math.ceil(float(np.max(np.asarray(res.contact_time_s))) * rate_Hz)) + 2


def _modal_slab_sources(slab: Slab, force, rate_Hz, edges, chain: Chain, orders, modal):
    """The finite slab's sources in the modal bands: one per (mode, band) pair, mode-major; the
    energy W_kb, the mode's decay ω_k η_k and radiation rate ω_k η_rad,k, and the membership."""
    index = np.flatnonzero(modal)
    fk, inverse_mass, _, eta, eta_rad = slab_modes(slab, orders)
    if chain.radiation == "unity":
        eta_rad = radiation_loss_factor(fk, 1.0, slab.mass_per_area_kg_per_m2)
        eta = slab.structural_loss(fk) + 2.0 * eta_rad
    energy = modal_band_energies_J(
        force, rate_Hz, fk, eta, inverse_mass, edges[0][index], edges[1][index]
    )
    omega = 2.0 * jnp.pi * fk
    member = np.zeros((len(modal), energy.size))
    for j, b in enumerate(index):
        member[b, j :: len(index)] = 1.0
    return (
        energy.reshape(-1),
        jnp.repeat(omega * eta, len(index)),
        jnp.repeat(omega * eta_rad, len(index)),
        jnp.asarray(member),
    )


def _sources(floor, slab: Slab, force, rate_Hz, fraction, chain: Chain, n_fft, orders):
    """Per source (band or mode): injected energy W, floor decay a, radiation rate ω η_rad and
    the (bands × sources) membership. The bare slab with ``orders``: the finite slab's modes in
    the modal bands (``modal_bands``), the infinite plate in the others."""
    _, centres, edges = bands(fraction)
    fc = critical_frequency_Hz(
        slab.thickness_m, slab.youngs_Pa, slab.density_kg_per_m3, slab.poisson
    )
    mass = slab.mass_per_area_kg_per_m2

    def rad_rate(f):
        sigma = (
            radiation_efficiency(f, fc, slab.length_x_m, slab.length_y_m)
            if chain.radiation == "iso12354"
            else jnp.ones_like(f)
        )
        return 2.0 * jnp.pi * f * radiation_loss_factor(f, sigma, mass)

    if isinstance(floor, AbstractModalFloor) and not (
        isinstance(floor, FloatingFloor) and chain.floating == "insertion"
    ):
        _, omega, eta = floor.modes()
        fk = omega / (2.0 * jnp.pi)
        energy = modal_energies_J(force, rate_Hz, floor, n_fft)
        f_safe = jnp.where(fk > 0.0, fk, 1.0)
        decay = 2.0 * jnp.pi * f_safe * eta
        radiate = jnp.where(fk > 0.0, rad_rate(f_safe), 0.0)
        member = (fk[None, :] >= edges[0][:, None]) & (fk[None, :] < edges[1][:, None])
        return energy, decay, radiate, member.astype(jnp.float64)
    impedance = slab.plate.impedance_Ns_per_m
    if isinstance(floor, FloatingFloor):
        energy = floating_band_energies_J(
            force, rate_Hz, edges[0], edges[1], floor, impedance, n_fft
        )
    else:
        energy = plate_band_energies_J(
            force,
            rate_Hz,
            edges[0],
            edges[1],
            impedance,
            n_record=max(force.shape[-1], int(rate_Hz)),
        )
    f = jnp.asarray(centres)
    radiate = rad_rate(f)
    decay = 2.0 * jnp.pi * f * slab.structural_loss(f) + 2.0 * radiate
    if floor is not None or orders is None:
        return energy, decay, radiate, jnp.eye(len(centres))
    modal = modal_bands(fraction)
    parts = _modal_slab_sources(slab, force, rate_Hz, edges, chain, orders, modal)
    plate = (jnp.where(jnp.asarray(modal), 0.0, energy), decay, radiate, jnp.eye(len(centres)))
    return tuple(jnp.concatenate([p, q], axis=-1) for p, q in zip(parts, plate))


def room_levels(
    slab: Slab,
    room: ReceivingRoom,
    *,
    floor: AbstractModalFloor | None = None,
    height_m=1.0,
    ball=JIS_RUBBER_BALL,
    model: Model | None = None,
    chain: Chain = Chain(),
    fraction: int = 1,
    rate_Hz: float = 44100.0,
    n_samples: int,
    solver: Solver = Solver(),
    n_fft: int | None = None,
    orders: tuple[int, int] | None = None,
) -> RoomLevels:
    """The chain's arrays for the ball on ``floor`` (``None``: on the bare ``slab``) over
    ``n_samples`` force samples (``contact_samples``); pure JAX, differentiable in the slab,
    room, ball, height and the parameters of a ``FloatingFloor`` (``jax.jvp``/``jax.jacfwd``
    with ``Solver(adjoint="forward")``).

    Args:
        slab: the :class:`Slab` that radiates into the room (struck itself where ``floor`` is
            ``None``).
        room: the :class:`ReceivingRoom`.
        floor: a modal floor over the slab that the ball strikes (``ModalFloor``,
            ``FloatingFloor``); ``None``: the bare slab.
        height_m: the drop height, m.
        ball: the ball (default: ``JIS_RUBBER_BALL``).
        model: the impact model; its floor is replaced by the one struck (default:
            ``Model(floor=...)`` of that floor).
        chain: the steps of the chain taken (:class:`Chain`).
        fraction: 1 (octaves 31.5 Hz–1 kHz) or 3 (one-third octaves 25 Hz–1.25 kHz).
        rate_Hz: the sampling rate of the force, Hz.
        n_samples: the force samples over the contact (:func:`contact_samples`).
        solver: the :class:`~rbjax.solve.solver.Solver` of the force history.
        n_fft: the frequency grid of a modal floor's energies
            (``rbjax.room.injection.modal_grid_size``, the default where the floor's values
            are concrete; give it where they are traced).
        orders: the finite slab's mode set for the ball on the bare slab with
            ``Chain(slab="modal")`` (``slab_mode_orders``, the default where the slab's values
            are concrete; give it where they are traced).

    Returns:
        The :class:`RoomLevels` of the chain.

    Raises:
        RoomChainError: a floor the chain cannot follow (not ``None`` nor a modal floor), no
            ``slab``, ``fraction`` not 1 or 3, or a reverberation time per band whose length
            is not the bands'.
        ValueError: ``orders`` or ``n_fft`` not given where the values they are computed from
            are traced.
    """
    _check_floor(floor, slab)
    if floor is None and chain.slab == "modal" and orders is None:
        orders = slab_mode_orders(slab, fraction)
    if floor is not None or chain.slab != "modal":
        orders = None
    labels, centres, edges = bands(fraction)
    t_band = room.reverberation_per_band(labels)
    impact_floor = slab.plate if floor is None else floor
    model = (
        Model(floor=impact_floor)
        if model is None
        else eqx.tree_at(lambda m: m.floor, model, impact_floor)
    )
    times = jnp.arange(n_samples) / rate_Hz
    force = trajectory(height_m, times, ball, model, solver).force_N
    if isinstance(floor, AbstractModalFloor) and n_fft is None:
        n_fft = modal_grid_size(floor, rate_Hz, n_samples)
    force, slab, volume, t_band, floor = as_arrays((force, slab, room.volume_m3, t_band, floor))
    return _levels_of_force(
        force, slab, volume, t_band, floor, chain, fraction, float(rate_Hz), n_fft, orders
    )


@eqx.filter_jit
def _levels_of_force(
    force,
    slab: Slab,
    volume_m3,
    t_band,
    floor,
    chain: Chain,
    fraction: int,
    rate_Hz: float,
    n_fft: int | None,
    orders: tuple[int, int] | None,
) -> RoomLevels:
    """Steps 2–5 of the chain on the force samples: one compiled program per floor kind,
    chain, fraction, force length and grid (the values are traced)."""
    energy, decay, radiate, member = _sources(
        floor, slab, force, rate_Hz, fraction, chain, n_fft, orders
    )
    b = decay_rate_per_s(t_band)
    kappa = AIR_DENSITY_kg_per_m3 * SPEED_OF_SOUND_m_per_s**2 / volume_m3
    parts = dict(
        injected_J=energy,
        radiated_fraction=radiate / decay,
        floor_decay_per_s=decay,
        room_decay_per_s=b,
        radiation_per_s=radiate,
        membership=member,
        pressure_scale=kappa,
    )

    def band(bi, row):
        return maximum_over_time(
            lambda t: _band_response(parts, chain, bi, row, t), 1e-4, 20.0 / bi
        )

    peak, t_star = jax.vmap(band)(b, member)
    # a band without a source (a modal floor without a mode in it) is silent: −inf dB, and a
    # zero gradient rather than 0/0
    heard = peak > 0.0
    level = jnp.where(
        heard, 10.0 * jnp.log10(jnp.where(heard, peak, 1.0) / REFERENCE_PRESSURE_Pa**2), -jnp.inf
    )
    return RoomLevels(
        level_dB=level,
        peak_time_s=t_star,
        normalised_dB=normalised_level_dB(level, volume_m3, t_band),
        **parts,
    )


def _band_response(parts, chain: Chain, room_rate, row, t):
    """y(t) of one band (p² in Pa² without the detector): the sum over the band's sources of
    the cascade floor → room → detector (module docstring)."""
    g = 1.0 / FAST_TIME_CONSTANT_s
    decay = parts["floor_decay_per_s"]
    if chain.floor_decay:
        rates, amp = [decay, room_rate], parts["radiation_per_s"] * parts["injected_J"]
    else:
        rates, amp = [room_rate], parts["radiated_fraction"] * parts["injected_J"]
    if chain.detector:
        rates = rates + [g]
    scale = parts["pressure_scale"] * (g if chain.detector else 1.0)
    return scale * jnp.sum(
        row * amp * cascade([jnp.broadcast_to(r, decay.shape) for r in rates], t)
    )


@eqx.filter_jit
def fast_levels_dB(levels: RoomLevels, chain: Chain, times_s):
    """The Fast-weighted level (or, without the detector, the level of p²) of each band at
    ``times_s``: shape (bands, times); the same closed form whose maximum is ``level_dB``.

    Args:
        levels: the :class:`RoomLevels` of :func:`room_levels`.
        chain: the :class:`Chain` they were computed with.
        times_s: the times after the impact, s (1-D).

    Returns:
        The levels, dB re (20 µPa)², shape (bands, times).
    """
    parts = {
        k: getattr(levels, k)
        for k in (
            "injected_J",
            "radiated_fraction",
            "floor_decay_per_s",
            "room_decay_per_s",
            "radiation_per_s",
            "membership",
            "pressure_scale",
        )
    }
    at = jax.vmap(
        jax.vmap(
            lambda bi, row, t: _band_response(parts, chain, bi, row, t), in_axes=(None, None, 0)
        ),
        in_axes=(0, 0, None),
    )
    y = at(levels.room_decay_per_s, levels.membership, jnp.asarray(times_s, dtype=jnp.float64))
    return 10.0 * jnp.log10(jnp.maximum(y, 1e-300) / REFERENCE_PRESSURE_Pa**2)


def rating_levels(levels_dB, fraction: int):
    """The levels of the rating bands (ISO 717-2 Annex D) out of the chain's bands."""
    labels, _, _ = bands(fraction)
    index = [labels.index(x) for x in RATING_BANDS[fraction]]
    return jnp.asarray(levels_dB)[..., jnp.asarray(index)]


def rating_unrounded_dB(levels: RoomLevels, fraction: int, *, normalised: bool = False):
    """10 lg Σ 10^{(L + A)/10} over the rating bands, unrounded (the differentiable rating).

    Args:
        levels: the :class:`RoomLevels` of :func:`room_levels`.
        fraction: their band fraction, 1 (octaves) or 3 (one-third octaves).
        normalised: rate the normalised levels (``normalised_dB``) rather than the levels in
            the room (``level_dB``).

    Returns:
        L_iA,Fmax (ISO 717-2:2020 Annex D), dB, unrounded: a JAX scalar.

    Raises:
        RoomChainError: ``fraction`` not 1 or 3.
        ValueError: a non-finite level in a rating band (concrete levels only; e.g. a band
            without a source).
    """
    return a_weighted_sum_dB(
        rating_levels(levels.normalised_dB if normalised else levels.level_dB, fraction), fraction
    )

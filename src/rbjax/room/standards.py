"""The standards' arithmetic of heavy-impact sound: the Fast-detector maximum of an
exponential decay, the normalisation of ISO 16283-2 to a reference room, and the single-number
rating L_iA,Fmax of ISO 717-2:2020 Annex D.

**Fast maximum of an exponential decay.** A diffuse field that decays from p²(0) = A with the
rate b = 6 ln 10 / T (60 dB in the reverberation time T; Sabine) drives the exponential
time weighting of a sound level meter (IEC 61672-1:2013, 3.7 and 5.8: τ = 0.125 s for F):
y(t) = (1/τ)∫₀ᵗ p²(s) e^{-(t−s)/τ} ds = A (e^{-bt} − e^{-t/τ})/(1 − bτ). It is largest where
b e^{-bt} = e^{-t/τ}/τ, and there (with C = bτ)

    y_max / A = g(C) = C^{C/(1 − C)}   (C ≠ 1;  g(1) = e^{-1}).

For T0 = 0.5 s, C0 = 6 ln 10 · 0.125/0.5 = 3.454 and g(C0) = 0.175: the Fast detector reads
7.6 dB below the initial level of a 0.5 s decay, 5.6 dB below at T = 1 s, 4.0 dB at 2 s.

**Normalisation (ISO 16283-2).** The energy an impact puts into a room, W, gives an initial
energy density W/V and p²(0) = ρ₀c₀²W/V: at equal W, the Fast maximum goes as g(C(T))/V.
Normalising the level measured in a room of volume V and reverberation time T to the
reference room V0 = 50 m³, T0 = 0.5 s of the heavy-impact measurements is therefore

    L_n = L + 10 lg(V/V0) − 10 lg(g(C(T))/g(C(T0))),

the closed-form Fast correction for an exponential decay (+1.94 dB at T = 1 s and +3.55 dB
at 2 s relative to 0.5 s are subtracted). It assumes that the floor's own decay is short
against T (the room decay sets the Fast maximum); ``rbjax.room.chain`` reports where it is not.

**Rating (ISO 717-2:2020, Annex D).** The A-weighted maximum impact sound pressure level is
the energetic sum of the band levels plus the A-weighted reference values A_k of ISO 717-2:2020
Table D.3 (printed p. 21), octaves 63–500 Hz or one-third octaves 50–630 Hz (Formula (D.1)),

    L_iA,Fmax = 10 lg Σ_k 10^{(L_i,Fmax,k + A_k)/10},

stated as an integer. Table D.3 is not the A-weighting of IEC 61672-1:2013 Table 3 at the
nominal frequencies: six of its twelve one-third-octave values differ by 0.1–0.2 dB (50 Hz
−30.3 against −30.2, 80 Hz −22.4/−22.5, 125 Hz −16.2/−16.1, 160 Hz −13.2/−13.4, 200 Hz
−10.8/−10.9, 250 Hz −8.7/−8.6), and so do the octaves 125 and 250 Hz (−16.2, −8.7). The
standard's text could not be read here: the values are those transcribed from Table D.3 in the
tests of the phonometry project (J. M. Requena Plens, ``tests/building/measurement/
test_heavy_impact.py``, "ISO 717-2:2020 Table D.3 (printed p. 21)"), checked against the
standard's worked example, Table D.4: the octave levels 65.3, 64.5, 58.0, 55.8 dB, corrected to
39.1, 48.3, 49.3, 52.6 dB, rate 55.350 66… → 55 dB (the IEC weights give 55.3955).
``IEC_61672_A_WEIGHTS_*`` keeps the IEC values for what really means A-weighting (a check of the
IEC formula; no rating uses them). The rounding is the ordinary one, half away from zero
(ISO 80000-1 Annex B, rule B): x.5 goes up; the sum is first rounded to 1e-9 dB so that a level
printed to 0.1 dB that sums to exactly x.5 is not flipped by floating point.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from .._validate import check_range, is_traced

#: Fast time constant τ_F, s (IEC 61672-1:2013, 3.7 and 5.8.1).
FAST_TIME_CONSTANT_s = 0.125
#: Reference volume and reverberation time of the heavy-impact normalisation (ISO 16283-2).
REFERENCE_VOLUME_m3 = 50.0
REFERENCE_REVERBERATION_s = 0.5
#: Decay rate of the energy, per s, per 1/T: 60 dB in T is e^{-6 ln 10}.
DECAY_PER_REVERBERATION = 6.0 * math.log(10.0)

#: The A-weighted reference values A_k, dB, of the rating (ISO 717-2:2020 Annex D, Table D.3):
#: octaves 63–500 Hz, one-third octaves 50–630 Hz.
ISO_717_2_TABLE_D3_OCTAVE_dB: dict[str, float] = {
    "63": -26.2, "125": -16.2, "250": -8.7, "500": -3.2,
}  # fmt: skip
ISO_717_2_TABLE_D3_THIRD_OCTAVE_dB: dict[str, float] = {
    "50": -30.3, "63": -26.2, "80": -22.4, "100": -19.1, "125": -16.2, "160": -13.2,
    "200": -10.8, "250": -8.7, "315": -6.6, "400": -4.8, "500": -3.2, "630": -1.9,
}  # fmt: skip
#: The A-weighting of IEC 61672-1:2013 Table 3 at the same nominal frequencies (what "A-weights"
#: means elsewhere; not the rating's values).
IEC_61672_A_WEIGHTS_OCTAVE_dB: dict[str, float] = {
    "63": -26.2, "125": -16.1, "250": -8.6, "500": -3.2,
}  # fmt: skip
IEC_61672_A_WEIGHTS_THIRD_OCTAVE_dB: dict[str, float] = {
    "50": -30.2, "63": -26.2, "80": -22.5, "100": -19.1, "125": -16.1, "160": -13.4,
    "200": -10.9, "250": -8.6, "315": -6.6, "400": -4.8, "500": -3.2, "630": -1.9,
}  # fmt: skip
RATING_BANDS = {
    1: tuple(ISO_717_2_TABLE_D3_OCTAVE_dB),
    3: tuple(ISO_717_2_TABLE_D3_THIRD_OCTAVE_dB),
}


def decay_rate_per_s(reverberation_s):
    """b = 6 ln 10 / T: the decay rate of a diffuse field's energy (60 dB in T)."""
    return DECAY_PER_REVERBERATION / jnp.asarray(reverberation_s, dtype=jnp.float64)


def fast_max_of_decay(reverberation_s, time_constant_s: float = FAST_TIME_CONSTANT_s):
    """g(C) = C^{C/(1−C)}, C = bτ: the Fast-detector maximum of an exponential decay of
    p²(0) = 1 (module docstring); differentiable, g(1) = 1/e taken by continuity.

    Args:
        reverberation_s: the reverberation time T, s (> 0): a scalar or an array (e.g. one
            per band).
        time_constant_s: the detector's time constant τ, s (default: τ_F = 0.125 s).

    Returns:
        g(C) = y_max/p²(0), dimensionless, between 0 and 1: a JAX array of the shape of
        ``reverberation_s``.

    Raises:
        ValueError: a reverberation time that is not finite and > 0 (not checked where it is
            traced).
    """
    check_range("reverberation_s", reverberation_s, lower=0.0)
    c = decay_rate_per_s(reverberation_s) * time_constant_s
    near = jnp.abs(c - 1.0) < 1e-6
    safe = jnp.where(near, 2.0, c)
    # ln g = C ln C/(1 − C) → −1 − (C − 1)/2 near C = 1 (Taylor)
    log_g = jnp.where(near, -1.0 - 0.5 * (c - 1.0), safe * jnp.log(safe) / (1.0 - safe))
    return jnp.exp(log_g)


def fast_correction_dB(reverberation_s, reference_s: float = REFERENCE_REVERBERATION_s):
    """10 lg(g(C(T))/g(C(T0))): how much higher the Fast maximum of a decay of reverberation
    time T reads than that of the same initial level decaying with T0 (module docstring).

    Args:
        reverberation_s: the reverberation time T, s (> 0): a scalar or an array.
        reference_s: the reference reverberation time T0, s (default: 0.5 s, ISO 16283-2).

    Returns:
        The correction, dB (positive for T > T0): a JAX array of the shape of
        ``reverberation_s``.

    Raises:
        ValueError: T or T0 not finite and > 0 (not checked where traced).
    """
    return 10.0 * jnp.log10(fast_max_of_decay(reverberation_s) / fast_max_of_decay(reference_s))


def normalised_level_dB(level_dB, volume_m3, reverberation_s):
    """L_n = L + 10 lg(V/V0) − 10 lg(g(C(T))/g(C(T0))) with V0 = 50 m³, T0 = 0.5 s
    (ISO 16283-2 heavy impact; module docstring).

    Args:
        level_dB: the band levels L measured in the room, dB, the bands on the last axis.
        volume_m3: the room's volume V, m³ (> 0).
        reverberation_s: the room's reverberation time T, s (> 0): one value, or one per band
            (it broadcasts against the last axis of ``level_dB``).

    Returns:
        L_n, dB: a JAX array of the broadcast shape of the arguments.

    Raises:
        ValueError: V or T not finite and > 0 (not checked where traced).
    """
    check_range("volume_m3", volume_m3, lower=0.0)
    check_range("reverberation_s", reverberation_s, lower=0.0)
    return (
        jnp.asarray(level_dB)
        + 10.0 * jnp.log10(jnp.asarray(volume_m3) / REFERENCE_VOLUME_m3)
        - fast_correction_dB(reverberation_s)
    )


def rating_reference_values_dB(fraction: int) -> np.ndarray:
    """The A-weighted reference values A_k of the rating bands of ``fraction`` (ISO 717-2:2020
    Table D.3; 1: octaves 63–500 Hz, 3: thirds 50–630 Hz)."""
    if fraction not in RATING_BANDS:
        raise ValueError(
            f"fraction={fraction!r} is outside the valid choices 1 (octave), 3 (one-third octave)"
        )
    table = ISO_717_2_TABLE_D3_OCTAVE_dB if fraction == 1 else ISO_717_2_TABLE_D3_THIRD_OCTAVE_dB
    return np.array(list(table.values()))


def a_weighted_sum_dB(levels_dB, fraction: int = 1):
    """10 lg Σ 10^{(L_k + A_k)/10} over the rating bands with A_k of ISO 717-2:2020 Table D.3
    (Formula (D.1); unrounded, differentiable).

    Args:
        levels_dB: L_i,Fmax,k, dB: the last axis holds one level per rating band (4 octaves
            63–500 Hz or 12 one-third octaves 50–630 Hz).
        fraction: 1 (octave bands) or 3 (one-third-octave bands).

    Returns:
        The unrounded L_iA,Fmax, dB: a JAX array of the shape of ``levels_dB`` less its last
        axis.

    Raises:
        ValueError: ``fraction`` not 1 or 3, a last axis of another length than the rating
            bands', a NaN or +inf level, or every band silent (checked on concrete levels
            only). A silent band (−inf dB: a modal floor without a mode in it) adds nothing.
    """
    weights = rating_reference_values_dB(fraction)
    levels = jnp.asarray(levels_dB, dtype=jnp.float64)
    if levels.shape[-1:] != weights.shape:
        raise ValueError(
            f"levels_dB has {levels.shape[-1:] or 'no'} bands on its last axis; valid: "
            f"{len(weights)} (the rating bands {', '.join(RATING_BANDS[fraction])} Hz)"
        )
    if not is_traced(levels):
        concrete = np.asarray(levels)
        if np.any(np.isnan(concrete) | np.isposinf(concrete)):
            raise ValueError(f"levels_dB={concrete.tolist()} has a NaN or +inf level")
        if np.any(np.all(np.isneginf(concrete), axis=-1)):
            raise ValueError(f"levels_dB={concrete.tolist()}: every rating band is silent")
    return 10.0 * jnp.log10(jnp.sum(10.0 ** ((levels + weights) / 10.0), axis=-1))


def round_rating(value_dB) -> int:
    """A rating stated as an integer, half away from zero (module docstring), after rounding to
    1e-9 dB.

    Args:
        value_dB: the unrounded rating, dB (a number or a one-element array).

    Returns:
        The rating in whole dB, an ``int``.
    """
    x = round(float(value_dB), 9)
    return int(math.copysign(math.floor(abs(x) + 0.5), x))


def rating_dB(levels_dB, fraction: int = 1) -> int:
    """L_iA,Fmax (ISO 717-2:2020 Annex D) of the band levels L_i,Fmax over the rating bands, an
    integer (``a_weighted_sum_dB`` rounded by ``round_rating``).

    Args:
        levels_dB: L_i,Fmax per rating band, dB, shape (4,) (octaves 63–500 Hz) or (12,)
            (one-third octaves 50–630 Hz).
        fraction: 1 (octave bands) or 3 (one-third-octave bands).

    Returns:
        L_iA,Fmax in whole dB, an ``int``.

    Raises:
        ValueError: as :func:`a_weighted_sum_dB` (``fraction``, band count, non-finite level).
    """
    return round_rating(a_weighted_sum_dB(levels_dB, fraction))

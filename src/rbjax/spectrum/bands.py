"""Octave and one-third-octave bands (IEC 61260-1 base-ten, G = 10^(3/10)): exact centres and
edges, and the nominal labels of the bands (31.5 Hz … 1 kHz for the rubber ball)."""

from __future__ import annotations

import functools
import math
from decimal import Decimal

import numpy as np

from .._validate import check_range

#: Octave frequency ratio of base-ten filters, G = 10^(3/10) (IEC 61260-1:2014, 5.2).
OCTAVE_RATIO_G = 10.0 ** (3.0 / 10.0)


#: Reference frequency f_r (IEC 61260-1:2014, 5.3).
REFERENCE_FREQUENCY_Hz = 1000.0


#: Octave bands of the rubber-ball L_FE spectrum, 31.5 Hz to 1 kHz (paper Fig. 8; the
#: standards tolerance 31.5-500 Hz, see ``rbjax.spectrum.standards``).
OCTAVE_BANDS = ("31.5", "63", "125", "250", "500", "1000")


#: One-third-octave bands 25 Hz to 1.25 kHz (the thirds inside OCTAVE_BANDS).
THIRD_OCTAVE_BANDS = (
    "25", "31.5", "40", "50", "63", "80", "100", "125", "160",
    "200", "250", "315", "400", "500", "630", "800", "1000", "1250",
)  # fmt: skip


def _check_fraction(fraction) -> int:
    if fraction not in (1, 3) or isinstance(fraction, bool):
        raise ValueError(f"fraction={fraction!r} must be 1 (octave) or 3 (one-third octave)")
    return int(fraction)


def _check_frequency_range(fmin_Hz, fmax_Hz) -> tuple[float, float]:
    check_range("fmin_Hz", fmin_Hz, lower=0.0)
    check_range("fmax_Hz", fmax_Hz, lower=0.0)
    fmin_Hz, fmax_Hz = float(fmin_Hz), float(fmax_Hz)
    if fmax_Hz < fmin_Hz:
        raise ValueError(f"fmax_Hz={fmax_Hz!r} must be >= fmin_Hz={fmin_Hz!r}")
    return fmin_Hz, fmax_Hz


def _nominal_label(third_index: int) -> str:
    """Nominal mid-band frequency (IEC 61260-1:2014 Annex E) of the base-ten third with
    band number ``third_index`` (0 at 1 kHz): the R10 preferred number of that decade."""
    decade, step = divmod(third_index, 10)
    value = Decimal(_R10[step]) * Decimal(10) ** (3 + decade)
    return format(value.normalize(), "f")


@functools.lru_cache(maxsize=64)
def _band_numbers(fraction: int, fmin_Hz: float, fmax_Hz: float) -> tuple[int, ...]:
    """Band numbers x (f_m = f_r G^(x/b)) whose nominal mid-band frequency is in [fmin, fmax]."""
    b = fraction
    log_G = math.log10(OCTAVE_RATIO_G)
    x_lo = math.floor(b * math.log10(fmin_Hz / REFERENCE_FREQUENCY_Hz) / log_G) - 2
    x_hi = math.ceil(b * math.log10(fmax_Hz / REFERENCE_FREQUENCY_Hz) / log_G) + 2
    third = 3 // b  # an octave's band number x is the third-octave band number 3x
    tol = 1e-12
    return tuple(
        x
        for x in range(x_lo, x_hi + 1)
        if fmin_Hz * (1 - tol) <= float(_nominal_label(third * x)) <= fmax_Hz * (1 + tol)
    )


def band_centres_Hz(fraction: int, fmin_Hz: float, fmax_Hz: float) -> np.ndarray:
    """Exact base-ten mid-band frequencies f_m = 1000 Hz · G^(x/b), G = 10^(3/10).

    IEC 61260-1:2014, Clause 5.2 (G, base ten), 5.3 (f_r = 1000 Hz) and 5.4 (exact mid-band
    frequencies, odd bandwidth designator b). Returns the bands whose *nominal* mid-band
    frequency (Annex E) lies in [fmin_Hz, fmax_Hz], e.g. octaves 31.5 Hz to 1 kHz give
    31.62, 63.10, 125.89, 251.19, 501.19, 1000 Hz.

    Args:
      fraction: bandwidth designator b: 1 (octave) or 3 (one-third octave).
      fmin_Hz, fmax_Hz: range of nominal mid-band frequencies, Hz (inclusive).
    """
    b = _check_fraction(fraction)
    fmin_Hz, fmax_Hz = _check_frequency_range(fmin_Hz, fmax_Hz)
    x = np.asarray(_band_numbers(b, fmin_Hz, fmax_Hz), dtype=float)
    return REFERENCE_FREQUENCY_Hz * OCTAVE_RATIO_G ** (x / b)


def band_edges_Hz(fraction: int, fmin_Hz: float, fmax_Hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper band-edge frequencies f_1,2 = f_m · G^(∓1/(2b)), Hz.

    IEC 61260-1:2014, Clause 5 (band-edge frequencies from the exact mid-band frequencies
    of 5.4, G of 5.2). Adjacent bands share an edge: upper[i] == lower[i + 1].
    """
    centres = band_centres_Hz(fraction, fmin_Hz, fmax_Hz)
    half = OCTAVE_RATIO_G ** (1.0 / (2 * int(fraction)))
    return centres / half, centres * half


def nominal_centres_Hz(fraction: int, fmin_Hz: float, fmax_Hz: float) -> list[str]:
    """Nominal mid-band frequencies as labels ("31.5", "63", ..., "1000"), IEC 61260-1:2014
    Annex E, for the same bands as :func:`band_centres_Hz`."""
    b = _check_fraction(fraction)
    fmin_Hz, fmax_Hz = _check_frequency_range(fmin_Hz, fmax_Hz)
    return [_nominal_label((3 // b) * x) for x in _band_numbers(b, fmin_Hz, fmax_Hz)]


# R10 preferred numbers (ISO 3, ISO 266): the nominal mid-band frequencies of the
# base-ten one-third-octave bands, IEC 61260-1:2014 Annex E, one decade.
_R10 = ("1", "1.25", "1.6", "2", "2.5", "3.15", "4", "5", "6.3", "8")

"""From a force history to the standard's figures: the octave and one-third-octave bands
(:mod:`~rbjax.spectrum.bands`), the energy spectrum, band energies and the force exposure level
L_FE (paper Eq. 11; :mod:`~rbjax.spectrum.levels`, the short-record kernel in
:mod:`~rbjax.spectrum.band_kernel`), the measuring chain's low-pass (:mod:`~rbjax.spectrum.filters`)
and the rubber ball's tolerances in the standards (:mod:`~rbjax.spectrum.standards`).
Plain functions of arrays: nothing here solves an impact."""

from .bands import (
    OCTAVE_BANDS,
    THIRD_OCTAVE_BANDS,
    band_centres_Hz,
    band_edges_Hz,
    nominal_centres_Hz,
)
from .filters import butter_lowpass_sos, lowpass_np, sosfilt_jax
from .levels import (
    band_energies_N2s,
    contact_resonance_Hz,
    energy_spectrum,
    force_spectrum_dB,
    lfe_dB,
    lfe_increase_per_doubling_dB,
    lfe_octave_dB,
    lfe_third_octave_dB,
    lfe_total_dB,
)
from .standards import (
    RUBBER_BALL_TOLERANCES,
    TOLERANCED_OCTAVE_BANDS,
    CheckItem,
    Conformance,
    RubberBallTolerances,
    Tolerance,
    check_conformance,
)

__all__ = [
    "OCTAVE_BANDS",
    "THIRD_OCTAVE_BANDS",
    "band_centres_Hz",
    "band_edges_Hz",
    "nominal_centres_Hz",
    "butter_lowpass_sos",
    "lowpass_np",
    "sosfilt_jax",
    "band_energies_N2s",
    "contact_resonance_Hz",
    "energy_spectrum",
    "force_spectrum_dB",
    "lfe_dB",
    "lfe_increase_per_doubling_dB",
    "lfe_octave_dB",
    "lfe_third_octave_dB",
    "lfe_total_dB",
    "RUBBER_BALL_TOLERANCES",
    "TOLERANCED_OCTAVE_BANDS",
    "CheckItem",
    "Conformance",
    "RubberBallTolerances",
    "Tolerance",
    "check_conformance",
]

"""Figures (matplotlib): force histories, L_FE bands with the tolerance band, and the paper's
Figs. 3–12.

Every function takes an optional ``ax`` (a new figure is made without one) and returns the
figure. Without a display (no ``DISPLAY``/``MPLBACKEND``, pyplot not yet imported) the Agg
backend is selected, so figures can always be saved.

One module a kind of figure: ``histories`` (force against time), ``spectra`` (octave-band L_FE,
its differences per band, narrow-band spectra), ``versus_height`` (quantities against drop
height), ``growth`` (L_FE growth with drop height), ``floors`` (several floors against the
blocked force) and ``fit`` (a fit's figures, written to files), all drawn through ``axes``.
"""

from __future__ import annotations

from .fit import plot_fit
from .floors import plot_floors
from .growth import plot_growth, plot_increase_per_doubling, plot_lfe_increase
from .histories import plot_force_components, plot_force_histories, plot_histories
from .spectra import plot_band_differences, plot_lfe_bands, plot_narrowband
from .spectra import tolerance_limits as tolerance_limits
from .versus_height import plot_relative_difference, plot_vs_height

__all__ = [
    "plot_histories",
    "plot_fit",
    "plot_force_histories",
    "plot_force_components",
    "plot_lfe_bands",
    "plot_vs_height",
    "plot_relative_difference",
    "plot_band_differences",
    "plot_lfe_increase",
    "plot_increase_per_doubling",
    "plot_narrowband",
    "plot_growth",
    "plot_floors",
]

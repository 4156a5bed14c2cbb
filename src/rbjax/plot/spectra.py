"""Force spectra: octave-band L_FE with the standard's tolerance band, its differences per band
(paper Fig. 9) and narrow-band spectra with the contact resonance marked (paper Fig. 12)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.standards import RUBBER_BALL_TOLERANCES
from .axes import colours, figure_and_axes, finish

__all__ = ["tolerance_limits", "plot_lfe_bands", "plot_band_differences", "plot_narrowband"]


def _band_values(lfe, bands):
    if isinstance(lfe, Mapping):
        return np.array([np.nan if lfe.get(b) is None else float(lfe[b]) for b in bands])
    return np.asarray(lfe, dtype=float).reshape(-1)


def tolerance_limits(bands: Sequence[str]):
    """Lower and upper L_FE limits (dB) per octave band from ``standards.RUBBER_BALL_TOLERANCES``
    (ISO 10140-5 Table F.1 = JIS A 1418-2 Table A.2); NaN for bands without a limit (1 kHz)."""

    table = RUBBER_BALL_TOLERANCES.lfe_octave_dB
    lower = [table[b].lower if b in table else np.nan for b in bands]
    upper = [table[b].upper if b in table else np.nan for b in bands]
    return np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)


def plot_lfe_bands(lfe_octave_dB, ax=None, tolerances=True, label=None, **line_kw):
    """L_FE (dB re 1 N²·s, Eq. 11) per octave band, with the standard's tolerance band shaded.

    ``lfe_octave_dB``: a mapping band label → dB (as ``rbjax simulate --json``) or a sequence
    over ``spectrum.OCTAVE_BANDS``. The tolerance band is the rubber ball's L_FE range at the
    standard drop height of 1 m (JIS A 1418-2 / ISO 10140-5 Annex F, via
    ``rbjax.spectrum.standards``).
    """

    fig, ax = figure_and_axes(ax)
    bands = list(OCTAVE_BANDS)
    x = np.arange(len(bands))
    if tolerances and not getattr(ax, "_rbjax_tolerances", False):
        lower, upper = tolerance_limits(bands)
        has = np.isfinite(lower) & np.isfinite(upper)
        if np.any(has):
            ax.fill_between(
                x[has],
                lower[has],
                upper[has],
                color="0.85",
                step=None,
                label="tolerance (1 m)",
                zorder=0,
            )
            ax.plot(x[has], lower[has], color="0.5", ls="--", lw=0.8, zorder=0)
            ax.plot(x[has], upper[has], color="0.5", ls="--", lw=0.8, zorder=0)
        ax._rbjax_tolerances = True
    line_kw.setdefault("marker", "o")
    ax.plot(x, _band_values(lfe_octave_dB, bands), label=label, **line_kw)
    ax.set_xticks(x, bands)
    ax.set_xlabel("octave band centre frequency (Hz)")
    ax.set_ylabel("L_FE (dB re 1 N²s)")
    ax.grid(alpha=0.3)
    if label is not None or tolerances:
        ax.legend(fontsize="small")
    return fig


def plot_band_differences(
    bands, differences: Mapping[str, np.ndarray], ax=None, *, ylabel, title=None
):
    """One line per labelled row of per-band values against the octave bands (paper Fig. 9)."""
    fig, ax = figure_and_axes(ax)
    x = np.arange(len(bands))
    for (name, values), c in zip(differences.items(), colours(len(differences))):
        ax.plot(x, np.asarray(values, dtype=float), marker="o", color=c, label=name)
    ax.set_xticks(x, list(bands))
    legend = {"title": "drop height", "loc": "center left", "bbox_to_anchor": (1.01, 0.5)}
    return finish(fig, ax, "octave band centre frequency (Hz)", ylabel, title, legend=legend)


def plot_narrowband(
    freq_Hz,
    spectra_dB: Mapping[str, np.ndarray],
    ax=None,
    *,
    resonances_Hz=None,
    references_Hz=None,
    fmax_Hz=500.0,
    title=None,
):
    """Narrow-band force spectra (dB) with the contact resonance marked (paper Fig. 12).

    ``spectra_dB``: label → level per frequency; ``resonances_Hz``: label → frequency of the
    first spectral minimum (the fundamental contact resonance) drawn as a marked vertical line;
    ``references_Hz``: label → frequency of a reported value, drawn as a grey dashed line.
    """
    fig, ax = figure_and_axes(ax)
    f = np.asarray(freq_Hz, dtype=float)
    keep = (f > 0) & (f <= fmax_Hz)
    for name, level in spectra_dB.items():
        line = ax.plot(f[keep], np.asarray(level, dtype=float)[keep], label=name)[0]
        fr = (resonances_Hz or {}).get(name)
        if fr is not None and np.isfinite(fr):
            ax.axvline(fr, color=line.get_color(), ls=":", lw=1.0)
            y = np.interp(fr, f[keep], np.asarray(level, dtype=float)[keep])
            ax.plot([fr], [y], marker="v", color=line.get_color(), ms=8)
            ax.annotate(
                f"{fr:.0f} Hz",
                (fr, y),
                textcoords="offset points",
                xytext=(6, -14),
                color=line.get_color(),
                fontsize="small",
            )
    for i, fr in enumerate((references_Hz or {}).values()):  # one legend entry for all of them
        ax.axvline(
            fr, color="0.4", ls="--", lw=0.9, label="; ".join(references_Hz) if i == 0 else None
        )
    ax.set_xlim(0, fmax_Hz)
    return finish(fig, ax, "frequency (Hz)", "|F(f)| (dB re 1 N·s)", title)

"""How L_FE grows with drop height: the increase per band against the height ratio (paper
Fig. 10), the increase per doubling of height (paper Fig. 11) and ``Growth`` estimates of data
and models with their standard errors."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .axes import figure_and_axes, finish

__all__ = ["plot_lfe_increase", "plot_increase_per_doubling", "plot_growth"]


def _paper_points(ax, x, paper, color) -> None:
    """The paper's values (§4.2, read off its figures) as open squares beside the curves."""
    ax.plot(
        x,
        np.asarray(paper, dtype=float),
        ls="none",
        marker="s",
        ms=9,
        mfc="none",
        color=color,
        label="paper (≈, §4.2)",
    )


def plot_lfe_increase(height_ratio, increase_dB, bands, ax=None, *, slopes_dB=None, title=None):
    """L_FE increase (dB) per band against the drop-height ratio, log2 axis (paper Fig. 10).

    ``increase_dB``: (n_heights, n_bands); ``slopes_dB``: fitted dB per doubling per band,
    drawn as dashed lines through the origin of the ratio 1.
    """
    fig, ax = figure_and_axes(ax)
    ratio = np.asarray(height_ratio, dtype=float)
    inc = np.asarray(increase_dB, dtype=float)
    for j, band in enumerate(bands):
        line = ax.plot(ratio, inc[:, j], marker=".", label=f"{band} Hz")[0]
        if slopes_dB is not None:
            ax.plot(ratio, slopes_dB[j] * np.log2(ratio), ls="--", lw=0.8, color=line.get_color())
    ax.set_xscale("log", base=2)
    legend = {"ncol": 2, "title": "octave band (dashed: linear fit)"}
    return finish(
        fig,
        ax,
        "drop height / 1 m",
        "L_FE increase re 1 m (dB)",
        title,
        legend=legend,
        grid={"which": "both"},
    )


def plot_increase_per_doubling(
    bands, slopes: Mapping[str, np.ndarray], ax=None, *, paper=None, title=None
):
    """L_FE increase per doubling of drop height (dB) per octave band (paper Fig. 11).

    ``slopes``: label → dB per band; ``paper``: dB per band as reported (NaN where none).
    """
    fig, ax = figure_and_axes(ax)
    x = np.arange(len(bands))
    for name, values in slopes.items():
        ax.plot(x, np.asarray(values, dtype=float), marker="o", label=name)
    if paper is not None:
        _paper_points(ax, x, paper, "k")
    ax.set_xticks(x, list(bands))
    return finish(
        fig,
        ax,
        "octave band centre frequency (Hz)",
        "L_FE increase per doubling of height (dB)",
        title,
    )


def plot_growth(growths, ax=None, *, paper=None, title=None):
    """L_FE growth per doubling of drop height per band, data against models, with ±1
    standard-error bars (``rbjax.studies.growth.Growth`` objects; paper Fig. 11).

    ``growths``: a sequence of ``Growth`` (their ``label`` is the legend); the first one is
    drawn with markers only (the data), the rest as lines; ``paper``: dB per band as
    reported (NaN where none). A dotted line marks a linear source, 10·log10 2 = 3.01 dB.
    """
    fig, ax = figure_and_axes(ax)
    growths = list(growths)
    if not growths:
        raise ValueError(
            "plot_growth: growths is empty (give at least one rbjax.studies.growth.Growth)"
        )
    bands = growths[0].bands_Hz
    x = np.arange(len(bands))
    n = len(growths)
    for k, g in enumerate(growths):
        if g.bands_Hz != bands:
            raise ValueError(f"plot_growth: {g.label!r} has bands {g.bands_Hz}, expected {bands}")
        dx = (k - (n - 1) / 2) * 0.06
        err = np.where(np.isfinite(g.stderr_dB), g.stderr_dB, 0.0)
        style = (
            {"ls": "none", "marker": "o", "ms": 6, "color": "k"}
            if k == 0
            else {"marker": ".", "lw": 1.2}
        )
        ax.errorbar(
            x + dx, g.slope_dB, yerr=err, capsize=3, label=g.label or f"series {k + 1}", **style
        )
    if paper is not None:
        _paper_points(ax, x, paper, "0.4")
    ax.axhline(10.0 * np.log10(2.0), color="0.6", lw=0.8, ls=":")
    ax.set_xticks(x, list(bands))
    return finish(
        fig,
        ax,
        "octave band centre frequency (Hz)",
        "L_FE growth per doubling of height (dB)",
        title,
    )

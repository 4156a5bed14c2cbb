"""Quantities against drop height (paper Figs. 5, 6) and rbjax's relative difference from the
paper's reported values (paper Fig. 7 analogue)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .axes import figure_and_axes, finish

__all__ = ["plot_vs_height", "plot_relative_difference"]


def plot_vs_height(
    heights_m,
    series: Mapping[str, np.ndarray],
    ax=None,
    *,
    ylabel,
    scale=1.0,
    references=None,
    band=None,
    title=None,
):
    """Quantities against drop height in cm (paper Figs. 5, 6).

    ``series``: label → values per height (multiplied by ``scale``); ``references``: label →
    (heights_m, values) drawn as markers; ``band``: (label, low, high) shaded horizontally.
    """
    fig, ax = figure_and_axes(ax)
    h_cm = np.asarray(heights_m, dtype=float) * 100
    if band is not None:
        name, low, high = band
        ax.axhspan(low * scale, high * scale, color="0.9", label=name, zorder=0)
    for name, values in series.items():
        ax.plot(h_cm, np.asarray(values, dtype=float) * scale, marker=".", label=name)
    markers = iter("sD^v<>")
    for name, (hs, vs) in (references or {}).items():
        ax.plot(
            np.asarray(hs, dtype=float) * 100,
            np.asarray(vs, dtype=float) * scale,
            ls="none",
            marker=next(markers),
            ms=7,
            mfc="none",
            mew=1.5,
            label=name,
        )
    return finish(fig, ax, "drop height (cm)", ylabel, title)


def plot_relative_difference(entries: Sequence[Mapping], ax=None, *, title=None):
    """Relative difference (%) of rbjax to the paper's reported values (paper Fig. 7 analogue).

    ``entries``: dicts with ``label``, ``height_m`` and ``relative_difference`` (label of the
    model variant → fraction).
    """
    fig, ax = figure_and_axes(ax, figsize=(7.0, 4.2))
    variants = list(dict.fromkeys(k for e in entries for k in e["relative_difference"]))
    markers = dict(zip(variants, "os^D"))
    labels = sorted({e["label"] for e in entries}, key=[e["label"] for e in entries].index)
    colours = dict(zip(labels, [f"C{i}" for i in range(len(labels))]))
    for e in entries:
        for v, rel in e["relative_difference"].items():
            if rel is None or not np.isfinite(rel):
                continue
            ax.plot(
                e["height_m"] * 100,
                rel * 100,
                ls="none",
                marker=markers[v],
                color=colours[e["label"]],
                ms=7,
                mfc="none" if v != variants[0] else colours[e["label"]],
            )
    # lazy: matplotlib costs 0.1–0.2 s at import
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color=colours[lab], marker="o", ls="none", label=lab) for lab in labels
    ]
    handles += [
        Line2D(
            [],
            [],
            color="k",
            marker=markers[v],
            ls="none",
            mfc="k" if v == variants[0] else "none",
            label=v,
        )
        for v in variants
    ]
    ax.axhline(0.0, color="k", lw=0.8)
    ax.axhspan(-10, 10, color="0.93", zorder=0)
    ax.set_xlim(0, 170)
    return finish(
        fig,
        ax,
        "drop height (cm)",
        "rbjax − paper (% of paper value)",
        title,
        legend={"handles": handles, "loc": "best"},
    )

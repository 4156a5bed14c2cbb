"""What every figure shares: the headless backend, the axes to draw on, the colours of a series
and the finishing touches (labels, grid, legend, title).

Importing this module selects matplotlib's Agg backend when there is no display (no
``DISPLAY``/``MPLBACKEND``, pyplot not yet imported), so figures can always be saved; every
module of ``rbjax.plot`` draws through it.
"""

from __future__ import annotations

import os
import sys

import matplotlib
import numpy as np

if (
    "matplotlib.pyplot" not in sys.modules
    and not os.environ.get("DISPLAY")
    and not os.environ.get("MPLBACKEND")
):
    matplotlib.use("Agg")

__all__ = ["figure_and_axes", "colours", "finish"]


def figure_and_axes(ax, figsize=(6.4, 4.2)):
    """``(figure, ax)`` of the given axes, or of a new figure of ``figsize`` without them."""
    if ax is not None:
        return ax.figure, ax
    # lazy: matplotlib.pyplot costs ~1 s at import
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize, layout="constrained")
    return fig, ax


def colours(n: int):
    """``n`` colours along the viridis map (one for ``n`` = 0), for the lines of a series."""
    # lazy: matplotlib.pyplot costs ~1 s at import
    import matplotlib as mpl

    cmap = mpl.colormaps["viridis"]
    return [cmap(x) for x in np.linspace(0.0, 0.9, max(n, 1))]


def finish(fig, ax, xlabel: str, ylabel: str, title=None, *, legend=None, grid=None):
    """Label the axes, draw a light grid (``grid``: more ``ax.grid`` arguments) and a legend in
    small type (``legend``: more ``ax.legend`` arguments), set the title if any; return ``fig``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, **(grid or {}))
    ax.legend(**{"fontsize": "small", **(legend or {})})
    if title:
        ax.set_title(title)
    return fig

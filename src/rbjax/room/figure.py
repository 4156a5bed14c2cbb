"""The figures of the room chain's results: an ``ImpactSound``'s band levels (as measured and
normalised) beside the Fast-weighted level of each band against time; a ``PositionAverage``'s
band levels per drop position beside their energy average."""

from __future__ import annotations

import numpy as np


def plot_impact_sound(res, path=None):
    """Two panels: L_i,Fmax and L_i,Fmax,n per band with the ratings; L_F(t) per band. Saved
    to ``path`` when given; returns the figure."""
    import matplotlib  # lazy: matplotlib costs 0.1–0.2 s at import

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # lazy: matplotlib.pyplot costs ~1 s at import

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
    x = np.arange(len(res.bands))
    left.plot(
        x,
        res.level_dB,
        "o-",
        label=f"L_i,Fmax (V = {res.volume_m3:g} m³); L_iA,Fmax = {res.LiA_Fmax_dB} dB",
    )
    left.plot(
        x,
        res.normalised_dB,
        "s--",
        label=f"normalised (50 m³, 0.5 s); {res.LiA_Fmax_normalised_dB} dB",
    )
    left.set_xticks(x, res.bands)
    left.set_xlabel("band, Hz")
    left.set_ylabel("level, dB re 20 µPa")
    left.legend(fontsize="small")
    left.grid(alpha=0.3)
    t = np.linspace(0.0, max(1.0, 3.0 * max(res.peak_time_s)), 400)
    for label, row in zip(res.bands, res.fast_levels_dB(t)):
        right.plot(t, row, label=f"{label} Hz")
    top = max(res.level_dB)
    right.set_ylim(top - 60.0, top + 5.0)
    right.set_xlabel("time after the impact, s")
    right.set_ylabel("L_F(t), dB")
    right.legend(fontsize="small", ncol=2)
    right.grid(alpha=0.3)
    fig.suptitle(f"{res.floor}: ball from {res.height_m:g} m")
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig


def plot_position_average(res, path=None):
    """The band levels of each position of a ``PositionAverage`` (thin) and their energy
    average (thick). Saved to ``path`` when given; returns the figure."""
    import matplotlib  # lazy: matplotlib costs 0.1–0.2 s at import

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # lazy: matplotlib.pyplot costs ~1 s at import

    fig, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    x = np.arange(len(res.bands))
    for (px, py), one in zip(res.positions_m, res.results):
        ax.plot(
            x, one.level_dB, "-", lw=0.8, alpha=0.7,
            label=f"({px:g}, {py:g}) m: {one.LiA_Fmax_dB} dB",
        )  # fmt: skip
    ax.plot(
        x, res.level_dB, "ko-", lw=2.0,
        label=f"energy average: L_iA,Fmax = {res.LiA_Fmax_dB} dB",
    )  # fmt: skip
    ax.set_xticks(x, res.bands)
    ax.set_xlabel("band, Hz")
    ax.set_ylabel("L_i,Fmax, dB re 20 µPa")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig

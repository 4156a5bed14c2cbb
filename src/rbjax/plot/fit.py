"""The figures of a ``FitResult``, written to files: measured against fitted histories with
their residuals, octave-band L_FE and the parameter correlations."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..spectrum.bands import OCTAVE_BANDS

__all__ = ["plot_fit"]


def plot_fit(result, out_dir) -> list[Path]:
    """Write ``histories.png`` (measured vs fitted with residuals), ``lfe_bands.png`` and
    ``correlations.png`` of a ``FitResult`` into ``out_dir``; return their paths."""
    # lazy: matplotlib.pyplot costs ~1 s at import
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    t_ms = result.time_s * 1e3
    n = len(result.heights_m)
    fig, axes = plt.subplots(
        2, 1, figsize=(7.5, 6.5), sharex=True, height_ratios=(3, 1), layout="constrained"
    )
    colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, max(n, 1)))
    for k in range(n):
        label = f"{result.heights_m[k] * 100:.0f} cm" + ("" if result.in_fit[k] else " (held out)")
        axes[0].plot(t_ms, result.measured_N[k], color=colours[k], lw=0.8, alpha=0.6)
        axes[0].plot(t_ms, result.predicted_N[k], color=colours[k], lw=1.2, ls="--", label=label)
        axes[1].plot(t_ms, result.predicted_N[k] - result.measured_N[k], color=colours[k], lw=0.8)
    axes[0].set_ylabel("force (N)")
    axes[0].set_title(f"{result.model_name}: measured (solid) and fitted (dashed)")
    axes[0].legend(fontsize=8, ncol=2)
    axes[1].set_ylabel("fitted − measured (N)")
    axes[1].set_xlabel("time (ms)")
    paths.append(out / "histories.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    bands = OCTAVE_BANDS
    fig, ax = plt.subplots(figsize=(7.0, 4.5), layout="constrained")
    x = np.arange(len(bands))
    for k, row in enumerate(result.per_height):
        ax.plot(
            x,
            row["measured"]["lfe_octave_dB"],
            "o-",
            color=colours[k],
            lw=0.8,
            label=f"{row['height_m'] * 100:.0f} cm",
        )
        ax.plot(x, row["fitted"]["lfe_octave_dB"], "x--", color=colours[k], lw=1.2)
    ax.set_xticks(x, bands)
    ax.set_xlabel("octave band (Hz)")
    ax.set_ylabel("L_FE (dB re 1 N, T0 = 1 s)")
    ax.set_title("octave-band L_FE (Eq. 11): measured (o) and fitted (x)")
    ax.legend(fontsize=8, ncol=2)
    paths.append(out / "lfe_bands.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)

    names, matrix = result.correlations
    fig, ax = plt.subplots(figsize=(5.0, 4.2), layout="constrained")
    m = np.asarray(matrix, dtype=float).reshape(len(names), len(names))
    im = ax.imshow(m, vmin=-1, vmax=1, cmap="RdBu_r")
    ax.set_xticks(range(len(names)), names, rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(len(names)), names, fontsize=8)
    for i in range(len(names)):
        for j in range(len(names)):
            ax.text(j, i, f"{m[i, j]:.2f}", ha="center", va="center", fontsize=8)
    fig.colorbar(im, ax=ax, label="correlation")
    ax.set_title("parameter correlations")
    paths.append(out / "correlations.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    return paths

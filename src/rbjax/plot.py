"""Figures (matplotlib): force histories, L_FE bands with the tolerance band, and the paper's
Figs. 3–12.

Every function takes an optional ``ax`` (a new figure is made without one) and returns the
figure. Without a display (no ``DISPLAY``/``MPLBACKEND``, pyplot not yet imported) the Agg
backend is selected, so figures can always be saved.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib
import numpy as np

from .spectrum.bands import OCTAVE_BANDS
from .spectrum.levels import lfe_octave_dB
from .spectrum.standards import RUBBER_BALL_TOLERANCES

if (
    "matplotlib.pyplot" not in sys.modules
    and not os.environ.get("DISPLAY")
    and not os.environ.get("MPLBACKEND")
):
    matplotlib.use("Agg")

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


def _axes(ax, figsize=(6.4, 4.2)):
    if ax is not None:
        return ax.figure, ax
    # lazy: matplotlib.pyplot costs ~1 s at import
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=figsize, layout="constrained")
    return fig, ax


def _colours(n: int):
    # lazy: matplotlib.pyplot costs ~1 s at import
    import matplotlib as mpl

    cmap = mpl.colormaps["viridis"]
    return [cmap(x) for x in np.linspace(0.0, 0.9, max(n, 1))]


def _finish(fig, ax, xlabel: str, ylabel: str, title=None, *, legend=None, grid=None):
    """Label the axes, draw a light grid (``grid``: more ``ax.grid`` arguments) and a legend in
    small type (``legend``: more ``ax.legend`` arguments), set the title if any; return ``fig``."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3, **(grid or {}))
    ax.legend(**{"fontsize": "small", **(legend or {})})
    if title:
        ax.set_title(title)
    return fig


def _contact_window(t_ms, values, contact_time_s, margin=1.1):
    """Only the samples up to ``margin`` × the longest contact (the rest of a 1 s record is
    zeros)."""
    if contact_time_s is None or not np.any(np.isfinite(contact_time_s)):
        return t_ms, values
    keep = t_ms <= margin * 1e3 * float(np.nanmax(contact_time_s))
    return t_ms[keep], values[..., keep]


def plot_force_histories(time_s, force_N, heights_m, ax=None, *, contact_time_s=None, title=None):
    """Force (N) against time (ms), one line per drop height (rows of ``force_N``)."""
    fig, ax = _axes(ax)
    t_ms = np.asarray(time_s, dtype=float) * 1e3
    force = np.atleast_2d(np.asarray(force_N, dtype=float))
    heights = np.atleast_1d(np.asarray(heights_m, dtype=float)).reshape(-1)
    t_ms, force = _contact_window(t_ms, force, contact_time_s)
    for f, h, c in zip(force, heights, _colours(len(heights))):
        ax.plot(t_ms, f, color=c, lw=1.2, label=f"{h * 100:.0f} cm")
    if contact_time_s is not None and np.any(np.isfinite(contact_time_s)):
        ax.set_xlim(0.0, 1.05e3 * float(np.nanmax(contact_time_s)))
    ax.set_ylim(bottom=0.0)
    where = (
        {"loc": "center left", "bbox_to_anchor": (1.01, 0.5)}
        if len(heights) > 6
        else {"loc": "upper right"}
    )
    return _finish(
        fig, ax, "time (ms)", "blocked force (N)", title, legend={"title": "drop height", **where}
    )


def plot_histories(result, ax=None, rate_Hz=None):
    """Blocked-force histories of an ``ImpactResult`` over the contact, one line per height.

    Used by ``ImpactResult.plot()``. ``rate_Hz`` (default: the result's, 44.1 kHz as in §2.4)
    sets the sampling of the plotted histories.
    """
    traj = result.history(rate_Hz=rate_Hz)
    heights = np.asarray(result.height_m, dtype=float).reshape(-1)
    force = np.asarray(traj.force_N, dtype=float).reshape(heights.size, -1)
    tc = np.asarray(result.contact_time_s, dtype=float)
    return plot_force_histories(
        np.asarray(traj.time_s),
        force,
        heights,
        ax,
        contact_time_s=tc,
        title=f"rbjax: model {result.model.name}, gas {result.model.gas}",
    )


def plot_force_components(
    time_s,
    forces: Mapping[str, np.ndarray],
    ax=None,
    *,
    contact_time_s=None,
    title=None,
    styles=None,
):
    """Named force histories (e.g. F_T, F_B, F_G; paper Fig. 3) in N against time in ms."""
    fig, ax = _axes(ax)
    t_ms = np.asarray(time_s, dtype=float) * 1e3
    styles = styles or {}
    for name, f in forces.items():
        t, f = _contact_window(t_ms, np.asarray(f, dtype=float), contact_time_s)
        ax.plot(t, f, label=name, **styles.get(name, {}))
    if contact_time_s is not None:
        ax.set_xlim(0.0, 1.05e3 * float(contact_time_s))
    return _finish(fig, ax, "time (ms)", "force (N)", title)


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

    fig, ax = _axes(ax)
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
    fig, ax = _axes(ax)
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
    return _finish(fig, ax, "drop height (cm)", ylabel, title)


def plot_relative_difference(entries: Sequence[Mapping], ax=None, *, title=None):
    """Relative difference (%) of rbjax to the paper's reported values (paper Fig. 7 analogue).

    ``entries``: dicts with ``label``, ``height_m`` and ``relative_difference`` (label of the
    model variant → fraction).
    """
    fig, ax = _axes(ax, figsize=(7.0, 4.2))
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
    return _finish(
        fig,
        ax,
        "drop height (cm)",
        "rbjax − paper (% of paper value)",
        title,
        legend={"handles": handles, "loc": "best"},
    )


def plot_band_differences(
    bands, differences: Mapping[str, np.ndarray], ax=None, *, ylabel, title=None
):
    """One line per labelled row of per-band values against the octave bands (paper Fig. 9)."""
    fig, ax = _axes(ax)
    x = np.arange(len(bands))
    for (name, values), c in zip(differences.items(), _colours(len(differences))):
        ax.plot(x, np.asarray(values, dtype=float), marker="o", color=c, label=name)
    ax.set_xticks(x, list(bands))
    legend = {"title": "drop height", "loc": "center left", "bbox_to_anchor": (1.01, 0.5)}
    return _finish(fig, ax, "octave band centre frequency (Hz)", ylabel, title, legend=legend)


def plot_lfe_increase(height_ratio, increase_dB, bands, ax=None, *, slopes_dB=None, title=None):
    """L_FE increase (dB) per band against the drop-height ratio, log2 axis (paper Fig. 10).

    ``increase_dB``: (n_heights, n_bands); ``slopes_dB``: fitted dB per doubling per band,
    drawn as dashed lines through the origin of the ratio 1.
    """
    fig, ax = _axes(ax)
    ratio = np.asarray(height_ratio, dtype=float)
    inc = np.asarray(increase_dB, dtype=float)
    for j, band in enumerate(bands):
        line = ax.plot(ratio, inc[:, j], marker=".", label=f"{band} Hz")[0]
        if slopes_dB is not None:
            ax.plot(ratio, slopes_dB[j] * np.log2(ratio), ls="--", lw=0.8, color=line.get_color())
    ax.set_xscale("log", base=2)
    legend = {"ncol": 2, "title": "octave band (dashed: linear fit)"}
    return _finish(
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
    fig, ax = _axes(ax)
    x = np.arange(len(bands))
    for name, values in slopes.items():
        ax.plot(x, np.asarray(values, dtype=float), marker="o", label=name)
    if paper is not None:
        ax.plot(
            x,
            np.asarray(paper, dtype=float),
            ls="none",
            marker="s",
            ms=9,
            mfc="none",
            color="k",
            label="paper (≈, §4.2)",
        )
    ax.set_xticks(x, list(bands))
    return _finish(
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
    fig, ax = _axes(ax)
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
        ax.plot(
            x,
            np.asarray(paper, dtype=float),
            ls="none",
            marker="s",
            ms=9,
            mfc="none",
            color="0.4",
            label="paper (≈, §4.2)",
        )
    ax.axhline(10.0 * np.log10(2.0), color="0.6", lw=0.8, ls=":")
    ax.set_xticks(x, list(bands))
    return _finish(
        fig,
        ax,
        "octave band centre frequency (Hz)",
        "L_FE growth per doubling of height (dB)",
        title,
    )


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
    fig, ax = _axes(ax)
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
    return _finish(fig, ax, "frequency (Hz)", "|F(f)| (dB re 1 N·s)", title)


def plot_floors(results: Mapping[str, object], blocked=None, axes=None, *, title=None):
    """The force on several floors against the blocked force: force histories, octave-band
    L_FE and L_FE on the floor minus L_FE of the blocked force (three panels).

    ``results``: label → ``ImpactResult`` of one drop height on that floor (the first height of
    a batch is drawn); ``blocked``: the ``ImpactResult`` on the rigid floor (default: the entry
    of ``results`` whose floor is rigid), drawn in black. ``axes``: three axes (a new figure is
    made without them). Returns the figure.
    """

    if blocked is None:
        rigid = [r for r in results.values() if r.model.floor.rigid]  # type: ignore[attr-defined]
        if not rigid:
            raise ValueError(
                "plot_floors: no result on the rigid floor; pass blocked=rbjax.simulate(h) (the "
                "blocked force)"
            )
        blocked = rigid[0]
    if axes is None:
        # lazy: matplotlib.pyplot costs ~1 s at import
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.2), layout="constrained")
    fig = axes[0].figure

    def first(result):
        traj = result.history()
        n = traj.force_N.shape[-1]
        force = np.asarray(traj.force_N, dtype=float).reshape(-1, n)[0]
        tc = float(np.asarray(result.contact_time_s, dtype=float).reshape(-1)[0])
        return (
            np.asarray(traj.time_s, dtype=float),
            force,
            tc,
            np.asarray(lfe_octave_dB(force, result.rate_Hz), dtype=float),
        )

    t, f0, tc0, lfe0 = first(blocked)
    curves = [(label, first(r)) for label, r in results.items() if r is not blocked]
    longest = max([tc0, *(c[1][2] for c in curves if np.isfinite(c[1][2]))])
    x = np.arange(len(OCTAVE_BANDS))
    ax_f, ax_l, ax_d = axes
    blocked_style = dict(color="k", ls="--", lw=1.4, label="blocked (rigid floor)")
    keep = t <= 1.1 * longest
    ax_f.plot(t[keep] * 1e3, f0[keep], **blocked_style)
    ax_l.plot(x, lfe0, marker="o", **blocked_style)
    for (label, (_, force, _, lfe)), c in zip(curves, _colours(len(curves))):
        ax_f.plot(t[keep] * 1e3, force[keep], color=c, lw=1.2, label=label)
        ax_l.plot(x, lfe, marker="o", color=c, label=label)
        ax_d.plot(x, lfe - lfe0, marker="o", color=c, label=label)
    ax_f.set_xlim(0.0, 1.05e3 * longest)
    ax_f.set_ylim(bottom=0.0)
    ax_d.axhline(0.0, color="k", lw=0.8)
    for ax in (ax_l, ax_d):
        ax.set_xticks(x, list(OCTAVE_BANDS))
    h = float(np.asarray(blocked.height_m, dtype=float).reshape(-1)[0])
    _finish(fig, ax_f, "time (ms)", "force on the floor (N)", f"drop height {h * 100:.0f} cm")
    _finish(fig, ax_l, "octave band centre frequency (Hz)", "L_FE (dB re 1 N²s)", None)
    _finish(fig, ax_d, "octave band centre frequency (Hz)", "L_FE − L_FE,blocked (dB)", None)
    if title:
        fig.suptitle(title)
    return fig


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

"""The figures of ``reproduce``, like the paper's Figs. 3–12 (Schoenwald, Zeitler & Nightingale
2011, §4): the force components at 1 m, the force histories, peak force and contact time against
height, rbjax relative to the paper's values, L_FE at 1 m within the rubber-ball tolerances, L_FE
normalised to 1 m, its increase with height and per doubling, and the narrow-band spectra with the
contact resonance. Drawn from the runs of :mod:`~rbjax.report.predictions` as PNG files.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..solve.inputs import PAPER_RATE_Hz
from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.levels import force_spectrum_dB
from ..spectrum.standards import RUBBER_BALL_TOLERANCES
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.forces import gas_force_N, shell_force_N
from .paper import FIG9_HEIGHTS_M, GAS, PAPER, STANDARD_HEIGHT_M, solved_ends
from .predictions import standard_index


class _Scene:
    """What every figure reads: the runs (``"adiabatic"``, ``"none"``), the heights, the index of
    1 m, the comparison with the paper, the growth fits, and the plotting module and figure
    class (imported on first use)."""

    def __init__(self, runs, heights, comparison, growth, plot, figure_class):
        self.runs, self.heights, self.comparison, self.growth = runs, heights, comparison, growth
        self.i1 = standard_index(heights)
        self.plot, self._figure_class = plot, figure_class

    def figure(self, ncols=1, width=6.4, height=4.4):
        fig = self._figure_class(figsize=(width * ncols, height), layout="constrained")
        return fig, np.atleast_1d(fig.subplots(1, ncols))


def _fig03_force_components(sc: _Scene):
    """F_T, F_B, F_G at 1 m (the forces evaluated on the trajectory's deflection)."""
    fig, (ax,) = sc.figure()
    on, off = sc.runs["adiabatic"], sc.runs["none"]
    d, inside = on["deflection_m"][sc.i1], on["in_contact"][sc.i1]
    fb = np.where(inside, np.asarray(shell_force_N(d, JIS_RUBBER_BALL)), 0.0)
    fg = np.where(inside, np.asarray(gas_force_N(d, JIS_RUBBER_BALL)), 0.0)
    sc.plot.plot_force_components(
        on["time_s"],
        {
            "F_T = F_B + F_G": fb + fg,
            "F_B (shell, Eqs. 1–3)": fb,
            "F_G (gas, Eq. 4 corrected)": fg,
            "F_T, gas off": off["force_N"][sc.i1],
        },
        ax,
        contact_time_s=max(on["contact_time_s"][sc.i1], off["contact_time_s"][sc.i1]),
        title="Fig. 3: force components at 1 m drop height",
        styles={"F_T, gas off": {"color": "0.5", "ls": "--"}},
    )
    return fig, "fig03_force_components_1m.png"


def _fig04_force_histories(sc: _Scene):
    """The histories at every height, one panel per gas law."""
    fig, axes = sc.figure(2)
    for ax, (gas, run) in zip(axes, sc.runs.items()):
        sc.plot.plot_force_histories(
            sc.runs["adiabatic"]["time_s"],
            run["force_N"],
            sc.heights,
            ax,
            contact_time_s=run["contact_time_s"],
            title=f"Fig. 4: blocked force, {GAS[gas]}",
        )
    return fig, "fig04_force_histories.png"


def _paper_points(name: str):
    """(heights, values) of one of the paper's tabulated series."""
    series = PAPER[name]
    return [float(h) for h in series], list(series.values())


def _fig05_peak_force(sc: _Scene):
    """The peak force against height, with the paper's values."""
    fig, (ax,) = sc.figure()
    sc.plot.plot_vs_height(
        sc.heights,
        {f"rbjax, {GAS[g]}": sc.runs[g]["peak_force_N"] for g in GAS},
        ax,
        ylabel="peak force (N)",
        references={"paper (≈, §4.1)": _paper_points("peak_force_N")},
        title="Fig. 5: peak force against drop height",
    )
    return fig, "fig05_peak_force.png"


def _fig06_contact_time(sc: _Scene):
    """The contact time against height, with the paper's and the standard's tolerance."""
    fig, (ax,) = sc.figure()
    tol = _contact_time_tolerance()
    sc.plot.plot_vs_height(
        sc.heights,
        {f"rbjax, {GAS[g]}": sc.runs[g]["contact_time_s"] for g in GAS},
        ax,
        ylabel="contact time (ms)",
        scale=1e3,
        references={
            "paper, predicted (§4.1)": _paper_points("predicted_contact_time_s"),
            "paper, measured (§4.1)": _paper_points("measured_contact_time_s"),
        },
        band=("tolerance 20 ± 2 ms (at 1 m)", tol[0], tol[1]),
        title="Fig. 6: contact time against drop height",
    )
    return fig, "fig06_contact_time.png"


def _fig07_relative_difference(sc: _Scene):
    """rbjax relative to the paper's reported values."""
    fig, (ax,) = sc.figure(width=7.0)
    entries = [
        {
            "label": r["series"],
            "height_m": r["height_m"],
            "relative_difference": {GAS[g]: v for g, v in r["relative_difference"].items()},
        }
        for r in sc.comparison
        if r["height_m"] is not None and not r["key"].startswith("contact_resonance")
    ]
    sc.plot.plot_relative_difference(
        entries, ax, title="Fig. 7: rbjax relative to the paper's values (grey: ±10 %)"
    )
    return fig, "fig07_relative_difference.png"


def _fig08_lfe_at_1m(sc: _Scene):
    """The octave L_FE at 1 m inside the tolerance band."""
    fig, (ax,) = sc.figure()
    for g in GAS:
        sc.plot.plot_lfe_bands(sc.runs[g]["lfe_octave_dB"][sc.i1], ax, label=f"rbjax, {GAS[g]}")
    ax.set_title("Fig. 8: L_FE at 1 m with the rubber-ball tolerances")
    return fig, "fig08_lfe_1m.png"


def _fig09_lfe_normalised(sc: _Scene):
    """L_FE per band relative to 1 m at the paper's heights."""
    fig, axes = sc.figure(2)
    heights = sc.heights
    pick = [h for h in FIG9_HEIGHTS_M if np.any(np.isclose(heights, h))] or list(heights)
    for ax, (g, run) in zip(axes, sc.runs.items()):
        rows = {
            f"{h * 100:.0f} cm": run["lfe_octave_dB"][np.flatnonzero(np.isclose(heights, h))[0]]
            - run["lfe_octave_dB"][sc.i1]
            for h in pick
        }
        sc.plot.plot_band_differences(
            OCTAVE_BANDS,
            rows,
            ax,
            ylabel="L_FE(h) − L_FE(1 m) (dB)",
            title=f"Fig. 9: L_FE normalised to 1 m, {GAS[g]}",
        )
    return fig, "fig09_lfe_normalised.png"


def _fig10_lfe_increase(sc: _Scene):
    """The increase against the height ratio, with the linear fits of Fig. 11."""
    fig, axes = sc.figure(2)
    for ax, (g, run) in zip(axes, sc.runs.items()):
        sc.plot.plot_lfe_increase(
            sc.heights / STANDARD_HEIGHT_M,
            run["lfe_octave_dB"] - run["lfe_octave_dB"][sc.i1],
            OCTAVE_BANDS,
            ax,
            slopes_dB=run["increase_per_doubling_dB"],
            title=f"Fig. 10: L_FE increase, {GAS[g]}",
        )
    return fig, "fig10_lfe_increase.png"


def _fig11_increase_per_doubling(sc: _Scene):
    """The increase per doubling of the height, with the paper's and the recordings'."""
    fig, (ax,) = sc.figure()
    series = {f"rbjax, {GAS[g]}": sc.runs[g]["increase_per_doubling_dB"] for g in GAS}
    if sc.growth and "recordings" in sc.growth:
        series["emulated recordings (bundled)"] = sc.growth["recordings"].slope_dB
    across = (sc.growth or {}).get("measured_ball")
    if across is not None:
        series["measured-ball model (layer + arrest)"] = across["growth_dB"]
    sc.plot.plot_increase_per_doubling(
        OCTAVE_BANDS,
        series,
        ax,
        paper=[PAPER["increase_per_doubling_dB"][b] for b in OCTAVE_BANDS],
        title="Fig. 11: L_FE increase per doubling of drop height",
    )
    if across is not None:  # what the paper states of its measured ball (read off Fig. 11)
        for band, (value, low, high) in across["paper_growth_dB"].items():
            x = list(OCTAVE_BANDS).index(band)
            ax.errorbar(
                [x], [value], yerr=[[value - low], [high - value]], fmt="s", color="C3", capsize=4
            )
        ax.plot([], [], "s", color="C3", label="paper, measured ball (§4.2, as stated)")
        ax.legend(fontsize=7)
    ax.axhline(10 * math.log10(2), color="0.6", lw=0.8, ls=":")
    return fig, "fig11_increase_per_doubling.png"


def _fig12_contact_resonance(sc: _Scene):
    """Narrow-band spectra at the lowest and highest height, the contact resonance marked."""
    fig, axes = sc.figure(2)
    freq = np.arange(0.0, 400.0 + 0.125, 0.25)
    ends = list(solved_ends(sc.runs["adiabatic"]))
    labels = [f"{sc.heights[i] * 100:.0f} cm" for i in ends]
    for ax, (g, run) in zip(axes, sc.runs.items()):
        # The record is zero after the contact, so its DTFT is that of the contact samples.
        n = int(np.max(np.sum(run["in_contact"], axis=1))) + 1
        f, level = force_spectrum_dB(run["force_N"][ends, :n], PAPER_RATE_Hz, freq)
        sc.plot.plot_narrowband(
            np.asarray(f),
            dict(zip(labels, np.asarray(level))),
            ax,
            resonances_Hz=dict(zip(labels, run["contact_resonance_Hz"][ends])),
            references_Hz={
                ("paper: " if i == 0 else "") + f"{v:g} Hz at {float(h) * 100:.0f} cm": v
                for i, (h, v) in enumerate(PAPER["contact_resonance_Hz"].items())
            },
            fmax_Hz=400.0,
            title=f"Fig. 12: force spectrum, {GAS[g]}",
        )
    return fig, "fig12_contact_resonance.png"


#: The figures in the order they are written.
FIGURES = (
    _fig03_force_components,
    _fig04_force_histories,
    _fig05_peak_force,
    _fig06_contact_time,
    _fig07_relative_difference,
    _fig08_lfe_at_1m,
    _fig09_lfe_normalised,
    _fig10_lfe_increase,
    _fig11_increase_per_doubling,
    _fig12_contact_resonance,
)


def draw_figures(out: Path, runs, heights, comparison, growth=None) -> list[str]:
    """Draw Figs. 3–12 into ``out``; the file names written, in order."""

    # lazy: matplotlib.figure costs ~0.9 s at import
    from matplotlib.figure import Figure

    # lazy: rbjax.plot imports matplotlib (0.1–0.2 s; pyplot ~1 s)
    from .. import plot

    scene = _Scene(runs, heights, comparison, growth, plot, Figure)
    files = []
    for draw in FIGURES:
        fig, name = draw(scene)
        fig.savefig(out / name, dpi=120)
        files.append(name)
    return files


def _contact_time_tolerance():
    """The rubber-ball tolerance on the contact time (at 1 m), lower and upper, s."""

    tol = RUBBER_BALL_TOLERANCES.contact_time
    return tol.lower, tol.upper

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

from ..solve.simulate import PAPER_RATE_Hz
from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.levels import force_spectrum_dB
from ..spectrum.standards import RUBBER_BALL_TOLERANCES
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.forces import gas_force_N, shell_force_N
from .paper import FIG9_HEIGHTS_M, GAS, PAPER, STANDARD_HEIGHT_M, solved_ends
from .predictions import standard_index


def draw_figures(out: Path, runs, heights, comparison, growth=None) -> list[str]:
    """Draw Figs. 3–12 into ``out``; the file names written, in order."""

    # lazy: matplotlib.figure costs ~0.9 s at import
    from matplotlib.figure import Figure

    # lazy: rbjax.plot imports matplotlib (0.1–0.2 s; pyplot ~1 s)
    from .. import plot

    ball = JIS_RUBBER_BALL
    files = []
    i1 = standard_index(heights)

    def save(fig, name):
        path = out / name
        fig.savefig(path, dpi=120)
        files.append(name)

    def figure(ncols=1, width=6.4, height=4.4):
        fig = Figure(figsize=(width * ncols, height), layout="constrained")
        axes = fig.subplots(1, ncols)
        return fig, np.atleast_1d(axes)

    # Fig. 3: F_T, F_B, F_G at 1 m (forces evaluated on the trajectory's deflection).
    fig, (ax,) = figure()
    on = runs["adiabatic"]
    d = on["deflection_m"][i1]
    inside = on["in_contact"][i1]
    fb = np.where(inside, np.asarray(shell_force_N(d, ball)), 0.0)
    fg = np.where(inside, np.asarray(gas_force_N(d, ball)), 0.0)
    t = on["time_s"]
    plot.plot_force_components(
        t,
        {
            "F_T = F_B + F_G": fb + fg,
            "F_B (shell, Eqs. 1–3)": fb,
            "F_G (gas, Eq. 4 corrected)": fg,
            "F_T, gas off": runs["none"]["force_N"][i1],
        },
        ax,
        contact_time_s=max(on["contact_time_s"][i1], runs["none"]["contact_time_s"][i1]),
        title="Fig. 3: force components at 1 m drop height",
        styles={"F_T, gas off": {"color": "0.5", "ls": "--"}},
    )
    save(fig, "fig03_force_components_1m.png")

    # Fig. 4: histories for all heights.
    fig, axes = figure(2)
    for ax, (gas, run) in zip(axes, runs.items()):
        plot.plot_force_histories(
            t,
            run["force_N"],
            heights,
            ax,
            contact_time_s=run["contact_time_s"],
            title=f"Fig. 4: blocked force, {GAS[gas]}",
        )
    save(fig, "fig04_force_histories.png")

    # Fig. 5 and 6: peak force and contact time against height.
    paper_f = PAPER["peak_force_N"]
    fig, (ax,) = figure()
    plot.plot_vs_height(
        heights,
        {f"rbjax, {GAS[g]}": runs[g]["peak_force_N"] for g in GAS},
        ax,
        ylabel="peak force (N)",
        references={"paper (≈, §4.1)": ([float(h) for h in paper_f], list(paper_f.values()))},
        title="Fig. 5: peak force against drop height",
    )
    save(fig, "fig05_peak_force.png")
    fig, (ax,) = figure()
    tol = _contact_time_tolerance()
    plot.plot_vs_height(
        heights,
        {f"rbjax, {GAS[g]}": runs[g]["contact_time_s"] for g in GAS},
        ax,
        ylabel="contact time (ms)",
        scale=1e3,
        references={
            "paper, predicted (§4.1)": (
                [float(h) for h in PAPER["predicted_contact_time_s"]],
                list(PAPER["predicted_contact_time_s"].values()),
            ),
            "paper, measured (§4.1)": (
                [float(h) for h in PAPER["measured_contact_time_s"]],
                list(PAPER["measured_contact_time_s"].values()),
            ),
        },
        band=("tolerance 20 ± 2 ms (at 1 m)", tol[0], tol[1]),
        title="Fig. 6: contact time against drop height",
    )
    save(fig, "fig06_contact_time.png")

    # Fig. 7: relative difference to the paper's reported values.
    fig, (ax,) = figure(width=7.0)
    entries = [
        {
            "label": r["series"],
            "height_m": r["height_m"],
            "relative_difference": {GAS[g]: v for g, v in r["relative_difference"].items()},
        }
        for r in comparison
        if r["height_m"] is not None and not r["key"].startswith("contact_resonance")
    ]
    plot.plot_relative_difference(
        entries, ax, title="Fig. 7: rbjax relative to the paper's values (grey: ±10 %)"
    )
    save(fig, "fig07_relative_difference.png")

    # Fig. 8: L_FE octave bands at 1 m inside the tolerance band.
    fig, (ax,) = figure()
    for g in GAS:
        plot.plot_lfe_bands(runs[g]["lfe_octave_dB"][i1], ax, label=f"rbjax, {GAS[g]}")
    ax.set_title("Fig. 8: L_FE at 1 m with the rubber-ball tolerances")
    save(fig, "fig08_lfe_1m.png")

    # Fig. 9: L_FE per band relative to 1 m for the paper's heights.
    fig, axes = figure(2)
    pick = [h for h in FIG9_HEIGHTS_M if np.any(np.isclose(heights, h))] or list(heights)
    for ax, (g, run) in zip(axes, runs.items()):
        rows = {
            f"{h * 100:.0f} cm": run["lfe_octave_dB"][np.flatnonzero(np.isclose(heights, h))[0]]
            - run["lfe_octave_dB"][i1]
            for h in pick
        }
        plot.plot_band_differences(
            OCTAVE_BANDS,
            rows,
            ax,
            ylabel="L_FE(h) − L_FE(1 m) (dB)",
            title=f"Fig. 9: L_FE normalised to 1 m, {GAS[g]}",
        )
    save(fig, "fig09_lfe_normalised.png")

    # Fig. 10: increase against height ratio, with the linear fits of Fig. 11.
    fig, axes = figure(2)
    for ax, (g, run) in zip(axes, runs.items()):
        plot.plot_lfe_increase(
            heights / STANDARD_HEIGHT_M,
            run["lfe_octave_dB"] - run["lfe_octave_dB"][i1],
            OCTAVE_BANDS,
            ax,
            slopes_dB=run["increase_per_doubling_dB"],
            title=f"Fig. 10: L_FE increase, {GAS[g]}",
        )
    save(fig, "fig10_lfe_increase.png")

    fig, (ax,) = figure()
    series = {f"rbjax, {GAS[g]}": runs[g]["increase_per_doubling_dB"] for g in GAS}
    if growth and "recordings" in growth:
        series["emulated recordings (bundled)"] = growth["recordings"].slope_dB
    plot.plot_increase_per_doubling(
        OCTAVE_BANDS,
        series,
        ax,
        paper=[PAPER["increase_per_doubling_dB"][b] for b in OCTAVE_BANDS],
        title="Fig. 11: L_FE increase per doubling of drop height",
    )
    ax.axhline(10 * math.log10(2), color="0.6", lw=0.8, ls=":")
    save(fig, "fig11_increase_per_doubling.png")

    # Fig. 12: narrow-band spectra at the lowest and highest height, contact resonance marked.
    fig, axes = figure(2)
    freq = np.arange(0.0, 400.0 + 0.125, 0.25)
    ends = list(solved_ends(runs["adiabatic"]))
    for ax, (g, run) in zip(axes, runs.items()):
        # The record is zero after the contact, so its DTFT is that of the contact samples.
        n = int(np.max(np.sum(run["in_contact"], axis=1))) + 1
        f, level = force_spectrum_dB(run["force_N"][ends, :n], PAPER_RATE_Hz, freq)
        labels = [f"{heights[i] * 100:.0f} cm" for i in ends]
        plot.plot_narrowband(
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
    save(fig, "fig12_contact_resonance.png")
    return files


def _contact_time_tolerance():
    """The rubber-ball tolerance on the contact time (at 1 m), lower and upper, s."""

    tol = RUBBER_BALL_TOLERANCES.contact_time
    return tol.lower, tol.upper

"""``reproduce``: the paper's predictions (Schoenwald, Zeitler & Nightingale 2011, §4), gas on
and off.

For the JIS ball (§4: R = 89 mm, h = 32 mm, M = 2.5 kg, E = 1.6 MPa, ν = 0.5) dropped from
10 to 160 cm, with the gas force (corrected Eq. 4) on and off, this computes the blocked
force (Eq. 7, 44.1 kHz × 1 s records as in §2.4), the contact time, peak force, restitution,
the octave-band L_FE (Eq. 11) and its increase per doubling of drop height, and the
contact resonance, the growth of L_FE per doubling of the bundled recordings beside the
model's (``rbjax.studies.growth``) and the ball's shell modes (``rbjax.terms.shell_modes``); it
draws figures like the paper's Figs. 3–12 and writes ``report.md`` (rbjax beside the values the
paper reports, with the reason for each difference) and ``results.json``.

All heights of one gas option are one batched ``simulate`` call (one compilation).

This module runs the job and writes ``results.json``; the computation is in
:mod:`~rbjax.report.predictions`, the figures in :mod:`~rbjax.report.figures`, the text of
``report.md`` in :mod:`~rbjax.report.markdown`, the paper's values and the comparison with them in
:mod:`~rbjax.report.paper` and the paper's measured ball in :mod:`~rbjax.report.measured_ball`.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from .. import __version__
from .._progress import progress as say
from ..solve.inputs import PAPER_RATE_Hz
from ..spectrum.bands import OCTAVE_BANDS, THIRD_OCTAVE_BANDS
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.serialize import jsonable
from .figures import draw_figures
from .markdown import report_markdown
from .measured_ball import measured_ball, report_section
from .measured_ball_heights import measured_ball_across_heights
from .measured_ball_heights import report_section as heights_section
from .paper import DEFAULT_HEIGHTS_M, GAS, PAPER, comparison_rows, explain_comparison
from .predictions import (
    conformance_at_standard_height,
    drop_heights,
    growth_results,
    shell_mode_fundamentals,
    simulate_heights,
)


def reproduce(out_dir, *, heights_m=DEFAULT_HEIGHTS_M, progress: bool = True) -> dict:
    """Reproduce the paper's predictions (§4, Figs. 3–12) with the gas force on and off.

    Args:
        out_dir: folder for the figures (``fig03_…png`` … ``fig12_…png``), ``report.md`` and
            ``results.json`` (created if missing).
        heights_m: drop heights in m (default 0.1–1.6 m in 0.1 m steps, §3); 1 m is always added.
        progress: one progress line per step on stderr.

    Returns:
        The content of ``results.json``: per-height results for ``gas`` ``adiabatic`` and
        ``none``, the comparison with the paper, the conformance at 1 m, and the file names.
    """

    start = time.perf_counter()
    heights = drop_heights(heights_m)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    runs = {}
    for k, gas in enumerate(GAS, start=1):
        say(
            f"reproduce: [{k}/4] simulating {len(heights)} drop heights, {GAS[gas]} (gas={gas!r})",
            enabled=progress,
        )
        runs[gas] = simulate_heights(heights, gas)
    comparison = comparison_rows(runs, heights)
    explanations = explain_comparison(runs, heights, comparison)
    conformance = conformance_at_standard_height(runs, heights)
    growth = growth_results(runs, heights)
    modes = shell_mode_fundamentals()

    measured = measured_ball(out, progress=progress)
    across = measured_ball_across_heights(out, progress=progress)
    growth["measured_ball"] = across
    say("reproduce: [3/4] drawing figures 3-12", enabled=progress)
    files = draw_figures(out, runs, heights, comparison, growth) + [measured["figure"]]
    say("reproduce: [4/4] writing report.md and results.json", enabled=progress)
    elapsed = time.perf_counter() - start

    def per_height(run):
        return {
            "status": run["status"],
            "contact_time_s": run["contact_time_s"],
            "grid_contact_time_s": run["grid_contact_time_s"],
            "peak_force_N": run["peak_force_N"],
            "restitution": run["restitution"],
            "max_deflection_m": run["max_deflection_m"],
            "lfe_total_dB": run["lfe_total_dB"],
            "lfe_octave_dB": {b: run["lfe_octave_dB"][:, j] for j, b in enumerate(OCTAVE_BANDS)},
            "lfe_third_octave_dB": {
                b: run["lfe_third_octave_dB"][:, j] for j, b in enumerate(THIRD_OCTAVE_BANDS)
            },
            "increase_per_doubling_dB": dict(zip(OCTAVE_BANDS, run["increase_per_doubling_dB"])),
            "contact_resonance_Hz": run["contact_resonance_Hz"],
        }

    results = jsonable(
        {
            "rbjax_version": __version__,
            "paper": (
                "Schoenwald, Zeitler & Nightingale (2011), Acta Acustica united with Acustica "
                "97, 590-598"
            ),
            "ball": {
                f: getattr(JIS_RUBBER_BALL, f)
                for f in ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")
            },
            "rate_Hz": PAPER_RATE_Hz,
            "heights_m": heights,
            "gas": {g: per_height(run) for g, run in runs.items()},
            "paper_values": PAPER,
            "comparison": comparison,
            "explanations": explanations,
            "conformance_1m": conformance,
            "growth_per_doubling": {
                k: v for k, v in growth.items() if k not in ("recordings_error", "measured_ball")
            },
            "measured_ball_across_heights": across,
            "shell_modes_fundamental_Hz": modes,
            "measured_ball": measured,
            "figures": files,
            "report": "report.md",
            "elapsed_s": elapsed,
        }
    )
    (out / "report.md").write_text(
        report_markdown(
            runs, heights, comparison, explanations, conformance, files, elapsed, growth, modes
        )
        + "\n".join(report_section(measured))
        + "\n".join(heights_section(across))
        + "\n"
    )
    (out / "results.json").write_text(json.dumps(results, indent=2, allow_nan=False))
    say(
        f"reproduce: done in {elapsed:.1f} s: {len(files)} figures, report.md and results.json in "
        f"{out}",
        enabled=progress,
    )
    return results

"""Fit and selection: how long a fit and the model selection take, and how well the fitted
models predict heights they never saw.

    .venv/bin/python benchmarks/fitting.py [--quick] [--only SECTION] [--list]

Sections (each writes ``results/<section>.json``; the figures are in RESULTS.md, "Fit and
selection"):

* ``fit_time``: ``rbjax fit`` cold and warm beside the scipy user's fit (``parts/scipy_fit.py``),
  and the full selection's table;
* ``default_fit``: the default selection's model against the held-out accuracy bars, the
  sampled path against the ODE;
* ``ball_mode``: the ball-mode candidates held out, peak force, cost per impact, ``rbjax select``;
* ``ball_mode_growth``: the fitted ball-mode model's L_FE growth and the tolerance check at 1 m;
* ``summary_fit``: recovery of a known model from summary figures, warm time of a 5-height fit;
* ``loader_faults``: the fit on faulty recordings and other sample rates against the clean fit;
* ``selection_lanes``: the selection as lanes of batched programs against one fit after another;
* ``design_check``: ``design``'s margins against ``simulate`` and a 32-start run;
* ``selection_race``: ``rbjax fit DIR`` (the selection races) cold and warm beside
  ``--exhaustive``; the race against the exhaustive selection on the tests' data sets.
"""

from __future__ import annotations

from _suite import Section, run_suite

SECTIONS = [
    Section("fit_time", "rbjax fit cold/warm vs a scipy fit"),
    Section("default_fit", "the default model against the held-out bars"),
    Section("ball_mode", "the ball mode held out; select with it"),
    Section("ball_mode_growth", "ball-mode L_FE growth and conformance at 1 m"),
    Section("summary_fit", "summary fits: recovery and warm time"),
    Section("loader_faults", "fits on faulty recordings vs clean"),
    Section("selection_lanes", "the selection as lanes vs sequential"),
    Section("design_check", "design's margins checked"),
    Section("selection_race", "the raced selection: time, and the exhaustive one's answer"),
]


def main(argv=None) -> dict:
    return run_suite("fitting", __doc__, SECTIONS, argv)


if __name__ == "__main__":
    main()

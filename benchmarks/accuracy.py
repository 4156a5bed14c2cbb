"""Accuracy: how close rbjax's outputs are to independent references, where each solver fails,
and what XLA's optimisation level changes.

    .venv/bin/python benchmarks/accuracy.py [--quick] [--only SECTION] [--list]

Sections (each writes ``results/<section>.json``; the figures are in RESULTS.md, "Accuracy
against the independent scipy reference" and "Work–precision and stability"):

* ``reference_agreement``: the default settings against the scipy reference, every model;
* ``work_precision``: error against cost per diffrax method and tolerance, and the quadrature;
* ``stability_map``: where each method fails over the parameter space;
* ``opt_levels``: the difference XLA's optimisation level makes, per path;
* ``arrest_peaks``: arrest laws over their parameters: every impact solved, its peak the largest
  floor force.
"""

from __future__ import annotations

from _suite import Section, run_suite

SECTIONS = [
    Section("reference_agreement", "defaults against the scipy reference"),
    Section("work_precision", "error against cost per method"),
    Section("stability_map", "where each method fails"),
    Section("opt_levels", "XLA optimisation level: output differences"),
    Section("arrest_peaks", "arrest laws: every impact solved, the peak the largest force"),
]


def main(argv=None) -> dict:
    return run_suite("accuracy", __doc__, SECTIONS, argv)


if __name__ == "__main__":
    main()

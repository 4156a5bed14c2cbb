"""Parallel: where work runs and what spreading it buys, on the CPU cores (for the accelerator,
``device_check.py``).

    .venv/bin/python benchmarks/parallel.py [--quick] [--only SECTION] [--list]

Sections (each writes ``results/<section>.json``; the figures are in RESULTS.md, "Parallel"):

* ``multicore``: a batch split over two host devices (sharded jit, and ``simulate``'s chunks);
* ``selection_workers``: ``rbjax select`` by worker count, cold and warm, results compared;
* ``sweep_parallel``: the bundled Sobol sweep in one process against two workers;
* ``sensitivity_study``: the Sobol study's time, its convergence and DGSM against SALib.
"""

from __future__ import annotations

from _suite import Section, run_suite

SECTIONS = [
    Section("multicore", "both CPU cores: sharded jit and chunks", isolated=True),
    Section("selection_workers", "select by worker count"),
    Section("sweep_parallel", "the Sobol sweep on 1 vs 2 workers"),
    Section("sensitivity_study", "Sobol study time, convergence, DGSM"),
]


def main(argv=None) -> dict:
    return run_suite("parallel", __doc__, SECTIONS, argv)


if __name__ == "__main__":
    main()

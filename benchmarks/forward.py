"""Forward speed: how fast ``rbjax.simulate`` and its solve cores run, at which batch sizes, and
what each path, term, floor and output costs.

    .venv/bin/python benchmarks/forward.py [--quick] [--only SECTION] [--list]

Sections (each writes ``results/<section>.json``; the figures are in RESULTS.md, "Forward
speed"):

* ``forward_speed``: the forward-speed targets at ``simulate``'s defaults against the scipy loop
  (impacts/s, compile, value + Jacobian, damped models, histories);
* ``throughput``: impacts/s against batch size per solve path and Solver, compile breakdown,
  histories and L_FE, Jacobians, the persistent cache;
* ``evaluate_speed``: ``rbjax.solve.evaluate`` against ``simulate`` on the same impacts;
* ``history_speed``: force histories, the ODE's dense interpolant against the sampled path;
* ``pulse_spectrum``: octave L_FE from the contact samples against the padded FFT;
* ``term_cost``: the cost per impact of each optional term;
* ``floors``: impacts/s and accuracy on moving floors;
* ``paired_forward``: ``simulate`` (damped and elastic, 10 000 heights) paired against an older
  revision (default ``fc0325d``; ``parts/paired_forward.py --against REV``), fresh processes
  taking turns.
"""

from __future__ import annotations

from _suite import Section, run_suite

SECTIONS = [
    Section("forward_speed", "simulate at its defaults: the forward-speed targets"),
    Section("throughput", "impacts/s against batch size, per path and solver"),
    Section("evaluate_speed", "evaluate >= 0.9x simulate on the same impacts", isolated=True),
    Section("history_speed", "force histories: ODE interpolant vs sampled path"),
    Section("pulse_spectrum", "L_FE from contact samples vs the padded FFT"),
    Section("term_cost", "cost per impact of each optional term"),
    Section("floors", "speed and accuracy on moving floors"),
    Section("paired_forward", "simulate paired against fc0325d, fresh processes in turn"),
]


def main(argv=None) -> dict:
    return run_suite("forward", __doc__, SECTIONS, argv)


if __name__ == "__main__":
    main()

"""``rbjax reproduce``: the paper's predictions, figures like its Figs. 3–12, report.md and
results.json."""

from __future__ import annotations

from . import add_command, emit_json, fmt, format_table

DESCRIPTION = """\
Reproduce the predictions of Schoenwald, Zeitler & Nightingale (2011), §4, for the JIS
rubber ball dropped from 10 to 160 cm, with the gas force (corrected Eq. 4) on and off:
figures like the paper's Figs. 3-12 (PNG), report.md (rbjax's numbers beside the paper's,
with the reason for each difference) and results.json, all in --out DIR.

examples:
  rbjax reproduce
  rbjax reproduce --out results/paper --json
"""


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "reproduce",
        help="reproduce the paper's predictions (figures, report.md, results.json)",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--out", default="rbjax-out", metavar="DIR", help="output folder (default: rbjax-out)"
    )
    p.set_defaults(func=run)


def summary_table(results: dict) -> str:
    """The comparison with the paper as a plain-text table."""
    header = ["quantity", "paper", "rbjax gas on", "rbjax gas off", "unit"]
    rows = []
    for r in results["comparison"]:
        rows.append(
            [
                r["quantity"],
                fmt(r["paper"], ".4g"),
                fmt(r["rbjax"]["adiabatic"], ".4g"),
                fmt(r["rbjax"]["none"], ".4g"),
                r["unit"],
            ]
        )
    return format_table(header, rows)


def run(args) -> int:
    from pathlib import Path

    from ..report.reproduce import reproduce

    results = reproduce(args.out, progress=True)
    out = Path(args.out)
    if args.json:
        emit_json(
            {
                "out_dir": str(out),
                "files": [str(out / f) for f in (*results["figures"], "report.md", "results.json")],
                **results,
            }
        )
    else:
        print(summary_table(results))
        print(
            f"\n{len(results['figures'])} figures, report.md and results.json written to {out}/ "
            f"({results['elapsed_s']:.1f} s)"
        )
    return 0

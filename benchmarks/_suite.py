"""The runner the suites share: ``--quick``, ``--only SECTION``, one table and one JSON per suite.

A suite is a script (``forward.py``, ``fit.py``, ``accuracy.py``, ``parallel.py``) naming its
sections; each section is a module of ``parts/`` whose ``main(quick)`` prints its own table and
writes ``results/<section>.json`` (``<section>_quick.json`` with ``--quick``). A section marked
isolated runs in a process of its own (it sets XLA flags before JAX starts); the others run in
the suite's process. The suite then prints which sections ran, their wall time and outcome, and
writes ``results/<suite>.json`` (``RBJAX_BENCH_RESULTS`` points the results elsewhere).
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))


@dataclass(frozen=True)
class Section:
    name: str  # the module in parts/
    question: str
    isolated: bool = False  # run in a process of its own (XLA flags set before JAX starts)


def _run_isolated(section: Section, quick: bool) -> None:
    code = (
        f"import sys; sys.path[:0] = [{str(HERE)!r}]; "
        f"from parts import {section.name} as m; m.main(quick={quick!r})"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def run_suite(suite: str, doc: str, sections: list[Section], argv=None) -> dict:
    p = argparse.ArgumentParser(
        description=doc.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--quick", action="store_true", help="a smoke run: tiny sizes (seconds)")
    p.add_argument(
        "--only",
        action="append",
        choices=[s.name for s in sections],
        help="run only this section (repeatable)",
    )
    p.add_argument("--list", action="store_true", help="list the sections and their questions")
    args = p.parse_args(argv)
    if args.list:
        for s in sections:
            print(f"{s.name:22s} {s.question}")
        return {}
    from _common import finish_machine_info, machine_info, table, write_json

    info = machine_info()
    chosen = [s for s in sections if not args.only or s.name in args.only]
    rows = []
    for s in chosen:
        print(f"\n== {suite} / {s.name}: {s.question}", flush=True)
        t0 = time.perf_counter()
        try:
            if s.isolated:
                _run_isolated(s, args.quick)
            else:
                importlib.import_module(f"parts.{s.name}").main(quick=args.quick)
            outcome = "ok"
        except Exception as exc:  # noqa: BLE001  (reported in the table, the suite fails after)
            traceback.print_exc()
            outcome = f"failed: {type(exc).__name__}: {exc}"
        rows.append({"section": s.name, "wall_s": time.perf_counter() - t0, "outcome": outcome})
    print(f"\n{suite}" + (" (quick)" if args.quick else ""))
    print(
        table(
            ["section", "question", "wall (s)", "outcome"],
            [
                [
                    r["section"],
                    next(s.question for s in chosen if s.name == r["section"]),
                    f"{r['wall_s']:.1f}",
                    r["outcome"][:60],
                ]
                for r in rows
            ],
        )
    )
    out = {"machine": finish_machine_info(info), "quick": args.quick, "sections": rows}
    print(f"wrote {write_json(suite + ('_quick' if args.quick else ''), out)}")
    failed = [r["section"] for r in rows if r["outcome"] != "ok"]
    if failed:
        raise SystemExit(f"{suite}: sections failed: {', '.join(failed)}")
    return out

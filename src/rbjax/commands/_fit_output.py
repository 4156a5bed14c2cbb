"""What ``rbjax fit`` writes and prints once a fit is done, for recordings and summary figures
alike (a helper of ``commands/fit.py``)."""

from __future__ import annotations

from pathlib import Path

from . import emit_json, progress, write_json_file

#: Exit status of a fit that stopped without converging (its result is still written).
NOT_CONVERGED_EXIT = 3


def finish(args, result, selection, *, extra: dict | None = None, after: str | None = None) -> int:
    """Write ``fit.json`` and the plots (``--out``), print the JSON (``--json``) or the tables
    and ``after``, and return the exit status. ``extra``: more keys for the JSON."""
    out = result.to_dict()
    out.update(extra or {})
    if selection is not None:
        out["selection"] = selection.to_dict()
    if args.out is not None:
        written = write_json_file(args.out, "fit.json", out)
        for path in result.plot(Path(args.out)):
            progress(f"wrote {path}")
        progress(f"wrote {written}")
    if args.json:
        emit_json(out)
    else:
        if selection is not None:
            print(selection.table())
            print()
        print(result.summary())
        if after:
            print(after)
    if not result.converged:
        progress(f"the fit did not converge: {result.message}")
        return NOT_CONVERGED_EXIT
    return 0

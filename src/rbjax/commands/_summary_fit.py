"""``rbjax fit --summary TABLE``: the fit to summary figures (a helper of ``commands/fit.py``)."""

from __future__ import annotations

from . import UsageError, progress
from ._fit_output import finish


def run_summary(args, fix: dict) -> int:
    """Run ``rbjax fit --summary`` (``fix``: the parsed ``--fix``)."""
    from ..fit.summary import fit_summary
    from ..fit.summary_table import read_summary

    if args.summary is None:
        raise UsageError("fit: give recordings (FILES_OR_DIR) or --summary TABLE")
    if args.paths:
        raise UsageError(
            f"fit: --summary {args.summary} fits a table of figures; leave out the recordings "
            f"{' '.join(args.paths)}"
        )
    table = read_summary(args.summary)
    for note in table.notes:
        progress(f"note: {note}")
    selection = None
    if args.model is None:
        from ..studies.selection.summary import select_summary

        progress("no --model: comparing models by leave-one-figure-out prediction")
        selection = select_summary(
            table,
            fix=fix,
            gas=args.gas,
            blocked_force=args.blocked_force or "paper",
            progress=not args.quiet,
        )
        if selection.recommended is None:
            raise ValueError(
                f"{table.source}: too few figures to compare models by held-out figures; give "
                f"--model ({selection.table()})"
            )
        result = selection.candidates[selection.recommended].fit
        progress(f"recommended: {selection.recommended}")
    else:
        result = fit_summary(
            table,
            args.model,
            blocked_force=args.blocked_force or "paper",
            gas=args.gas,
            fix=fix,
            progress=not args.quiet,
        )
    return finish(args, result, selection)

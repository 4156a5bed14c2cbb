"""Plain-text tables for reports and the command line."""

from __future__ import annotations

import math


def format_table(header: list[str], rows: list[list[str]]) -> str:
    """A plain-text table with right-aligned columns."""
    widths = [max(len(str(c)) for c in col) for col in zip(header, *rows)]
    line = lambda cells: "  ".join(str(c).rjust(w) for c, w in zip(cells, widths))  # noqa: E731
    return "\n".join([line(header), line(["-" * w for w in widths]), *(line(r) for r in rows)])


def fmt(value, spec: str = ".1f", *, missing: str = "—") -> str:
    """Format a number, or ``missing`` for None/NaN."""
    if value is None:
        return missing
    value = float(value)
    return missing if not math.isfinite(value) else format(value, spec)

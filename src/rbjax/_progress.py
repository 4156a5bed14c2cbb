"""Progress lines of long work: on stderr, so that ``--json`` output on stdout stays clean."""

from __future__ import annotations

import sys


def progress(message: str, *, enabled: bool = True) -> None:
    """Print ``rbjax: message`` on stderr (when ``enabled``)."""
    if enabled:
        print(f"rbjax: {message}", file=sys.stderr, flush=True)

"""Where a record comes from: its source string and the drop height read from a file name
(``h100`` → 1.00 m)."""

from __future__ import annotations

import os
import re
from pathlib import Path

_HEIGHT_RE = re.compile(r"(?<![A-Za-z0-9])h(\d{3})(?!\d)", re.IGNORECASE)


def height_from_name(name: str | os.PathLike) -> float | None:
    """Drop height in metres from a file name containing ``hNNN`` (centimetres), else None.

    ``h100_d1.csv`` -> 1.0, ``raw_h020_x.wav`` -> 0.2. The three digits must not be
    part of a longer number and the ``h`` must not follow a letter or digit.

    Args:
        name: a file name or path; only its stem (the name without directory and suffix)
            is searched.

    Returns:
        The drop height in metres, or ``None`` when the name holds no ``hNNN``.
    """
    m = _HEIGHT_RE.search(Path(name).stem)
    if m is None:
        return None
    return int(m.group(1)) / 100.0


def as_source(path) -> str:
    return Path(path).name if isinstance(path, (str, os.PathLike)) else str(path)

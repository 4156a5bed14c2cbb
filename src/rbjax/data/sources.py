"""Where a record comes from: its source string, the drop height read from a file name
(``h100`` → 1.00 m), and the check that a file to read is there."""

from __future__ import annotations

import os
import re
from pathlib import Path

from .errors import DataError

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


def existing_file(path, what: str = "") -> Path:
    """``path`` as a ``Path``, checked to be a file: a :class:`DataError` naming it if not.

    The readers and :func:`rbjax.data.load` say this, not a bare ``FileNotFoundError`` (or
    ``IsADirectoryError``) from deep inside a reader. ``what`` prefixes the message (e.g.
    ``"manifest "``).
    """
    p = Path(path)
    if not p.is_file():
        problem = "a directory, not a file" if p.is_dir() else "no such file or directory"
        raise DataError(f"{what}{p}: {problem}")
    return p

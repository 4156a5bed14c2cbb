"""The two ways :mod:`rbjax.data` reports a problem with a recording."""

from __future__ import annotations

__all__ = ["DataError", "DataWarning"]


class DataError(ValueError):
    """A recording cannot be used as it is; the message names the file and the problem."""


class DataWarning(UserWarning):
    """A recording is usable but something about it deserves attention."""

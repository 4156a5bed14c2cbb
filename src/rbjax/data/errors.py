"""The ways :mod:`rbjax.data` reports a problem with a recording.

:class:`DataError` (a ``ValueError``) is every refusal; the faults of a real record that
a caller may want to tell apart have a subclass each: :class:`ClippedRecordError`,
:class:`NoImpactError`, :class:`RecordCutOffError`, and :class:`MissingFormatError` for a
file whose reader is an optional extra that is not installed.
"""

from __future__ import annotations

__all__ = [
    "DataError",
    "DataWarning",
    "ClippedRecordError",
    "NoImpactError",
    "RecordCutOffError",
    "MissingFormatError",
]


class DataError(ValueError):
    """A recording cannot be used as it is; the message names the file and the problem."""


class ClippedRecordError(DataError):
    """Samples sit at the acquisition's full scale (or a flat top): the peak force is unknown.

    ``rbjax.data.load(..., strict=False)`` (the fit's default) excludes such a file and
    keeps its reason; with ``strict=True`` it is refused with this error."""


class NoImpactError(DataError):
    """No sample of the record rises above the impact threshold."""


class RecordCutOffError(DataError):
    """The record starts or ends inside the impact (or inside the window kept around it)."""


class MissingFormatError(DataError):
    """The file's format is read by an optional dependency that is not installed; the
    message names the extra to install (``pip install 'rbjax[formats]'``)."""


class DataWarning(UserWarning):
    """A recording is usable but something about it deserves attention."""

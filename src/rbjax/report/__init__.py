"""Reports: the reproduction of the paper (:func:`~rbjax.report.reproduce.reproduce`: figures,
``report.md`` and ``results.json``), with the values the paper reports and rbjax's comparison
with them in :mod:`~rbjax.report.paper`."""

from .reproduce import reproduce

__all__ = ["reproduce"]

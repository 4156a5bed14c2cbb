"""Reports: the reproduction of the paper (:func:`~rbjax.report.reproduce.reproduce`: figures,
``report.md`` and ``results.json``), with the values the paper reports and rbjax's comparison
with them in :mod:`~rbjax.report.paper`, and the paper's measured ball across drop heights
(``MEASURED_BALL`` with ``MEASURED_BALL_MODEL``: what ``rbjax reproduce`` writes as
``measured_ball.json``)."""

from .measured_ball_heights import MEASURED_BALL, MEASURED_BALL_MODEL
from .paper import DEFAULT_HEIGHTS_M, GAS, PAPER, STANDARD_HEIGHT_M, printed_eq4_limit_m
from .reproduce import reproduce

__all__ = [
    "DEFAULT_HEIGHTS_M",
    "GAS",
    "MEASURED_BALL",
    "MEASURED_BALL_MODEL",
    "PAPER",
    "STANDARD_HEIGHT_M",
    "printed_eq4_limit_m",
    "reproduce",
]

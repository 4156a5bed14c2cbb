"""Settings objects of the solve layer, and the one way to give a model.

:class:`EvaluationSpec`: how a batch of impacts is evaluated (the solve path and its ``Solver``,
the force record of the L_FE, progress bars), the settings that
:func:`rbjax.solve.batch.evaluate`, :func:`~rbjax.solve.batch.evaluate_jacobian` and the studies
pass along as one object instead of relaying each keyword (as diffrax passes a ``SaveAt``).
Where the batch runs (devices, chunks, worker processes) is an :class:`rbjax.Parallel`.

:class:`ModelShortcuts`: the keyword shortcuts of :func:`rbjax.simulate` that build a
:class:`~rbjax.terms.model.Model`; :func:`model_from_shortcuts` builds it, and refuses a mix of
``model=`` and shortcuts by name (a function may not silently drop either).
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Mapping, Sequence
from typing import Any, TypedDict

from .._validate import check_choice, check_range, settings_or_default
from ..terms.ball_mode import BallMode
from ..terms.damping import AbstractDamping
from ..terms.floors.kinds import AbstractFloor
from ..terms.forces import CubicStiffening
from ..terms.model import Model
from ..terms.series_kelvin_voigt import SeriesKelvinVoigt
from .inputs import PAPER_DURATION_S, PAPER_RATE_Hz
from .solver import Solver

#: The solve paths (``"auto"``: the fastest exact path the model allows; see
#: ``rbjax.solve.path.resolve_path``).
PATHS = ("auto", "ode", "quadrature", "angle")


@dataclasses.dataclass(frozen=True)
class EvaluationSpec:
    """How a batch of impacts is evaluated (``rbjax.solve.batch.evaluate``, the studies).

    Attributes:
        path: the solve path of the scalar outputs, ``"auto"`` (default: the fastest exact path
            the model allows), ``"ode"``, ``"quadrature"`` or ``"angle"`` (as ``path`` of
            ``rbjax.simulate``).
        solver: an ``rbjax.Solver``: asks for the diffrax ODE with it (default: none given).
        rate_Hz, duration_s: the force record of the L_FE (default the paper's 44.1 kHz × 1 s).
        progress: progress bars on stderr.

    Raises:
        ValueError: an unknown ``path``; a ``solver`` that is not an ``rbjax.Solver``;
            ``rate_Hz`` or ``duration_s`` not finite and > 0; a ``progress`` that is not a
            bool. The message names the field.
    """

    path: str = "auto"
    solver: Solver | None = None
    rate_Hz: float = PAPER_RATE_Hz
    duration_s: float = PAPER_DURATION_S
    progress: bool = False

    def __post_init__(self):
        check_choice("path", self.path, PATHS)
        if self.solver is not None and not isinstance(self.solver, Solver):
            raise ValueError(f"solver={self.solver!r} must be an rbjax.Solver or None")
        check_range("rate_Hz", self.rate_Hz, lower=0.0)
        check_range("duration_s", self.duration_s, lower=0.0)
        if not isinstance(self.progress, bool):
            raise ValueError(f"progress={self.progress!r} must be True or False")

    def replace(self, **changes) -> EvaluationSpec:
        """A copy with ``changes`` (validated again)."""
        return dataclasses.replace(self, **changes)


def spec_or_default(evaluation: EvaluationSpec | None) -> EvaluationSpec:
    """``evaluation``, or ``EvaluationSpec()`` when it is ``None`` (anything else: a
    ``ValueError``)."""
    return settings_or_default("evaluation", EvaluationSpec, evaluation)


class ModelShortcuts(TypedDict, total=False):
    """The keyword shortcuts of ``rbjax.simulate``: the fields of an ``rbjax.Model``."""

    gas: str
    blocked_force: str
    damping: AbstractDamping | Sequence[AbstractDamping] | None
    stiffening: CubicStiffening | None
    max_deflection_ratio: float
    ball_mode: BallMode | None
    floor: AbstractFloor | None
    series: SeriesKelvinVoigt | None


#: The names of the shortcuts (the fields of ``Model``).
SHORTCUTS = tuple(ModelShortcuts.__annotations__)
#: Every keyword ``Model`` takes: accepted as a shortcut too (a field added to ``Model`` is a
#: shortcut at once; ``ModelShortcuts`` types the usual ones).
MODEL_KEYWORDS = tuple(p for p in inspect.signature(Model.__init__).parameters if p != "self")
#: The shortcuts whose ``None`` is their default (no such term): ``None`` counts as not given.
OPTIONAL_TERMS = ("damping", "stiffening", "ball_mode", "floor", "series")


def model_from_shortcuts(function: str, model: Model | None, shortcuts: Mapping[str, Any]) -> Model:
    """The ``Model`` of a call of ``function``: ``model``, or one built from the keyword
    ``shortcuts`` (``Model(**shortcuts)``; ``Model()`` with neither). A mix of ``model=`` and
    shortcuts is a ``ValueError`` naming both (a term's ``None`` is no shortcut: it is the
    default); an unknown keyword a ``TypeError``."""
    unknown = sorted(set(shortcuts) - set(MODEL_KEYWORDS))
    if unknown:
        raise TypeError(f"{function}() got unexpected keyword arguments {unknown}")
    shortcuts = {k: v for k, v in shortcuts.items() if not (v is None and k in OPTIONAL_TERMS)}
    if model is not None and not isinstance(model, Model):
        raise ValueError(
            f"model={model!r} must be an rbjax.Model (or None, to build one from the keywords)"
        )
    if model is not None and shortcuts:
        given = ", ".join(sorted(shortcuts))
        raise ValueError(
            f"{function} got model= and the keyword options {sorted(shortcuts)}: give the "
            f"options in the Model (Model(..., {given}=...)) or leave model out"
        )
    if model is not None:
        return model
    return Model(**shortcuts)

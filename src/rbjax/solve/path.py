"""Which path solves a model: the choice ``simulate(path=...)`` makes among the solve paths.

:func:`resolve_path` picks the fastest exact path the model allows (``path="auto"``), or
checks that the path asked for can solve it; :func:`quadrature_unsupported` (here) and
:func:`~rbjax.solve.angle.angle_unsupported` say why a fast path cannot. Running the path chosen,
with the ODE as the fallback of the impacts it flags, is :mod:`rbjax.solve.path_runner`'s.
"""

from __future__ import annotations

from .._validate import check_choice
from ..terms.model import Model
from .angle import angle_unsupported, local_terms_unsupported
from .options import PATHS
from .solver import Solver


def quadrature_unsupported(model: Model) -> str | None:
    """Why the quadrature path (``rbjax.solve.quadrature``) cannot solve ``model``; None if it can.

    It solves Eq. 7 for a contact force F(δ) of the deflection alone: the shell (with or
    without ``CubicStiffening``), the gas force or none, either blocked-force convention, any
    ``max_deflection_ratio``. A damping law makes the force depend on δ̇ or on internal states.
    """
    local = local_terms_unsupported(model)
    if local is not None:
        return local
    if model.damping:
        names = ", ".join(d.name for d in model.damping)
        return (
            f"the damping ({names}) makes the contact force depend on the velocity or on internal "
            "states, not on δ alone"
        )
    return model.coupling


def resolve_path(path: str, model: Model, solver: Solver | None = None) -> str:
    """The path ``simulate(path=...)`` runs for ``model``: ``"quadrature"``, ``"angle"`` or
    ``"ode"``.

    ``auto`` is the fastest exact path the model allows when no ``solver`` is given (a ``Solver``
    describes an ODE integration: passing one asks for it): the quadrature where
    ``quadrature_unsupported(model)`` is None, else the phase-angle integration where
    ``angle_unsupported(model)`` is None, else the ODE. Asking for a path that cannot solve the
    model raises ``ValueError`` saying why.
    """
    check_choice("path", path, PATHS)
    reasons = {"quadrature": quadrature_unsupported(model), "angle": angle_unsupported(model)}
    if path in reasons:
        if reasons[path] is not None:
            raise ValueError(
                f"path={path!r} cannot solve this model: {reasons[path]}; valid: "
                "path='ode' or path='auto'"
            )
        return path
    if path == "ode" or solver is not None:
        return "ode"
    return next((p for p, reason in reasons.items() if reason is None), "ode")

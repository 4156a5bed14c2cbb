"""Which path solves a model: the choice ``simulate(method=...)`` makes among the solve paths.

:func:`resolve_method` picks the fastest exact path the model allows (``method="auto"``), or
checks that the path asked for can solve it; :func:`quadrature_unsupported` (here) and
:func:`~rbjax.solve.angle.angle_unsupported` say why a fast path cannot. Running the path chosen,
with the ODE as the fallback of the impacts it flags, is :mod:`rbjax.solve.engine`'s.
"""

from __future__ import annotations

from .._validate import check_choice
from ..terms.model import Model, Solver
from .angle import angle_unsupported
from .options import PATHS


def quadrature_unsupported(model: Model) -> str | None:
    """Why the quadrature path (``rbjax.solve.quadrature``) cannot solve ``model``; None if it can.

    It solves Eq. 7 for a contact force F(δ) of the deflection alone: the shell (with or
    without ``CubicStiffening``), the gas force or none, either blocked-force convention, any
    ``max_deflection_ratio``. A damping law makes the force depend on δ̇ or on internal states.
    """
    if model.damping:
        names = ", ".join(d.name for d in model.damping)
        return (
            f"the damping ({names}) makes the contact force depend on the velocity or on internal "
            "states, not on δ alone"
        )
    return model.coupling


def resolve_method(method: str, model: Model, solver: Solver | None = None) -> str:
    """The path ``simulate(method=...)`` runs for ``model``: ``"quadrature"``, ``"angle"`` or
    ``"ode"``.

    ``auto`` is the fastest exact path the model allows when no ``solver`` is given (a ``Solver``
    describes an ODE integration: passing one asks for it): the quadrature where
    ``quadrature_unsupported(model)`` is None, else the phase-angle integration where
    ``angle_unsupported(model)`` is None, else the ODE. Asking for a path that cannot solve the
    model raises ``ValueError`` saying why.
    """
    check_choice("method", method, PATHS)
    reasons = {"quadrature": quadrature_unsupported(model), "angle": angle_unsupported(model)}
    if method in reasons:
        if reasons[method] is not None:
            raise ValueError(
                f"method={method!r} cannot solve this model: {reasons[method]}; valid: "
                "method='ode' or method='auto'"
            )
        return method
    if method == "ode" or solver is not None:
        return "ode"
    return next((path for path, reason in reasons.items() if reason is None), "ode")

"""The candidates a model selection fits, and how: the (model, blocked force) pairs that
candidate names stand for (:func:`candidate_pairs`), the shared structure each is fitted in
(:func:`shared_structures`: one compiled fit program for many candidates) and their relative
cost per evaluation (:func:`structure_cost`). A fitted, cross-validated candidate is a
:class:`~rbjax.studies.selection.results.Candidate`.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..._validate import check_choice
from ...fit import model_from_name, parse_model_name, parse_model_terms
from ...fit.layout import ARREST_SUFFIX, LAYER_SUFFIX
from ...terms.model import BLOCKED_FORCE_OPTIONS, Model, structure_model

__all__ = [
    "candidate_pairs",
    "shared_structure",
    "shared_structures",
    "structure_cost",
]


def candidate_pairs(
    candidates: Sequence[str], blocked_forces: Sequence[str]
) -> list[tuple[str, str]]:
    """(model, blocked force) pairs: ``"name"`` pairs with every blocked force,
    ``"name/paper"`` or ``"name/momentum"`` with that one only."""

    if not candidates or not blocked_forces:
        raise ValueError("give at least one candidate model and one blocked-force definition")
    for bf in blocked_forces:
        check_choice("blocked_force", bf, BLOCKED_FORCE_OPTIONS)
    pairs = []
    for c in candidates:
        name, sep, bf = str(c).partition("/")
        parse_model_name(name)
        if sep:
            check_choice("blocked_force", bf, BLOCKED_FORCE_OPTIONS)
            pairs.append((name, bf))
        elif parse_model_terms(name).arrest:  # the arrest law is its own blocked force
            pairs.append((name, "paper"))
        else:
            pairs += [(name, b) for b in blocked_forces]
    return list(dict.fromkeys(pairs))


def shared_structure(names: Sequence[str], gas: str = "adiabatic") -> Model:
    """One model holding the terms of every candidate named (their damping laws, and the
    stiffening, the ball mode and the series element if any candidate has them): the structure
    of the one compiled fit program that all candidates and folds run through, each with the
    terms it lacks held off (the ball mode at μ = 0, the series element at C = 0)."""
    laws, stiff, mode, series, local = [], False, False, False, set()
    for name in names:
        terms = parse_model_terms(name)
        laws += [t for t in terms.laws if t not in laws]
        stiff = stiff or terms.stiffening
        mode = mode or terms.ball_mode
        series = series or terms.series
        local.add((terms.layer, terms.arrest))
    if len(local) > 1:
        raise ValueError(
            f"models {list(names)} differ in the contact layer or the arrest law, which have no "
            "off value: they cannot share one structure"
        )
    (layer, arrest), *_ = local or {(False, False)}
    base = model_from_name(
        "paper" + LAYER_SUFFIX * layer + ARREST_SUFFIX * arrest, gas=gas, blocked_force="paper"
    )
    return structure_model(base, laws, stiffening=stiff, ball_mode=mode, series=series)


def shared_structures(
    names: Sequence[str], gas: str = "adiabatic", given: Model | None = None
) -> dict[str, Model]:
    """The structure each candidate named is fitted in (``given``, if one is given, for all):
    one :func:`shared_structure` for the candidates without the series element and one for
    those with it. The element's closed-form coupling makes every solve of a program that
    holds it, even held off, ~2.7× as costly (the force's rate dF_c/dt is differentiated
    again for the Jacobian), so the other candidates do not carry it."""
    if given is not None:
        return {name: given for name in names}
    groups: dict[tuple[bool, bool, bool], list[str]] = {}
    for name in names:
        terms = parse_model_terms(name)
        groups.setdefault((terms.series, terms.layer, terms.arrest), []).append(name)
    out = {}
    for group in groups.values():
        structure = shared_structure(group, gas)
        out.update({name: structure for name in group})
    return out


def structure_cost(name: str) -> float:
    """A candidate's relative cost per evaluation (the order in which work starts, nothing
    else): the ball mode and the series element make every solve several times dearer."""
    terms = parse_model_terms(name)
    local = 1.0 * terms.layer + 0.5 * terms.arrest
    return 1.0 + 3.0 * terms.ball_mode + 2.0 * terms.series + 0.5 * len(terms.laws) + local

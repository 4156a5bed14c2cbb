"""The paired one-standard-error rule of a model selection (:data:`RULE`, :func:`recommend`;
stated in :mod:`rbjax.studies.selection.select`) and what the same paired comparison of held-out
errors says about the blocked-force definition (:func:`blocked_force_note`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .results import Candidate

__all__ = ["RULE", "recommend", "blocked_force_note"]

RULE = (
    "paired one-standard-error rule on the leave-one-height-out history error: among the "
    "candidates whose mean fold-by-fold excess error over the best candidate is at most the "
    "standard error of that excess, take the one with the fewest fitted physical parameters "
    "(ties: smaller held-out error)"
)


def _paired(a: Candidate, b: Candidate) -> tuple[float, float]:
    d = a.fold_errors_pct - b.fold_errors_pct
    se = float(np.std(d, ddof=1) / math.sqrt(d.size)) if d.size > 1 else float("inf")
    return float(np.mean(d)), se


def recommend(candidates: Sequence[Candidate]) -> tuple[Candidate, tuple]:
    """(recommended, candidates within the noise of the best) by the rule in :data:`RULE`.

    Args:
        candidates: the cross-validated :class:`Candidate` objects; those with a non-finite
            held-out error, and those dropped from a race (their folds are partial), are left
            out.

    Returns:
        ``(recommended, within)``: the recommended :class:`Candidate` and the tuple of the
        candidates within the noise of the best (the best among them).

    Raises:
        ValueError: no candidates, or none with a finite held-out error.
    """
    candidates = [c for c in candidates if getattr(c, "dropped", None) is None]
    if not candidates:
        raise ValueError("no candidates to choose from")
    failed = [c for c in candidates if not math.isfinite(c.cv_error_pct)]
    candidates = [c for c in candidates if math.isfinite(c.cv_error_pct)]
    if not candidates:
        raise ValueError(
            "every candidate failed cross-validation (non-finite held-out error): "
            f"{', '.join(c.label for c in failed)}"
        )
    best = min(candidates, key=lambda c: c.cv_error_pct)
    within = tuple(c for c in candidates if c is best or _paired(c, best)[0] <= _paired(c, best)[1])
    chosen = min(within, key=lambda c: (c.n_physical, c.cv_error_pct))
    return chosen, within


def blocked_force_note(candidates, chosen: Candidate) -> str:
    """What the held-out errors of ``chosen``'s model with each blocked-force definition say
    about the definition (the paired difference against twice its standard error), in words."""
    pair = [c for c in candidates if c.model_name == chosen.model_name]
    if len(pair) < 2:
        return f"blocked force: only {chosen.blocked_force!r} was tried for {chosen.model_name}."
    a, b = (
        (c for c in pair if c.blocked_force == "momentum"),
        (c for c in pair if c.blocked_force == "paper"),
    )
    mom, pap = next(a, None), next(b, None)
    if mom is None or pap is None:
        return "blocked force: not compared."
    other = pap if chosen is mom else mom
    if other.dropped is not None:
        return (
            f"blocked force ({chosen.model_name}): held-out error {chosen.cv_error_pct:.2f} % "
            f"with {chosen.blocked_force!r}; {other.blocked_force!r} was dropped from the race "
            f"after round {other.dropped.round} ({other.dropped.reason})."
        )
    mean, se = _paired(pap, mom)
    verdict = (
        "the data support 'momentum' (the floor also takes the momentum flux (M/2R)δ̇² in "
        "compression)"
        if mean > 2 * se
        else "the data support 'paper' (F_B + F_G + F_d)"
        if mean < -2 * se
        else "the data do not distinguish the two definitions"
    )
    return (
        f"blocked force ({chosen.model_name}): held-out error {mom.cv_error_pct:.2f} % with "
        f"'momentum', {pap.cv_error_pct:.2f} % with 'paper' (paper − momentum = {mean:+.2f} ± "
        f"{se:.2f} %): {verdict}."
    )

"""The model-selection rule of rbjax.studies.selection.rule.recommend, on hand-made candidates.

The rule (the paired one-standard-error rule of the rbjax.studies.selection.select module
docstring): let B be the candidate with the smallest mean held-out error; a candidate is
within the noise of B
when the mean of its fold-by-fold excess d = (its fold errors) − (B's fold errors) is at most
the standard error of that excess, SE = std(d, ddof=1)/√folds; the recommendation is the
candidate within the noise of B with the fewest fitted physical parameters (ties: the smaller
mean held-out error). Candidates whose mean held-out error is NaN (failed cross-validation) take
no part.

``recommend`` reads only ``cv_error_pct``, ``fold_errors_pct``, ``n_physical`` and ``label``,
so the candidates here are a small stand-in class, not fitted models: every expected answer
below is worked out by hand in the comments. Most excesses are built as a + (−1, −1, +2):
mean a, deviations (−1, −1, +2), std (ddof 1) = √((1 + 1 + 4)/2) = √3, SE = √3/√3 = 1, so such a
candidate is within the noise exactly when a ≤ 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rbjax.studies.selection.rule import recommend

BEST_FOLDS = (5.0, 6.0, 7.0)  # mean 6 %
UNIT_SE = np.array([-1.0, -1.0, 2.0])  # excess pattern with SE = 1 (module docstring)


class Stand:
    """A candidate as recommend() sees it: a label, a parameter count and fold errors (%)."""

    def __init__(self, label, n_physical, folds):
        self.label = label
        self.n_physical = n_physical
        self.fold_errors_pct = np.asarray(folds, dtype=float)
        self.cv_error_pct = float(
            np.mean(self.fold_errors_pct)
        )  # as rbjax.studies.selection.results.Candidate

    def __repr__(self):
        return f"Stand({self.label!r}, p={self.n_physical}, cv={self.cv_error_pct:.3g} %)"


def excess(a, pattern=UNIT_SE):
    """Fold errors of a candidate whose excess over BEST_FOLDS is a + pattern."""
    return np.array(BEST_FOLDS) + a + pattern


def choose(candidates):
    """Label of the recommendation, checked to be the same for the reversed input order."""
    chosen, within = recommend(list(candidates))
    again, within_again = recommend(list(reversed(candidates)))
    assert again.label == chosen.label
    assert {c.label for c in within_again} == {c.label for c in within}
    return chosen.label, {c.label for c in within}


def test_clear_winner():
    # best: kv (p = 2), mean 6 %.
    # paper (p = 1): folds (11, 13, 12), excess d = (6, 7, 5): mean 6, std 1, SE 1/√3 = 0.58;
    #   6 > 0.58: outside.
    # zener (p = 3): folds (9, 10, 11), excess (4, 4, 4): mean 4, SE 0: outside.
    # Only kv is within the noise of itself: kv.
    candidates = [
        Stand("paper", 1, [11.0, 13.0, 12.0]),
        Stand("kv", 2, BEST_FOLDS),
        Stand("zener", 3, [9.0, 10.0, 11.0]),
    ]
    assert choose(candidates) == ("kv", {"kv"})


def test_simpler_model_within_one_paired_standard_error_wins():
    # best: zener (p = 3), folds (5, 6, 7), mean 6 %.
    # kv (p = 2): excess 0.5 + (−1, −1, 2) = (−0.5, −0.5, 2.5): mean 0.5 ≤ SE 1: within,
    #   although its mean (6.5 %) is larger; fewer parameters: kv.
    candidates = [Stand("zener", 3, BEST_FOLDS), Stand("kv", 2, excess(0.5))]
    assert choose(candidates) == ("kv", {"zener", "kv"})


def test_an_excess_equal_to_its_standard_error_is_within():
    # kv: excess 1 + (−1, −1, 2) = (0, 0, 3): mean 1 = SE 1 ("no larger than"): within: kv.
    candidates = [Stand("zener", 3, BEST_FOLDS), Stand("kv", 2, excess(1.0))]
    assert choose(candidates) == ("kv", {"zener", "kv"})


def test_simpler_model_outside_one_paired_standard_error_loses():
    # kv: excess 1.5 + (−1, −1, 2): mean 1.5 > SE 1: outside; the best, zener, is chosen.
    candidates = [Stand("zener", 3, BEST_FOLDS), Stand("kv", 2, excess(1.5))]
    assert choose(candidates) == ("zener", {"zener"})


def test_the_standard_error_is_that_of_the_paired_differences():
    # kv: folds (5.4, 6.5, 7.6), excess (0.4, 0.5, 0.6): mean 0.5, std 0.1, SE 0.1/√3 = 0.058;
    # 0.5 > 0.058: outside, although 0.5 is less than the unpaired SE of either candidate's
    # own fold errors (std(5, 6, 7)/√3 = 0.58). The consistent excess counts: zener.
    kv_folds = np.array(BEST_FOLDS) + [0.4, 0.5, 0.6]
    assert 0.5 < np.std(BEST_FOLDS, ddof=1) / math.sqrt(3)
    candidates = [Stand("zener", 3, BEST_FOLDS), Stand("kv", 2, kv_folds)]
    assert choose(candidates) == ("zener", {"zener"})


def test_fewest_parameters_among_all_within_the_noise():
    # best: zener (p = 3). kv (p = 2): excess mean 0.5: within. paper (p = 1): excess mean 0.9:
    # within. hc (p = 1) excess mean 3: outside. Fewest parameters within: paper (p = 1).
    candidates = [
        Stand("zener", 3, BEST_FOLDS),
        Stand("kv", 2, excess(0.5)),
        Stand("paper", 1, excess(0.9)),
        Stand("hc", 1, excess(3.0)),
    ]
    assert choose(candidates) == ("paper", {"zener", "kv", "paper"})


def test_equal_parameter_counts_go_to_the_smaller_error():
    # best: zener (p = 3), mean 6 %. kv (p = 2): excess mean 0.5 (mean 6.5 %); hc (p = 2):
    # excess mean 0.2 (mean 6.2 %); both within (≤ SE 1), both p = 2: the smaller error, hc.
    # kv comes first in the list, so the first of the tied counts would be the wrong answer.
    candidates = [
        Stand("kv", 2, excess(0.5)),
        Stand("hc", 2, excess(0.2)),
        Stand("zener", 3, BEST_FOLDS),
    ]
    assert choose(candidates) == ("hc", {"zener", "kv", "hc"})


def test_the_best_wins_a_tie_in_parameter_count_with_a_candidate_within_its_noise():
    # zener (p = 2) is best (6 %); hc (p = 2), excess mean 0.5 (6.5 %), is within: equal counts,
    # so the smaller error: zener.
    candidates = [Stand("hc", 2, excess(0.5)), Stand("zener", 2, BEST_FOLDS)]
    assert choose(candidates) == ("zener", {"zener", "hc"})


def test_candidates_whose_cross_validation_failed_are_ignored():
    # broken (p = 1) has a NaN fold, so its mean held-out error is NaN: it takes no part, though
    # it has the fewest parameters and comes first (with it, min() of the errors would keep it).
    # Of the rest: zener best (6 %), kv (p = 2) excess mean 0.5 within: kv.
    broken = Stand("broken", 1, [4.0, math.nan, 4.0])
    assert math.isnan(broken.cv_error_pct)
    candidates = [broken, Stand("zener", 3, BEST_FOLDS), Stand("kv", 2, excess(0.5))]
    assert choose(candidates) == ("kv", {"zener", "kv"})
    # and a NaN candidate never changes the outcome of the others
    assert choose(candidates[1:]) == ("kv", {"zener", "kv"})


def test_every_candidate_failed_raises():
    candidates = [Stand("a", 1, [math.nan, 1.0, 2.0]), Stand("b", 2, [math.nan] * 3)]
    with pytest.raises(ValueError):
        recommend(candidates)


def test_no_candidates_raises():
    with pytest.raises(ValueError):
        recommend([])


def test_cross_validation_refuses_a_height_the_data_do_not_hold():
    """Named before any fit runs: the valid heights are the data's."""
    from rbjax.data import examples_dir
    from rbjax.studies import cross_validate

    files = [examples_dir() / f"h{h:03d}_d1.csv" for h in (10, 40)]
    with pytest.raises(ValueError, match=r"heights=\[0\.7\] m .* valid: \[0\.1, 0\.4\]"):
        cross_validate(files, "kelvin-voigt", heights=[0.1, 0.7])

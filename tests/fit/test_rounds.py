"""When a start of a multi-start fit is given up (rbjax.fit.rounds.abandoned).

The costs are those of the three starts of hunt-crossley+ball-mode/paper fitted to the bundled
emulated recordings, recorded round by round with no start given up (2026-11-29): start 0
converged at round 4 at the cost below; starts 1 and 2 crawled on to the round limit.
"""

from __future__ import annotations

import math

import numpy as np

from rbjax.fit.rounds import ABANDON_FACTOR, MAX_ROUNDS, Lane, abandoned

BEST = 20064272.6  # start 0, converged at round 4
# rounds 3..8 of the starts that crawled (each round a few optimiser steps)
CRAWL = {
    1: [20107585.6, 20107164.7, 20105769.2, 20104507.9, 20103497.6, 20102808.7],
    2: [20782580.2, 20751445.6, 20742356.0, 20730012.9, 20721477.3, 20715651.7],
}


def lane(cost: float, previous: float = math.inf) -> Lane:
    """A lane whose residuals cost ``cost`` (½ r·r) after a round from ``previous``."""
    return Lane(
        theta=np.zeros(1), out={"r": np.array([math.sqrt(2 * cost)])}, previous_cost=previous
    )


def test_a_crawling_start_is_given_up_once_a_start_has_converged():
    # at every round of the crawl after start 0 converged (neither start ever got below it in
    # the run without the rule), up to the last, where the round limit ends it instead
    for costs in CRAWL.values():
        for i in range(1, len(costs)):
            rounds = 3 + i
            why = abandoned(lane(costs[i], costs[i - 1]), BEST, rounds)
            if rounds < MAX_ROUNDS:
                assert "last round's descent" in why and f"{MAX_ROUNDS - rounds} rounds left" in why
            else:
                assert why == ""


def test_a_start_descending_fast_enough_goes_on():
    # 40 000 a round for four rounds would take start 1 below the converged start
    assert abandoned(lane(20107164.7, 20147164.7), BEST, 4) == ""
    # no converged start yet, the first round, the last round: the rule does not apply
    assert abandoned(lane(20107164.7, 20107585.6), math.inf, 4) == ""
    assert abandoned(lane(20107164.7), BEST, 1) == ""
    assert abandoned(lane(20107164.7, 20107585.6), BEST, MAX_ROUNDS) == ""


def test_a_start_far_above_a_converged_one_is_given_up_after_two_rounds():
    high = ABANDON_FACTOR * BEST * 1.01
    assert abandoned(lane(high), BEST, 1) == ""
    assert f"> {ABANDON_FACTOR:g}×" in abandoned(lane(high), BEST, 2)

"""The race of a model selection (rbjax.studies.selection.race): its decisions on given fold
errors, checked against the rule run on every fold (the exhaustive selection), and its bad
input. The race run end to end against ``exhaustive=True`` and across worker counts is in
``test_parallel_selection.py``.

The claim (the race module's docstring): where no fold's held-out error is below its full fit's
in-sample error at that height (the bound the race uses), the race recommends what the rule
recommends on every fold of every candidate, with the same candidates within the noise of the
best, and the recommended candidate ran every fold. Here the fold errors and the bounds are
given numbers, so the race's decisions are checked against
``rbjax.studies.selection.rule.recommend`` on the full table, without a fit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rbjax import Parallel
from rbjax.studies.selection.race import Race, RaceState
from rbjax.studies.selection.rule import recommend

# A smoke test (tests/conftest.py: compiled with most optimisations off): the race's fits are
# compared with the same fits run exhaustively and in worker processes, at the same level.
pytestmark = pytest.mark.xla_smoke


class Stand:
    """A candidate as recommend() sees it (as in test_selection_rule.py), with ``dropped``."""

    def __init__(self, label, n_physical, folds, dropped=None):
        self.label = label
        self.n_physical = n_physical
        self.fold_errors_pct = np.asarray(folds, dtype=float)
        e = self.fold_errors_pct
        self.cv_error_pct = float(np.mean(e)) if e.size else math.nan
        self.dropped = dropped


def run(errors, floors, params, margin=Race().margin):
    """The race on a table of fold errors (candidates × heights): the RaceState and the folds
    it asked for, round by round."""
    errors = np.asarray(errors, dtype=float)
    labels = [f"c{k}" for k in range(len(errors))]
    heights = [0.1 * (j + 1) for j in range(errors.shape[1])]
    state = RaceState(labels, heights, floors, floors, margin)
    rounds, asked, round_no = [], {}, 0
    while True:
        for k, js in asked.items():
            for j in js:
                state.record(k, j, errors[k, j])
        state.decide(round_no)
        asked = state.requests() if state.live() else {}
        if not asked:
            return state, rounds
        rounds.append(asked)
        round_no += 1


def outcomes(errors, floors, params, margin=Race().margin):
    """(the rule on every fold, the rule on the race's complete candidates, the race's state)."""
    errors = np.asarray(errors, dtype=float)
    state, _ = run(errors, floors, params, margin)
    full = [Stand(f"c{k}", p, errors[k]) for k, p in enumerate(params)]
    raced = [
        Stand(f"c{k}", p, [state.obs[k][j] for j in sorted(state.obs[k])], state.dropped[k])
        for k, p in enumerate(params)
    ]

    def rule(candidates):
        try:
            chosen, within = recommend(candidates)
        except ValueError:
            return None
        return chosen.label, sorted(c.label for c in within)

    return rule(full), rule(raced), state


#: The leave-one-height-out history errors (%) of the twelve default candidates on the bundled
#: recordings (heights 0.1, 0.2, 0.4, 0.8, 1.0, 1.6 m), each fold, from the exhaustive run, and
#: each full fit's in-sample error at the same heights (benchmarks/parts/selection_race.py
#: prints both). docs/guides/fitting.md, "The race": 12 of 72 folds, 10 candidates dropped
#: after round 2 with no fold run.
BUNDLED = {
    "paper/paper": (1, (9.161, 9.659, 10.382, 11.053, 11.401, 11.873)),
    "paper/momentum": (1, (7.166, 7.710, 8.407, 8.905, 9.071, 9.267)),
    "kelvin-voigt/paper": (2, (7.106, 7.847, 8.869, 9.622, 9.971, 10.634)),
    "kelvin-voigt/momentum": (2, (3.157, 2.877, 2.455, 2.326, 2.443, 3.303)),
    "hunt-crossley/paper": (2, (5.212, 5.320, 5.680, 6.163, 6.481, 7.101)),
    "hunt-crossley/momentum": (2, (3.793, 3.351, 2.864, 1.928, 1.651, 1.958)),
    "zener/paper": (3, (4.011, 4.705, 5.754, 6.957, 7.575, 8.810)),
    "zener/momentum": (3, (3.310, 2.894, 2.166, 1.492, 1.551, 2.800)),
    "hunt-crossley+ball-mode/paper": (5, (5.754, 4.458, 2.733, 1.535, 2.204, 4.702)),
    "hunt-crossley+ball-mode/momentum": (5, (1.744, 1.212, 0.858, 0.782, 0.820, 0.788)),
    "hunt-crossley+series-kelvin-voigt/paper": (4, (5.824, 4.782, 3.228, 1.475, 2.202, 4.690)),
    "hunt-crossley+series-kelvin-voigt/momentum": (4, (1.805, 1.252, 0.867, 0.796, 0.881, 0.841)),
}
BUNDLED_IN_SAMPLE = {
    "paper/paper": (3.740, 3.433, 3.346, 3.836, 4.233, 5.559),
    "paper/momentum": (4.009, 4.217, 4.885, 5.834, 6.209, 7.252),
    "kelvin-voigt/paper": (2.806, 2.726, 2.910, 3.732, 4.209, 5.603),
    "kelvin-voigt/momentum": (2.684, 2.559, 2.284, 2.293, 2.438, 3.076),
    "hunt-crossley/paper": (2.207, 1.832, 1.876, 2.722, 3.216, 4.571),
    "hunt-crossley/momentum": (2.476, 2.090, 1.855, 1.447, 1.353, 1.617),
    "zener/paper": (2.263, 2.268, 2.488, 3.443, 3.972, 5.452),
    "zener/momentum": (2.915, 2.642, 1.992, 1.436, 1.501, 2.302),
    "hunt-crossley+ball-mode/paper": (3.000, 2.792, 2.139, 1.437, 1.506, 2.346),
    "hunt-crossley+ball-mode/momentum": (1.503, 1.117, 0.817, 0.620, 0.606, 0.624),
    "hunt-crossley+series-kelvin-voigt/paper": (2.935, 2.696, 2.002, 1.309, 1.392, 2.224),
    "hunt-crossley+series-kelvin-voigt/momentum": (1.544, 1.141, 0.823, 0.614, 0.601, 0.623),
}


def test_the_bundled_recordings_race_runs_the_best_its_runner_up_and_five_cheap_folds():
    labels = list(BUNDLED)
    errors = np.array([BUNDLED[k][1] for k in labels])
    floors = np.array([BUNDLED_IN_SAMPLE[k] for k in labels])
    params = [BUNDLED[k][0] for k in labels]
    # docs/guides/fitting.md, "The race (the default)": the bound holds on every fold of the
    # exhaustive run (smallest ratio 1.002); the race runs 17 of the 72 folds and drops the
    # other ten candidates after round 2, six of them without one of their folds
    assert 1.0015 < (errors / floors).min() < 1.0025
    assert labels[9] == "hunt-crossley+ball-mode/momentum"
    full, raced, state = outcomes(errors, floors, params)
    assert raced == full == ("c9", ["c9"])
    _, rounds = run(errors, floors, params)
    # round 1: the most promising (least in-sample error) runs its folds; round 2: its
    # runner-up, whose bound settles nothing, and the folds at which another candidate's bound
    # is within 1.6× the best's error (kelvin-voigt/momentum, hunt-crossley/paper and /momentum,
    # zener/paper at 0.1 m, hunt-crossley/paper at 0.2 m too)
    assert rounds == [
        {9: [0, 1, 2, 3, 4, 5]},
        {3: [0], 4: [0, 1], 5: [0], 6: [0], 11: [0, 1, 2, 3, 4, 5]},
    ]
    assert sum(len(o) for o in state.obs) == 17
    dropped = [k for k, d in enumerate(state.dropped) if d is not None]
    assert dropped == [k for k in range(12) if k not in (9, 11)]
    ran = {labels[k]: state.dropped[k].heights_run for k in dropped if state.dropped[k].heights_run}
    assert ran == {
        "kelvin-voigt/momentum": (0.1,),
        "hunt-crossley/paper": (0.1, 0.2),
        "hunt-crossley/momentum": (0.1,),
        "zener/paper": (0.1,),
    }
    assert all(state.dropped[k].round == 2 for k in dropped) and state.bound_failed is None
    # the smallest ratio of a dropped candidate's bound to the best's held-out error: 1.265
    # (hunt-crossley/paper at 0.1 m); with a margin of 0.25 no dropped candidate runs a fold
    ratio = floors[dropped] / errors[9]
    assert np.unravel_index(np.argmin(ratio), ratio.shape) == (dropped.index(4), 0)
    assert 1.26 < ratio.min() < 1.27
    state, rounds = run(errors, floors, params, margin=0.25)
    assert rounds == [{9: [0, 1, 2, 3, 4, 5]}, {11: [0, 1, 2, 3, 4, 5]}]
    assert all(state.dropped[k].heights_run == () for k in dropped)


def test_a_fold_below_its_bound_by_more_than_the_margin_takes_the_bound_away():
    # a and b complete first and neither dominates the other; c is dropped on its bound (5 %,
    # far above both) although its folds would make it the best (0.5 %: the bound is wrong);
    # d's fold at the first height then comes out at 1 %, below its bound 3 % / 1.6: the race
    # stops using the bound, takes c back and runs its folds, and recommends what every fold does
    errors = np.array([[1.0, 2.0], [2.0, 1.0], [0.5, 0.5], [1.0, 4.0]])
    floors = np.array([[0.5, 0.5], [0.8, 0.6], [5.0, 5.0], [3.0, 3.5]])
    state, rounds = run(errors, floors, [1, 1, 1, 1])
    assert rounds[:3] == [{0: [0, 1]}, {1: [0, 1]}, {3: [0]}]
    assert state.bound_failed is not None and "c3's fold without 0.1 m" in state.bound_failed
    assert state.dropped[2] is None and len(state.obs[2]) == 2
    full, raced, _ = outcomes(errors, floors, [1, 1, 1, 1])
    assert raced == full and full[0] == "c2"


def test_a_fold_that_fails_drops_its_candidate_with_that_reason():
    errors = [[1.0, 1.0, 1.0], [2.0, math.nan, 2.0], [3.0, 3.0, 3.0]]
    floors = [[0.0] * 3] * 3
    full, raced, state = outcomes(errors, floors, [2, 1, 3])
    assert raced == full
    assert state.dropped[1] is not None and "failed (non-finite held-out error)" in (
        state.dropped[1].reason
    )
    assert "0.2 m" in state.dropped[1].reason


def test_a_candidate_a_contender_does_not_beat_somewhere_runs_every_fold():
    # c1 beats c0 at the second height: it can never be dominated by c0, so it is not dropped
    errors = [[1.0, 1.0, 1.0], [2.0, 0.5, 2.0]]
    floors = [[0.9, 0.9, 0.9], [1.0, 0.1, 1.9]]
    state, rounds = run(errors, floors, [1, 1])
    assert state.dropped == [None, None]
    assert all(len(o) == 3 for o in state.obs)


def test_a_complete_candidate_of_larger_mean_error_no_longer_shields_the_others():
    # c1 beats the best (c0) at the first height, so c0 never dominates it, but once complete
    # its mean (2.17 %) exceeds c0's (1 %): it is not the best, and c2, which c0 dominates on its
    # bound (1.7 % > 1.6 × 1 %), is dropped without a fold although c1 never dominates it
    errors = [[1.0, 1.0, 1.0], [0.5, 3.0, 3.0], [2.0, 2.0, 2.0]]
    floors = [[0.9, 0.9, 0.9], [0.4, 2.5, 2.5], [1.7, 1.7, 1.7]]
    state, rounds = run(errors, floors, [2, 1, 1])
    assert rounds == [{0: [0, 1, 2]}, {1: [0]}, {1: [1, 2]}]
    assert state.dropped[2] is not None and state.dropped[2].heights_run == ()
    assert "worse than c0 at every height" in state.dropped[2].reason
    full, raced, _ = outcomes(errors, floors, [2, 1, 1])
    assert raced == full == ("c0", ["c0"])


# fold errors on a grid of 0.25 % (ties happen), bounds a fraction of each (the assumption)
ERRORS = st.integers(1, 40).map(lambda x: 0.25 * x)


@st.composite
def tables(draw):
    n_c, n_h = draw(st.integers(2, 6)), draw(st.integers(2, 5))
    errors = np.array([[draw(ERRORS) for _ in range(n_h)] for _ in range(n_c)])
    fractions = np.array(
        [
            [draw(st.sampled_from([0.0, 0.3, 0.6, 0.8, 0.95, 1.0])) for _ in range(n_h)]
            for _ in range(n_c)
        ]
    )
    if draw(st.booleans()):  # a failed fold
        errors[draw(st.integers(0, n_c - 1)), draw(st.integers(0, n_h - 1))] = math.nan
    floors = np.where(np.isfinite(errors), errors * fractions, 0.0)
    params = [draw(st.integers(1, 4)) for _ in range(n_c)]
    margin = draw(st.sampled_from([0.0, 0.1, 0.25, 1.0]))
    return errors, floors, params, margin


@settings(max_examples=300, deadline=None)
@given(tables())
def test_the_race_recommends_what_the_rule_does_on_every_fold(table):
    errors, floors, params, margin = table
    full, raced, state = outcomes(errors, floors, params, margin)
    assert raced == full
    if full is not None:  # the recommended candidate ran every fold
        k = int(full[0][1:])
        assert state.dropped[k] is None and len(state.obs[k]) == errors.shape[1]


@pytest.mark.parametrize("margin", [-0.1, math.nan, math.inf, "a"])
def test_a_race_margin_outside_its_range_is_named(margin):
    with pytest.raises(ValueError, match=r"Race\.margin="):
        Race(margin=margin)


def test_exhaustive_with_race_settings_is_named_before_any_fit():
    from rbjax.studies import select_model

    with pytest.raises(ValueError, match=r"exhaustive=True.*give one or the other"):
        select_model(object(), exhaustive=True, race=Race(margin=0.5))
    with pytest.raises(ValueError, match=r"exhaustive='yes' must be True or False"):
        select_model(object(), exhaustive="yes")
    with pytest.raises(ValueError, match=r"race=0\.3 must be an rbjax Race"):
        select_model(object(), race=0.3)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["select", "DIR", "--exhaustive", "--race-margin", "0.3"], "give one or the other"),
        (["fit", "DIR", "--exhaustive", "--race-margin", "0.3"], "give one or the other"),
        (["select", "DIR", "--race-margin", "-1"], "--race-margin -1.0: Race.margin=-1.0"),
    ],
)
def test_cli_race_options_bad_input_is_one_line_exit_2(argv, message):
    from rbjax.data import examples_dir

    from cli_runner import run_cli

    code, out, err = run_cli([str(examples_dir()) if a == "DIR" else a for a in argv])
    assert code == 2, err
    assert err.startswith("rbjax: error:") and err.count("\n") == 1, err
    assert message in err


# ----------------------------------------------------------------------------------------------
# The race run end to end: the smallest data set on which it drops candidates (three of the
# bundled heights, one drop each; the elastic and Kelvin–Voigt models with both blocked forces:
# it runs 5 of the 12 folds and drops three candidates), against every fold and across worker
# counts.

SMALL = ["paper", "kelvin-voigt"]


@pytest.fixture(scope="module")
def small_data():
    from rbjax.data import examples_dir
    from rbjax.fit import load_data, prepare_data

    return prepare_data(load_data([examples_dir() / f"h{h:03d}_d1.csv" for h in (10, 40, 100)]))


@pytest.fixture(scope="module")
def raced(small_data):
    from rbjax.studies import select_model

    return select_model(small_data, SMALL, parallel=Parallel(workers=1), progress=False)


@pytest.fixture(scope="module")
def every_fold(small_data):
    from rbjax.studies import select_model

    one = Parallel(workers=1)
    return select_model(small_data, SMALL, parallel=one, progress=False, exhaustive=True)


def test_the_race_recommends_what_every_fold_does_with_the_same_errors(raced, every_fold):
    assert every_fold.race is None and raced.race is not None
    dropped = [c for c in raced.candidates if c.dropped is not None]
    assert dropped and raced.race.folds_run < raced.race.folds_total
    assert raced.recommended.label == every_fold.recommended.label
    assert [c.label for c in raced.within_noise] == [c.label for c in every_fold.within_noise]
    # the recommended model's held-out errors: every fold, bit for bit
    assert raced.recommended.dropped is None
    np.testing.assert_array_equal(
        raced.recommended.fold_errors_pct, every_fold.recommended.fold_errors_pct
    )
    # every fold the race ran is the exhaustive run's fold; a dropped candidate lists its own
    by_label = {c.label: c for c in every_fold.candidates}
    for c in raced.candidates:
        theirs = {f.height_m: f.history_error_pct for f in by_label[c.label].folds}
        assert all(f.history_error_pct == theirs[f.height_m] for f in c.folds), c.label
        if c.dropped is not None:
            assert c.dropped.heights_run == tuple(f.height_m for f in c.folds)
            assert "worse than" in c.dropped.reason
    table = raced.table()
    assert "dropped after round" in table and f"{raced.race.folds_run} of 12 folds" in table
    assert raced.to_dict()["race"]["folds_run"] == raced.race.folds_run


@pytest.fixture(scope="module")
def raced_in_workers(small_data):
    from rbjax.studies import select_model

    return select_model(small_data, SMALL, parallel=Parallel(workers=2), progress=False)


def test_the_race_in_worker_processes_is_the_in_process_race_bit_for_bit(raced, raced_in_workers):
    import json

    def text(selection):
        return json.dumps(selection.to_dict() | {"elapsed_s": None}, sort_keys=True)

    assert text(raced_in_workers) == text(raced)

"""The race of a model selection (the default of
:func:`~rbjax.studies.selection.select.select_model`; ``exhaustive=True`` runs every fold).

The candidates' full fits run first (round 0); their folds then run in rounds, and after each
round a candidate that can no longer be the best nor the recommended one is dropped and its
remaining folds are never started. The criterion (:data:`RACE_CRITERION`):

* **A lower bound on a fold not run.** A fold starts from its candidate's full fit and only
  descends the cost of the other heights, while the full fit minimises the cost of all of
  them; so the held-out record's cost after the fold is at least its cost in the full fit, and
  the held-out error of a fold (its onset aligned, not fitted) is at least the full fit's
  in-sample error at that height (exact with one record per height; with several, bounded
  through their noise weights). The bound needs a converged full fit, ``decimate=1``, no extra
  residual rows and no ν prior; where these do not hold the bound is 0 (the fold must run).
* **Dominated.** Candidate *c* is dominated by *y* (whose folds are all run) when at every
  height *c*'s held-out error exceeds *y*'s: the fold's own error where it ran, else its
  bound, which must exceed ``(1 + margin)`` × *y*'s error. Then every paired excess of *c* over
  *y* is positive, so its mean exceeds its standard error (for positive excesses d = δ + y,
  y ≥ 0: SE(d) = SE(y) ≤ mean(y) < mean(d)): *c* is neither the best nor within the noise of
  *y*.
* **Dropped.** The contenders are the candidates that can still be the best: those no
  complete candidate dominates, and of the complete ones only those of least mean held-out
  error (a complete candidate with a larger mean than another one is not the best); the best
  candidate of the exhaustive run is always among them. A candidate dominated by every
  contender is therefore neither the best nor within the noise of the best, and leaving it
  out changes neither the recommendation nor the set within the noise: it is dropped. A
  candidate whose fold fails (a non-finite held-out error) is dropped too (the rule never
  counts it).
* **Which folds run.** While no contender is complete, the most promising one (least
  in-sample error) runs all its folds; then each candidate runs the folds at which a complete
  contender does not yet beat it, all of them where one already fails to.

The recommended candidate's folds are the same tasks on the same inputs as in the exhaustive
run, so its held-out errors are the same bits. What the race may get wrong: the bound assumes
the full fit is the deepest minimum the fold can reach. For a fit with one minimum that holds
up to the optimiser's tolerance; a fit with several (the ball mode's, fitted from several
starts) can have a fold that finds a deeper one and predicts its height better than the full
fit does (measured down to 0.65× on the simulated Zener drops of
``benchmarks/fitting.py --only selection_race``). ``margin`` (default 0.6: the bound must
clear the contender's error by 60 %) covers that; and every fold that runs checks the bound:
one below it by more than the margin and the race uses no bound from then on, its candidates
dropped on the bound taken back and their folds run.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..._validate import check_range
from ...fit.options import options_or_default

__all__ = [
    "RACE_CRITERION",
    "Race",
    "Dropped",
    "RaceRound",
    "RaceSummary",
    "RaceState",
    "in_sample_floor",
    "mean_or_inf",
]

RACE_CRITERION = (
    "a candidate is dropped when every contender (a candidate no complete candidate beats at "
    "every height and, once complete, of least mean held-out error) beats it at every height: "
    "its held-out error, or where its fold has not run "
    "its full fit's in-sample error (a lower bound), exceeds the contender's there, the bound "
    "by (1 + margin); it is then neither the best nor within the noise of the best"
)


@dataclasses.dataclass(frozen=True)
class Race:
    """How a selection races (see :mod:`rbjax.studies.selection.race`).

    Attributes:
        margin: how far, relatively, a candidate's in-sample error at a height whose fold has
            not run must exceed a contender's held-out error there to count as beaten
            (≥ 0; default 0.6: 60 % above; see the module docstring for why).

    Raises:
        ValueError: ``margin`` negative or not finite.
    """

    margin: float = 0.6

    def __post_init__(self):
        if isinstance(self.margin, bool) or not isinstance(self.margin, int | float):
            raise ValueError(f"Race.margin={self.margin!r} must be a number >= 0")
        check_range("Race.margin", self.margin, lower=0.0, lower_open=False)
        object.__setattr__(self, "margin", float(self.margin))


@dataclasses.dataclass(frozen=True)
class Dropped:
    """Why and when a candidate left the race: after round ``round``, for ``reason``, with the
    folds of ``heights_run`` (m) run."""

    round: int
    reason: str
    heights_run: tuple[float, ...]

    def to_dict(self) -> dict:
        return {"round": self.round, "reason": self.reason, "heights_run_m": list(self.heights_run)}


@dataclasses.dataclass(frozen=True)
class RaceRound:
    """One round: the folds it ran (label, height), the candidates dropped after it (label,
    reason) and those still in the race."""

    number: int
    ran: tuple[tuple[str, float], ...]
    dropped: tuple[tuple[str, str], ...]
    in_race: tuple[str, ...]

    def to_dict(self) -> dict:
        return {
            "round": self.number,
            "ran": [{"candidate": c, "height_m": h} for c, h in self.ran],
            "dropped": [{"candidate": c, "reason": r} for c, r in self.dropped],
            "in_race": list(self.in_race),
        }


@dataclasses.dataclass(frozen=True)
class RaceSummary:
    """The race of a selection: its ``margin``, the criterion in words, every round, how many
    folds ran of the exhaustive run's ``folds_total``, and where the bound failed (``None``:
    it held on every fold that ran)."""

    margin: float
    criterion: str
    rounds: tuple[RaceRound, ...]
    folds_run: int
    folds_total: int
    bound_failed: str | None = None

    def lines(self) -> list[str]:
        out = [
            f"race: {self.folds_run} of {self.folds_total} folds run in {len(self.rounds) - 1} "
            f"rounds after the full fits (margin {self.margin:g}; --exhaustive runs them all)."
        ]
        if self.bound_failed is not None:
            out.append(f"  the bound failed ({self.bound_failed}): no bound used after that.")
        for r in self.rounds:
            out += [f"  dropped after round {r.number}: {c}: {why}." for c, why in r.dropped]
        return out

    def to_dict(self) -> dict:
        return {
            "margin": self.margin,
            "criterion": self.criterion,
            "folds_run": self.folds_run,
            "folds_total": self.folds_total,
            "bound_failed": self.bound_failed,
            "rounds": [r.to_dict() for r in self.rounds],
        }


def in_sample_floor(fit, data, options=None) -> np.ndarray:
    """A lower bound of the held-out error (% of peak) of every fold warm-started from the full
    fit ``fit``, one per height of ``data`` (see the module docstring); 0 where none holds."""
    options = options_or_default(options)
    heights = data.heights_m
    out = np.zeros(len(heights))
    extra = any(float(w) > 0 for w in (options.extra_weights or {}).values())
    if not fit.converged or options.decimate != 1 or extra or options.poisson_prior is not None:
        return out
    for j, h in enumerate(heights):
        k = np.isclose(fit.heights_m, h, atol=5e-4)
        sq = np.sum((fit.predicted_N[k] - fit.measured_N[k]) ** 2, axis=1)
        if sq.size > 1:  # several records: their cost is noise-weighted, the error is not
            if options.scale != "noise":
                continue
            w2 = 1.0 / np.maximum(np.asarray(data.noise_rms_N)[k], 1e-12) ** 2
            sq = np.full_like(sq, float(np.sum(w2 * sq) / np.max(w2)) / sq.size)
        peak = float(np.mean(np.max(fit.measured_N[k], axis=1)))
        value = 100.0 * math.sqrt(float(np.sum(sq)) / fit.measured_N[k].size) / peak
        out[j] = value if math.isfinite(value) else 0.0
    return out


class RaceState:
    """The race's decisions, from the fold errors observed so far (nothing else: the same
    observations give the same decisions, whatever order the folds finished in).

    Args:
        labels: the candidates' labels.
        heights: the held-out heights, m.
        in_sample: each candidate's full-fit in-sample error per height (its promise).
        floors: each candidate's lower bound per height (:func:`in_sample_floor`).
        margin: :attr:`Race.margin`.
    """

    def __init__(self, labels, heights, in_sample, floors, margin: float):
        self.labels = list(labels)
        self.heights = [float(h) for h in heights]
        self.floors = [np.asarray(f, dtype=float) for f in floors]
        self.promise = [mean_or_inf(e) for e in in_sample]
        self.margin = float(margin)
        self.obs: list[dict[int, float]] = [{} for _ in self.labels]
        self.dropped: list[Dropped | None] = [None for _ in self.labels]
        #: where a fold came out below its bound by more than the margin (then no bound is used)
        self.bound_failed: str | None = None

    @property
    def n(self) -> int:
        return len(self.heights)

    def record(self, k: int, j: int, error: float) -> None:
        """Record the held-out error of candidate ``k``'s fold at height ``j``, and check the
        bound on it: a fold below its bound by more than the margin means the bound cannot be
        trusted on these data, and the race uses none from then on."""
        self.obs[k][j] = float(error)
        floor = float(self.floors[k][j])
        if self.bound_failed is None and floor > 0 and error * (1.0 + self.margin) < floor:
            self.bound_failed = (
                f"{self.labels[k]}'s fold without {self.heights[j]:g} m: held-out error "
                f"{error:.3g} %, its full fit's in-sample error {floor:.3g} %"
            )

    def complete(self, k: int) -> bool:
        return len(self.obs[k]) == self.n and all(math.isfinite(e) for e in self.obs[k].values())

    def failed(self, k: int) -> bool:
        return any(not math.isfinite(e) for e in self.obs[k].values())

    def live(self) -> list[int]:
        """Candidates still in the race with folds to run."""
        return [
            k
            for k in range(len(self.labels))
            if self.dropped[k] is None and not self.complete(k) and not self.failed(k)
        ]

    def beats(self, y: int, c: int, j: int) -> bool:
        """Whether complete ``y`` beats ``c`` at height ``j`` (see the module docstring)."""
        ey = self.obs[y][j]
        if j in self.obs[c]:
            return self.obs[c][j] > ey
        return bool(self.floors[c][j] > (1.0 + self.margin) * ey)

    def dominates(self, y: int, c: int) -> bool:
        return all(self.beats(y, c, j) for j in range(self.n))

    def contenders(self) -> list[int]:
        """The candidates (not dropped, not failed) that can still be the best: none that a
        complete candidate dominates, and of the complete ones only those of least mean held-out
        error (a complete candidate with a larger mean than another is not the best)."""
        standing = [
            k for k in range(len(self.labels)) if self.dropped[k] is None and not self.failed(k)
        ]
        complete = [k for k in standing if self.complete(k)]
        least = min((self.mean(k) for k in complete), default=math.inf)
        return [
            c
            for c in standing
            if not any(self.dominates(y, c) for y in complete if y != c)
            and not (self.complete(c) and self.mean(c) > least)
        ]

    def mean(self, k: int) -> float:
        """Candidate ``k``'s mean held-out error over the folds it ran."""
        return mean_or_inf(list(self.obs[k].values()))

    def decide(self, round_no: int) -> list[int]:
        """Drop, after round ``round_no``, the candidates with a failed fold and those every
        contender dominates; returns them."""
        out = []
        if self.bound_failed is not None and any(np.any(f > 0) for f in self.floors):
            self.floors = [np.zeros(self.n) for _ in self.labels]
            for k, d in enumerate(self.dropped):  # those dropped on the bound run their folds
                if d is not None and not self.failed(k):
                    self.dropped[k] = None
        for k in range(len(self.labels)):
            bad = [j for j, e in sorted(self.obs[k].items()) if not math.isfinite(e)]
            if self.dropped[k] is None and bad:
                self._drop(
                    k,
                    round_no,
                    f"its fold without {self.heights[bad[0]]:g} m failed (non-finite held-out "
                    "error)",
                )
                out.append(k)
        contenders = self.contenders()
        if contenders and all(self.complete(y) for y in contenders):
            names = ", ".join(self.labels[y] for y in contenders)
            for c in self.live():
                if c not in contenders and all(self.dominates(y, c) for y in contenders):
                    ran = len(self.obs[c])
                    how = (
                        "no fold run: at each height"
                        if not ran
                        else f"{ran} of {self.n} folds run, at the other heights"
                    )
                    self._drop(
                        c,
                        round_no,
                        f"worse than {names} at every height ({how} its full fit's in-sample "
                        f"error, a lower bound, exceeds {1 + self.margin:g}× theirs)",
                    )
                    out.append(c)
        return out

    def _drop(self, k: int, round_no: int, reason: str) -> None:
        ran = tuple(self.heights[j] for j in sorted(self.obs[k]))
        self.dropped[k] = Dropped(round_no, reason, ran)

    def requests(self) -> dict[int, list[int]]:
        """The folds (candidate → height indices) of the next round; empty when the race is
        over."""
        live = self.live()
        contenders = self.contenders()
        complete = [y for y in contenders if self.complete(y)]
        out: dict[int, list[int]] = {}
        if not complete:
            ahead = [c for c in contenders if c in live]
            if ahead:
                c = min(ahead, key=lambda k: (self.promise[k], k))
                out[c] = self.remaining(c)
            return out or {c: self.remaining(c) for c in live}
        for c in live:
            wanted: set[int] = set()
            for y in complete:
                if any(not self.beats(y, c, j) for j in self.obs[c]):
                    wanted = set(self.remaining(c))  # never dominated by y: it runs them all
                    break
                wanted |= {j for j in self.remaining(c) if not self.beats(y, c, j)}
            if wanted:
                out[c] = sorted(wanted)
        return out or {c: self.remaining(c) for c in live}

    def remaining(self, k: int) -> list[int]:
        return [j for j in range(self.n) if j not in self.obs[k]]


def mean_or_inf(values) -> float:
    """The mean of ``values``, or infinity where one is not finite (or there are none)."""
    values = np.asarray(values, dtype=float)
    return float(np.mean(values)) if values.size and np.all(np.isfinite(values)) else math.inf

"""Conformance probability of the rubber ball to its tolerance table, by Monte Carlo.

:func:`conformance_probability`: the probability that a ball whose drop height, mass or rubber
vary stays inside the rubber-ball tolerances (ISO 16283-2:2020 Table A.1 = ISO 10140-5:2010
Table F.1 = JIS A 1418-2:2019 Table A.2: L_FE per octave band 31.5–500 Hz (Eq. 11, §2.4),
contact time, restitution, mass, drop height), with Wilson score confidence intervals
(:func:`wilson_interval`). The inputs are drawn by :func:`draw_samples` from the
distributions of ``DISTRIBUTION_KINDS``; :func:`conformance_flags` applies the tolerances to
arrays of outputs.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping

import numpy as np

from ..._validate import as_float, check_range
from ...solve.batch import canonical_name
from ...solve.options import EvaluationSpec
from ...solve.parallel import Parallel
from ...spectrum.standards import CLAUSE, RUBBER_BALL_TOLERANCES, TOLERANCED_OCTAVE_BANDS
from ...terms.ball import JIS_RUBBER_BALL, Ball
from ...terms.model import Model
from ..parallel.rows import row_evaluator
from ._common import study_settings

DISTRIBUTION_KINDS = {
    "uniform": ("low", "high"),
    "normal": ("mean", "sd"),
    "lognormal": ("median", "sigma"),
}


def _distribution(name: str, spec) -> tuple[str, float, float]:
    """(kind, a, b) from ``{"kind": ..., <two parameters>}`` or ``(kind, a, b)``."""
    if isinstance(spec, Mapping):
        spec = dict(spec)
        kind = spec.pop("kind", None)
        keys = DISTRIBUTION_KINDS.get(kind)
        if keys is None or set(spec) != set(keys):
            raise ValueError(
                f"distributions[{name!r}]={spec!r} (kind {kind!r}) is not valid; valid: "
                + "; ".join(
                    f"{{kind = {k!r}, {', '.join(v)}}}" for k, v in DISTRIBUTION_KINDS.items()
                )
            )
        a, b = (spec[k] for k in keys)
    else:
        try:
            kind, a, b = spec
        except (TypeError, ValueError):
            raise ValueError(
                f"distributions[{name!r}]={spec!r} must be a mapping or (kind, a, b)"
            ) from None
        if kind not in DISTRIBUTION_KINDS:
            raise ValueError(
                f"distributions[{name!r}] kind {kind!r} is not known; valid: "
                f"{', '.join(DISTRIBUTION_KINDS)}"
            )
    a, b = float(a), float(b)
    ok = (
        math.isfinite(a)
        and math.isfinite(b)
        and (a < b if kind == "uniform" else b > 0.0)
        and (kind != "lognormal" or a > 0.0)
    )
    if not ok:
        need = {
            "uniform": "low < high",
            "normal": "sd > 0",
            "lognormal": "median > 0 and sigma > 0",
        }[kind]
        raise ValueError(
            f"distributions[{name!r}] = {kind}({a!r}, {b!r}) is not valid: needs {need}"
        )
    return kind, a, b


def draw_samples(distributions: Mapping, n_samples: int, seed: int = 0) -> dict[str, np.ndarray]:
    """n_samples independent draws per parameter: uniform(low, high), normal(mean, sd), or
    lognormal(median, sigma) (ln X ~ N(ln median, sigma²)); seeded, identical on every host."""
    rng = np.random.default_rng(seed)
    out = {}
    for name, spec in distributions.items():
        kind, a, b = _distribution(name, spec)
        if kind == "uniform":
            out[name] = rng.uniform(a, b, n_samples)
        elif kind == "normal":
            out[name] = rng.normal(a, b, n_samples)
        else:
            out[name] = a * np.exp(b * rng.standard_normal(n_samples))
    return out


def wilson_interval(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (Wilson 1927; ``scipy.stats.binomtest``);
    (nan, nan) for n = 0."""
    if n == 0:
        return (math.nan, math.nan)
    # lazy: scipy.stats costs 0.5–1.5 s at import
    from scipy.stats import binomtest

    ci = binomtest(int(successes), int(n)).proportion_ci(
        confidence_level=confidence, method="wilson"
    )
    return (float(ci.low), float(ci.high))


@dataclasses.dataclass(frozen=True)
class ConformanceProbability:
    """Monte Carlo conformance of the rubber ball to its tolerance table.

    Attributes:
        n_samples: draws; ``n_valid`` of them solved (status 0) and enter the probabilities.
        probability: item → fraction of valid samples inside the tolerance: ``lfe_<band>_dB``
            for 31.5–500 Hz, ``lfe`` (all five bands), ``contact_time_s``, ``restitution``,
            ``mass_kg``, ``height_m``, ``overall`` (every item).
        interval: item → Wilson score interval at ``confidence``.
        distributions: the input distributions, as (kind, a, b).
        samples: inputs, outputs and per-item pass flags of every draw.
    """

    n_samples: int
    n_valid: int
    confidence: float
    probability: dict
    interval: dict
    distributions: dict
    samples: dict = dataclasses.field(repr=False)

    def to_dict(self) -> dict:

        return {
            "method": "monte-carlo conformance",
            "clause": CLAUSE,
            "n_samples": self.n_samples,
            "n_valid": self.n_valid,
            "confidence": self.confidence,
            "interval_method": "Wilson score",
            "distributions": {k: list(v) for k, v in self.distributions.items()},
            "probability": dict(self.probability),
            "interval": {k: list(v) for k, v in self.interval.items()},
        }

    def table(self) -> str:
        lines = [
            f"Conformance probability, {self.n_valid} valid of {self.n_samples} samples, "
            f"{self.confidence:.0%} Wilson interval"
        ]
        for k, p in self.probability.items():
            lo, hi = self.interval[k]
            lines.append(f"  {k:<18} {p:7.4f}  [{lo:.4f}, {hi:.4f}]")
        return "\n".join(lines)


def conformance_flags(values: Mapping, tolerances=None) -> dict[str, np.ndarray]:
    """Per-sample pass flags, vectorised, by the rule of
    ``rbjax.spectrum.standards.check_conformance`` (lower ≤ value ≤ upper of
    ``RUBBER_BALL_TOLERANCES``). ``values`` holds arrays of the band levels ``lfe_<band>_dB``,
    ``contact_time_s``, ``restitution``, ``mass_kg``, ``height_m``."""

    tol = RUBBER_BALL_TOLERANCES if tolerances is None else tolerances
    inside = lambda t, v: (t.lower <= v) & (v <= t.upper)  # noqa: E731
    flags = {
        f"lfe_{b}_dB": inside(tol.lfe_octave_dB[b], values[f"lfe_{b}_dB"])
        for b in TOLERANCED_OCTAVE_BANDS
    }
    flags["lfe"] = np.all(np.stack(list(flags.values())), axis=0)
    flags["contact_time_s"] = inside(tol.contact_time, values["contact_time_s"])
    flags["restitution"] = inside(tol.restitution, values["restitution"])
    flags["mass_kg"] = inside(tol.mass, values["mass_kg"])
    flags["height_m"] = inside(tol.drop_height, values["height_m"])
    flags["overall"] = (
        flags["lfe"]
        & flags["contact_time_s"]
        & flags["restitution"]
        & flags["mass_kg"]
        & flags["height_m"]
    )
    return flags


def conformance_probability(
    n_samples: int,
    distributions: Mapping,
    *,
    seed: int = 0,
    height_m: float = 1.0,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    confidence: float = 0.95,
    evaluation: EvaluationSpec | None = None,
    parallel: Parallel | Callable | None = None,
) -> ConformanceProbability:
    """Probability that the ball meets the rubber-ball tolerances when its parameters vary.

    ``distributions`` maps parameter names (height, ball or damping fields, any case) to
    ``{"kind": "uniform", "low", "high"}``, ``{"kind": "normal", "mean", "sd"}`` or
    ``{"kind": "lognormal", "median", "sigma"}`` (or a tuple ``(kind, a, b)``), e.g.
    ``{"height_m": ("uniform", 0.99, 1.01), "mass_kg": ("normal", 2.5, 0.05),
    "youngs_Pa": ("lognormal", 1.6e6, 0.1)}``. Each of ``n_samples`` draws is simulated (the
    others keep ``height_m``, ``ball`` and ``model``, an ``rbjax.Model``, default ``Model()``),
    its L_FE per octave band (Eq. 11, §2.4),
    contact time, restitution, mass and drop height are checked against
    ``rbjax.spectrum.standards.RUBBER_BALL_TOLERANCES`` (ISO 16283-2 Table A.1 =
    ISO 10140-5 Table F.1 = JIS A 1418-2 Table A.2), and the pass fractions come with Wilson score
    intervals. The L_FE limits hold for the standard drop height, so vary ``height_m`` around 1 m.
    Draws whose solve is flagged (status ≠ 0) are left out and counted (``n_valid``).
    ``evaluation`` (an ``rbjax.EvaluationSpec``: solve path, ``Solver``, the L_FE record,
    progress) and ``parallel`` (where the draws run): as in
    :func:`~rbjax.studies.sensitivity.global_sensitivity` (default: every draw in this process,
    split over its devices).
    """
    model, evaluation = study_settings("conformance_probability", model, evaluation)
    check_range("n_samples", n_samples, lower=1.0, upper=math.inf, lower_open=False)
    check_range("confidence", confidence, lower=0.0, upper=1.0)
    if not isinstance(distributions, Mapping) or not distributions:
        raise ValueError(
            f"distributions={distributions!r} must be a non-empty mapping of parameter name "
            "to distribution"
        )
    distributions = {canonical_name(k, model): v for k, v in distributions.items()}
    parsed = {k: _distribution(k, v) for k, v in distributions.items()}
    samples = draw_samples(distributions, int(n_samples), seed)
    out = row_evaluator(parallel, evaluation.progress)(
        samples,
        False,
        height_m=height_m,
        ball=ball,
        model=model,
        lfe=True,
        evaluation=evaluation,
    )
    n = int(n_samples)
    values = dict(out)
    values["mass_kg"] = samples.get("mass_kg", np.full(n, as_float(ball.mass_kg)))
    values["height_m"] = samples.get("height_m", np.full(n, float(height_m)))
    valid = out["status"] == 0
    flags = conformance_flags(values)
    n_valid = int(valid.sum())
    probability, interval = {}, {}
    for k, f in flags.items():
        hits = int(np.sum(f & valid))
        probability[k] = hits / n_valid if n_valid else math.nan
        interval[k] = wilson_interval(hits, n_valid, confidence)
    return ConformanceProbability(
        n_samples=n,
        n_valid=n_valid,
        confidence=float(confidence),
        probability=probability,
        interval=interval,
        distributions=parsed,
        samples={
            **{f"input_{k}": v for k, v in samples.items()},
            **out,
            **{f"pass_{k}": v & valid for k, v in flags.items()},
        },
    )

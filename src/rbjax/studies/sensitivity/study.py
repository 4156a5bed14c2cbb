"""Global sensitivity of the rubber-ball impact: a SALib design, evaluated in batches on the
fastest exact path and sharded over the JAX devices (``rbjax.solve.batch``), analysed by SALib.

Outputs: contact time, peak force, restitution, maximum deflection (paper §2.4, Eq. 7) and the
octave-band force exposure levels L_FE 31.5 Hz–1 kHz (Eq. 11, from the 44.1 kHz × 1 s record).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping

import numpy as np

from ..._validate import check_range
from ...solve.batch import (
    SCALAR_OUTPUTS,
    assemble,
    canonical_name,
    lfe_output_names,
)
from ...solve.options import EvaluationSpec
from ...solve.parallel import Parallel
from ...terms.ball import JIS_RUBBER_BALL, Ball
from ...terms.model import Model
from ..parallel.rows import row_evaluator
from ._common import check_ranges, is_lfe, study_settings
from .dgsm import DGSMResult, dgsm_measures
from .indices import fast_indices, morris_screening, pawn_indices, sobol_indices
from .results import FastResult, MorrisResult, PawnResult, SobolResult

#: The analyses of ``global_sensitivity`` and the function that runs each (``n`` is its first
#: size argument: Sobol and DGSM base points, Morris trajectories, eFAST samples per parameter,
#: PAWN samples).
ANALYSES: dict[str, Callable] = {
    "sobol": sobol_indices,
    "morris": morris_screening,
    "fast": fast_indices,
    "pawn": pawn_indices,
    "dgsm": dgsm_measures,
}


def _signature(analysis: str) -> inspect.Signature:
    if analysis not in ANALYSES:
        raise ValueError(
            f"analysis={analysis!r} is not a known sensitivity analysis; valid: "
            f"{', '.join(map(repr, ANALYSES))}"
        )
    return inspect.signature(ANALYSES[analysis])


def analysis_options(analysis: str) -> tuple[str, ...]:
    """The keyword options of ``analysis`` (e.g. ``second_order``, ``n_levels``)."""
    parameters = _signature(analysis).parameters
    return tuple(
        k
        for k, p in parameters.items()
        if p.kind is p.KEYWORD_ONLY and k not in ("seed", "jacobian")
    )


def size_name(analysis: str) -> str:
    """The name of ``analysis``'s sample size (``n_base``, ``n_trajectories``, ...)."""
    return list(_signature(analysis).parameters)[2]


def impact_outputs(outputs) -> tuple[tuple[str, ...], bool]:
    """Expand ``"lfe"`` to the band names; check the names; say whether L_FE is needed."""
    valid = SCALAR_OUTPUTS + lfe_output_names()
    expanded: list[str] = []
    for o in [outputs] if isinstance(outputs, str) else outputs:
        expanded.extend(lfe_output_names() if o == "lfe" else [o])
    unknown = [o for o in expanded if o not in valid]
    if unknown or not expanded:
        raise ValueError(
            f"outputs={list(outputs)!r}: unknown {unknown}; valid: 'lfe', {', '.join(valid)}"
        )
    names = tuple(dict.fromkeys(expanded))
    return names, any(is_lfe(o) for o in names)


def global_sensitivity(
    ranges: Mapping,
    n: int,
    *,
    analysis: str = "sobol",
    outputs=("contact_time_s", "peak_force_N", "restitution", "lfe"),
    height_m: float = 1.0,
    ball: Ball = JIS_RUBBER_BALL,
    model: Model | None = None,
    evaluation: EvaluationSpec | None = None,
    parallel: Parallel | Callable | None = None,
    **options,
) -> SobolResult | MorrisResult | FastResult | PawnResult | DGSMResult:
    """Global sensitivity of the impact outputs over uniform parameter ranges (SALib).

    Args:
        ranges: parameter name (any case; see ``rbjax.parameter_names``) → (low, high).
        n: the analysis's sample size: ``"sobol"`` base points N (a power of two; N (d + 2)
            impacts, N (2d + 2) with ``second_order=True``, the default), ``"morris"``
            trajectories (n (d + 1) impacts), ``"fast"`` samples per parameter (n d), ``"pawn"``
            samples (n), ``"dgsm"`` base points (n (d + 1) impacts for SALib's finite
            differences, and the exact gradients at the n base points).
        analysis: ``"sobol"``, ``"morris"``, ``"fast"``, ``"pawn"`` or ``"dgsm"``.
        outputs: among ``contact_time_s``, ``peak_force_N``, ``restitution``,
            ``max_deflection_m``, ``lfe_<band>_dB`` and ``"lfe"`` (all octave bands).
        height_m, ball, model: the nominal impact (an ``rbjax.Model``, default ``Model()``);
            parameters not in ``ranges`` keep these values.
        evaluation: an ``rbjax.EvaluationSpec``: the solve path and ``Solver`` (default: the
            fastest exact path the model allows), the L_FE record, progress bars.
        parallel: where the design's rows run: an ``rbjax.Parallel`` (default
            ``Parallel(workers=1)``: every row in this process, split over its ``devices`` in
            chunks of ``chunk_size``; with ``workers``, ``scheduler`` or ``executor``: the rows
            as tasks, :func:`rbjax.studies.parallel.rows.evaluate_rows`), or an evaluator called
            as ``evaluator(samples, gradients, **settings)`` (a sweep's job-array parts,
            :mod:`rbjax.studies.sweeps.parts`).
        options: ``seed`` (default 0: of the design and of SALib's bootstrap; every analysis has
            it) and the analysis's keyword options (``analysis_options(analysis)``), e.g.
            ``second_order``, ``design``, ``n_bootstrap``, ``confidence``, ``n_levels``,
            ``optimal_trajectories``, ``interference``, ``n_conditioning``, ``delta``.

    Returns:
        the analysis's result object (``rbjax.studies.sensitivity.results``, ``DGSMResult``):
        ``.driver(output)`` names the parameter that drives an output's spread, ``.table()``,
        ``.plot()``, ``.to_dict()``, ``.salib`` (SALib's own results).
    """
    model, evaluation = study_settings("global_sensitivity", model, evaluation)
    options = dict(options)
    seed = options.pop("seed", 0)
    valid = analysis_options(analysis)
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise ValueError(
            f"options {unknown} are not known for analysis={analysis!r}; valid: {', '.join(valid)}"
        )
    ranges = check_ranges(ranges, lambda name: canonical_name(name, model))
    names, lfe = impact_outputs(outputs)
    for name, (lo, hi) in ranges.items():  # bounds must be valid parameter values (named errors)
        bounds = {name: np.array([lo, hi])}
        assemble(bounds, height_m, ball, model)
        if name == "height_m":
            check_range("height_m", bounds[name], lower=0.0)
    common = dict(
        height_m=height_m,
        ball=ball,
        model=model,
        lfe=lfe,
        evaluation=evaluation,
    )

    evaluator = row_evaluator(parallel, evaluation.progress)

    def func(inputs):
        out = evaluator(inputs, False, **common)
        return {o: out[o] for o in names}

    if analysis == "dgsm":

        def jacobian(inputs):
            _, jac = evaluator(inputs, True, **common)
            return {o: jac[o] for o in names}

        return dgsm_measures(func, ranges, n, jacobian=jacobian, seed=seed, **options)
    return ANALYSES[analysis](func, ranges, n, seed=seed, **options)

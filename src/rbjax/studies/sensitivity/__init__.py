"""Sensitivity of the rubber-ball impact to its parameters: local, global, and conformance.

* **Local** (:func:`local_sensitivity`, :mod:`rbjax.studies.sensitivity.local`): the Jacobian of the
  contact time, peak force, restitution coefficient (paper §2.4, Eq. 7 solved to the end of
  contact) and the octave-band force exposure levels L_FE 31.5 Hz–1 kHz (Eq. 11, from the
  44.1 kHz × 1 s force history, §2.4) with respect to the drop height (Eq. 10), the ball
  parameters (R, h, M, E, ν: §2.1, Eqs. 1–3, 6) and the damping parameters, by forward-mode
  automatic differentiation (``jax.jvp`` per parameter, ``Solver(adjoint="forward")``) through
  the diffrax solve and its event times. Elasticities ∂ln y/∂ln x are % change of the output
  per % change of the parameter; for an L_FE band, whose dB value is already logarithmic, the
  elasticity is that of the band's force energy E (L_FE = 10 log10 E, so
  ∂ln E/∂ln x = (ln 10/10) x ∂L_FE/∂x).
* **Global**, on SALib (sample → evaluate in batches on the fastest exact path, sharded over the
  JAX devices → analyse): Sobol first-, total- and second-order indices on a Sobol'-sequence
  design (:func:`sobol_indices`), Morris screening (:func:`morris_screening`), eFAST
  (:func:`fast_indices`) and PAWN (:func:`pawn_indices`) in
  :mod:`~rbjax.studies.sensitivity.indices`, their result objects in
  :mod:`~rbjax.studies.sensitivity.results`; derivative-based measures from exact gradients
  beside SALib's finite differences, with the total-index bound (:func:`dgsm_measures`,
  :mod:`~rbjax.studies.sensitivity.dgsm`); :func:`global_sensitivity`
  (:mod:`~rbjax.studies.sensitivity.study`) applies any of them to the impact model.
* **Conformance probability** (:func:`conformance_probability`,
  :mod:`rbjax.studies.sensitivity.conformance`): Monte Carlo probability that a ball whose drop
  height, mass or rubber vary stays inside the rubber-ball tolerances (ISO 16283-2:2020 Table A.1 =
  ISO 10140-5:2010 Table F.1 = JIS A 1418-2:2019 Table A.2: L_FE per octave band 31.5–500 Hz,
  contact time, restitution, mass, drop height), with Wilson score confidence intervals.
"""

from .conformance import (
    DISTRIBUTION_KINDS,
    ConformanceProbability,
    conformance_flags,
    conformance_probability,
    draw_samples,
    wilson_interval,
)
from .dgsm import DGSMResult, dgsm_measures
from .indices import SOBOL_DESIGNS, fast_indices, morris_screening, pawn_indices, sobol_indices
from .local import SCALAR_OUTPUTS, Sensitivity, local_sensitivity
from .results import FastResult, IndexResult, MorrisResult, PawnResult, SobolResult
from .study import ANALYSES, analysis_options, global_sensitivity, size_name

__all__ = [
    "SCALAR_OUTPUTS",
    "Sensitivity",
    "local_sensitivity",
    "IndexResult",
    "SobolResult",
    "SOBOL_DESIGNS",
    "sobol_indices",
    "MorrisResult",
    "morris_screening",
    "FastResult",
    "fast_indices",
    "PawnResult",
    "pawn_indices",
    "DGSMResult",
    "dgsm_measures",
    "ANALYSES",
    "analysis_options",
    "size_name",
    "global_sensitivity",
    "DISTRIBUTION_KINDS",
    "draw_samples",
    "wilson_interval",
    "ConformanceProbability",
    "conformance_flags",
    "conformance_probability",
]

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
* **Global** (:mod:`rbjax.studies.sensitivity.indices`): Sobol first- and total-order indices
  (:func:`sobol_indices`, Saltelli 2010 first-order and Jansen 1999 total-order estimators,
  bootstrap confidence intervals) and Morris elementary-effect screening
  (:func:`morris_screening`) over uniform parameter ranges; :func:`global_sensitivity` applies
  them to the impact model, evaluated in batches sharded over the JAX devices
  (:mod:`rbjax.studies.sweep`).
* **Conformance probability** (:func:`conformance_probability`,
  :mod:`rbjax.studies.sensitivity.conformance`): Monte Carlo probability that a ball whose drop height,
  mass or rubber vary stays inside the rubber-ball tolerances (ISO 16283-2:2020 Table A.1 =
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
from .indices import MorrisResult, SobolResult, global_sensitivity, morris_screening, sobol_indices
from .local import SCALAR_OUTPUTS, Sensitivity, local_sensitivity

__all__ = [
    "SCALAR_OUTPUTS",
    "Sensitivity",
    "local_sensitivity",
    "SobolResult",
    "sobol_indices",
    "MorrisResult",
    "morris_screening",
    "global_sensitivity",
    "DISTRIBUTION_KINDS",
    "draw_samples",
    "wilson_interval",
    "ConformanceProbability",
    "conformance_flags",
    "conformance_probability",
]

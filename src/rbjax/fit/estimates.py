"""The uncertainties of a fit at its optimum (a step of :func:`rbjax.fit.driver.fit`): the
covariance of the free parameters from the history rows (:mod:`rbjax.fit.uncertainty`), the
ν prior folded in where ν was held at its mean, and from it every parameter's
:class:`~rbjax.fit.result.ParameterEstimate`, the effective modulus E/√(1−ν²) and the
correlations of the free physical parameters."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from . import uncertainty as unc
from .freedom import Freedom
from .result import ParameterEstimate
from .setup import FitSetup


@dataclasses.dataclass(frozen=True, eq=False)
class Estimates:
    """``parameters``: name → :class:`ParameterEstimate` (with ``effective_modulus_Pa``);
    ``correlations``: (names, matrix) of the free physical parameters (ν among them where its
    prior was folded in); ``conditioning``: the note on the scaled Jacobian;
    ``residuals``: the fitted records' history residuals at the optimum (flat);
    ``tau``: their integrated autocorrelation."""

    parameters: dict[str, ParameterEstimate]
    correlations: tuple[tuple[str, ...], np.ndarray]
    conditioning: str
    residuals: np.ndarray
    tau: float


def estimates(setup: FitSetup, freedom: Freedom, theta, out) -> Estimates:
    """The estimates at the optimum ``theta`` (``out``: its evaluation): Gauss–Newton
    covariance in the transformed coordinates φ, 95 % intervals φ ± 1.96σ_φ mapped back, and
    the delta method for the standard deviations and E/√(1−ν²)."""
    problem, lay, fit_mask, poisson_prior = (
        setup.problem,
        setup.layout,
        setup.fit_mask,
        setup.poisson_prior,
    )
    free_names, physical_free, free_idx = (
        freedom.free_names,
        freedom.physical_free,
        freedom.free_idx,
    )
    ie, inu = lay.index("youngs_Pa"), lay.index("poisson")
    hist_r = problem.history_rows(out["r"], fit_mask)
    tau = unc.integrated_autocorrelation(hist_r)
    hist_r = hist_r.reshape(-1)
    phi_hat = lay.to_phi(theta)
    dtheta = lay.from_phi(phi_hat)[1]
    jac_phi_hist = (
        problem.history_jacobian(out["jac_theta"], fit_mask)[:, free_idx]
        * dtheta[free_idx][None, :]
    )
    prior_index = (
        free_names.index("poisson")
        if (poisson_prior is not None and "poisson" in physical_free)
        else None
    )
    prior_precision = (
        (dtheta[inu] / poisson_prior[1]) ** 2
        if (poisson_prior is not None and prior_index is not None)
        else 0.0
    )
    cov_phi = unc.covariance(jac_phi_hist, hist_r, tau, prior_index, prior_precision)
    if freedom.prior_held:
        free_names, physical_free, cov_phi = unc.fold_in_poisson_prior(
            free_names,
            physical_free,
            list(lay.physical),
            cov_phi,
            float(theta[inu]),
            poisson_prior,
            float(dtheta[inu]),
        )
    std_phi = np.sqrt(np.clip(np.diag(cov_phi), 0, None))

    parameters = {}
    phys_idx = [free_names.index(n) for n in physical_free]
    for n in setup.fittable:
        i = lay.index(n)
        spec = lay.specs[i]
        if n in physical_free:
            j = free_names.index(n)
            lo = float(spec.from_unconstrained(phi_hat[i] - 1.96 * std_phi[j]))
            hi = float(spec.from_unconstrained(phi_hat[i] + 1.96 * std_phi[j]))
            parameters[n] = ParameterEstimate(
                float(theta[i]), float(abs(dtheta[i]) * std_phi[j]), (lo, hi), spec.unit
            )
        else:
            parameters[n] = ParameterEstimate(
                float(theta[i]), 0.0, (float(theta[i]), float(theta[i])), spec.unit, fixed=True
            )
    nu = theta[inu]
    factor = 1.0 / math.sqrt(1.0 - nu**2)
    e_est = parameters["youngs_Pa"]
    e_eff = float(theta[ie] * factor)
    if "poisson" in physical_free:
        # delta method through E/√(1−ν²) with the covariance block of the free ones of (E, ν)
        pairs = [
            ("youngs_Pa", factor * dtheta[ie]),
            ("poisson", theta[ie] * nu * factor**3 * dtheta[inu]),
        ]
        block = [free_names.index(n) for n, _ in pairs if n in free_names]
        grad = np.array([g for n, g in pairs if n in free_names])
        eff_std = float(math.sqrt(max(grad @ cov_phi[np.ix_(block, block)] @ grad, 0.0)))
        eff_ci = (e_eff - 1.96 * eff_std, e_eff + 1.96 * eff_std)
    else:  # ν held: E/√(1−ν²) is E times a constant
        eff_std, eff_ci = e_est.std * factor, (e_est.ci95[0] * factor, e_est.ci95[1] * factor)
    parameters["effective_modulus_Pa"] = ParameterEstimate(
        e_eff, eff_std, eff_ci, "Pa", fixed=e_est.fixed and "poisson" not in physical_free
    )
    d_std = np.sqrt(np.clip(np.diag(cov_phi)[phys_idx], 1e-300, None))
    corr = np.clip(cov_phi[np.ix_(phys_idx, phys_idx)] / np.outer(d_std, d_std), -1.0, 1.0)
    conditioning = unc.conditioning_note(jac_phi_hist, free_names, physical_free, corr)
    return Estimates(parameters, (tuple(physical_free), corr), conditioning, hist_r, tau)

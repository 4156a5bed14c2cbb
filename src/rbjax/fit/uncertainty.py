"""Uncertainty and identifiability of a fit, from the Jacobian at the optimum.

Gauss–Newton covariance C = τ σ̂² (JᵀJ)⁻¹ in the transformed coordinates, σ̂² = RSS/(N − p).
The residuals are correlated in time (low-passed noise, and the systematic misfit of an
approximate model), so N samples carry only N_eff = N/τ independent ones; τ = 1 + 2 Σ ρ_j is
the integrated autocorrelation of the residuals (ρ summed while positive, pooled over
records). 95 % intervals are φ ± 1.96σ_φ mapped through the transform (so they respect the
bounds); standard deviations are the delta-method values in natural units.
"""

from __future__ import annotations

import numpy as np


def whitening(jac, full=False) -> np.ndarray:
    """Inverse column norms of J (Marquardt's scaling); with ``full`` W = R⁻¹ (J = QR)."""
    norms = np.linalg.norm(jac, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    if not full:
        return np.diag(1.0 / norms)
    r = np.linalg.qr(jac / norms, mode="r")
    d = np.abs(np.diag(r))
    if d.size == 0 or d.min() <= 1e-8 * d.max():
        return np.diag(1.0 / norms)
    return np.diag(1.0 / norms) @ np.linalg.inv(r)


def step_in_sigma(r, jac, tau=1.0) -> float:
    """Largest Gauss–Newton step |δ_j|/σ_j still to go, σ_j² = τ σ̂² [(JᵀJ)⁻¹]_jj the
    reported variance. Below ``STEP_TOLERANCE_SIGMA`` the fit has converged."""
    if jac.size == 0:
        return 0.0
    step = np.linalg.lstsq(jac, r, rcond=None)[0]
    sigma2 = tau * float(r @ r) / max(r.size - jac.shape[1], 1)
    cov = np.linalg.pinv(jac.T @ jac, hermitian=True) * sigma2
    return float(np.max(np.abs(step) / np.sqrt(np.maximum(np.diag(cov), 1e-300))))


#: Convergence: the remaining Gauss–Newton step is below this many standard deviations.
STEP_TOLERANCE_SIGMA = 0.05


def integrated_autocorrelation(res) -> float:
    """τ = 1 + 2 Σ_{j≥1} ρ_j of the residual series (rows: records), pooled over records,
    summed while ρ_j > 0 (the initial positive sequence); at least 1."""
    res = np.asarray(res, dtype=float)
    if res.ndim == 1:
        res = res[None, :]
    res = res - res.mean(axis=1, keepdims=True)
    n = res.shape[1]
    var = float(np.sum(res**2))
    if var <= 0:
        return 1.0
    tau = 1.0
    for lag in range(1, n // 2):
        rho = float(np.sum(res[:, :-lag] * res[:, lag:])) / var
        if rho <= 0:
            break
        tau += 2 * rho
    return max(tau, 1.0)


def conditioning_note(jac_phi, free_names, physical_free, corr) -> str:
    if not np.all(np.isfinite(jac_phi)):
        return "(The Jacobian is not finite at the fitted parameters: a failed solve.)"
    j = jac_phi / np.maximum(np.linalg.norm(jac_phi, axis=0), 1e-300)
    sv = np.linalg.svd(j, compute_uv=False)
    cond = float(sv[0] / max(sv[-1], 1e-300))
    worst = ""
    if len(physical_free) > 1:
        c = np.abs(corr - np.eye(len(physical_free)))
        i, k = np.unravel_index(np.argmax(c), c.shape)
        worst = f", largest correlation {corr[i, k]:+.3f} ({physical_free[i]}–{physical_free[k]})"
        if c[i, k] > 0.99:
            worst += ": these two are poorly identifiable separately"
    return f"Fitted parameters: scaled-Jacobian condition number {cond:.2g}{worst}."


def identifiability(jac_hist, i_e: int, i_nu: int, columns) -> tuple[str, bool, float]:
    """(note, E–ν flagged?, |cos(∂r/∂E, ∂r/∂ν)|) from the history Jacobian (columns of θ).

    E and ν enter the model only through the Reissner stiffness k = 4Eh²/(R√(3(1−ν²)))
    (Eqs. 1–3, corrected); the gas force (Eq. 4) does not involve them and the damping terms
    scale with k. So ∂r/∂E and ∂r/∂ν are parallel and only E/√(1−ν²) is determined.
    ``columns``: the θ columns that would be free with E and ν both free.
    """
    a, b = jac_hist[:, i_e], jac_hist[:, i_nu]
    denom = np.linalg.norm(a) * np.linalg.norm(b)
    cos = float(abs(a @ b) / denom) if denom > 0 else 1.0
    j = jac_hist[:, list(columns)]
    j = j / np.maximum(np.linalg.norm(j, axis=0), 1e-300)
    sv = np.linalg.svd(j, compute_uv=False)
    cond = float(sv[0] / max(sv[-1], 1e-300))
    flagged = cos > 1 - 1e-6 or cond > 1e8
    note = f"(With E and ν both free the column-scaled Jacobian has condition number {cond:.1e}.)"
    return note, flagged, cos


def covariance(
    jac_phi, r, tau: float, prior_index=None, prior_precision: float = 0.0
) -> np.ndarray:
    """Scaled-inverse Gauss–Newton covariance of φ, τσ̂²(JᵀJ)⁻¹ (plus a prior's precision);
    all NaN where the Jacobian or the residuals are not finite (a failed solve: no uncertainty
    to report, and the fit says it did not converge)."""
    p = jac_phi.shape[1]
    if not (np.all(np.isfinite(jac_phi)) and np.all(np.isfinite(r))):
        return np.full((p, p), np.nan)
    sigma2 = float(r @ r) / max(r.size - p, 1)
    info = jac_phi.T @ jac_phi / (tau * sigma2)
    if prior_index is not None:
        info[prior_index, prior_index] += prior_precision
    scale = np.sqrt(np.maximum(np.diag(info), 1e-300))
    return np.linalg.pinv(info / np.outer(scale, scale), rcond=1e-13, hermitian=True) / np.outer(
        scale, scale
    )


def fold_in_poisson_prior(
    free_names, physical_free, physical, cov_phi, nu: float, prior, dnu_dphi: float
):
    """Add ν ~ N(mean, std²) to a covariance fitted with ν held at the mean (in φ = (log E,
    logit ν, …)).

    With ν held, the fitted log E is log E_eff + ½log(1 − ν²) at ν fixed; letting ν vary
    by its prior at fixed E_eff adds a = ∂log E/∂ν = −ν/(1 − ν²) times ν's deviation to log E.
    """
    std = prior[1]
    a = -nu / (1.0 - nu**2)
    ie = free_names.index("youngs_Pa")
    n = len(free_names)
    cov = np.zeros((n + 1, n + 1))
    order = list(range(ie + 1)) + [n] + list(range(ie + 1, n))  # ν right after E
    cov[:n, :n] = cov_phi
    cov[n, n] = (std / dnu_dphi) ** 2
    cov[ie, ie] += a**2 * std**2
    cov[ie, n] = cov[n, ie] = a * std**2 / dnu_dphi
    cov = cov[np.ix_(order, order)]
    names = free_names[: ie + 1] + ["poisson"] + free_names[ie + 1 :]
    phys = [p for p in physical if p in physical_free or p == "poisson"]
    return names, phys, cov

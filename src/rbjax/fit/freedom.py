"""Which parameters a fit frees (a step of :func:`rbjax.fit.driver.fit`): E and ν checked for
identifiability from the Jacobian at the first start (ν held, fitted, or determined by its
prior), then the free physical parameters, the fitted records' onset shifts and height errors;
and the ν prior's residual row."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from . import uncertainty as unc
from .setup import FitSetup
from .start import Starts


@dataclasses.dataclass(frozen=True, eq=False)
class Freedom:
    """The free parameters of a fit: ``physical_free`` (names), ``free_names`` (those and the
    free onset shifts and height errors), their θ positions ``free_idx`` and mask ``free``;
    ``nu``: the value of ν in every start; ``prior_held``: ν held at its prior mean, the prior
    folded into the covariance afterwards; ``notes``: what the E–ν check found; ``ident_msg``:
    the conditioning with E and ν both free."""

    physical_free: list[str]
    free_names: list[str]
    free_idx: np.ndarray
    free: np.ndarray
    nu: float
    prior_held: bool
    notes: list[str]
    ident_msg: str


def free_parameters(setup: FitSetup, starts: Starts, hold_poisson: float) -> Freedom:
    """Identifiability from the Jacobian at the first start with ν free: E and ν enter only
    through E/√(1−ν²) (:func:`rbjax.fit.uncertainty.identifiability`), so ν is held at
    ``hold_poisson`` (or at the prior mean, with a prior) when their columns are parallel;
    then the free parameters."""
    problem, lay, fit_mask, poisson_prior = (
        setup.problem,
        setup.layout,
        setup.fit_mask,
        setup.poisson_prior,
    )
    theta, out = starts.thetas[0], starts.outs[0]
    physical_free = [n for n in setup.fittable if n not in setup.fixed]
    ie, inu = lay.index("youngs_Pa"), lay.index("poisson")
    nu = theta[inu]
    shift_cols = list(np.arange(len(lay.names))[lay.shift_slice][fit_mask])
    cols = [
        lay.index(n) for n in setup.fittable if n in physical_free or n in ("youngs_Pa", "poisson")
    ] + shift_cols
    jac_hist = problem.history_jacobian(out["jac_theta"], fit_mask)
    ident_msg, nu_flagged, cos_e_nu = unc.identifiability(jac_hist, ie, inu, cols)
    prior_held = False
    notes = []
    if "poisson" in physical_free and "youngs_Pa" not in physical_free:
        notes.append("E held as given; ν alone sets the stiffness and is fitted.")
    elif "poisson" in physical_free and poisson_prior is None:
        if nu_flagged:
            physical_free.remove("poisson")
            nu = hold_poisson
            notes.append(
                f"E and ν are not separately identifiable: their Jacobian columns are parallel "
                f"(|cos| = {cos_e_nu:.8f}); the data determine only E/√(1−ν²) (Reissner stiffness, "
                f"Eqs. 1–3; the gas force does not involve E or ν). ν is held at {hold_poisson:g}"
                + (
                    " (the paper's value, §4; the bound of the model's range)"
                    if hold_poisson == 0.5
                    else ""
                )
                + " and effective_modulus_Pa = E/√(1−ν²) is the fitted quantity."
            )
        else:
            notes.append(f"E and ν: |cos| of their Jacobian columns {cos_e_nu:.6f}; both fitted.")
    elif "poisson" in physical_free and poisson_prior is not None:
        notes.append(
            f"E and ν are not separately identifiable from the histories (|cos| = {cos_e_nu:.8f}); "
            f"ν is determined by its prior N({poisson_prior[0]:g}, {poisson_prior[1]:g}²)."
        )
        if nu_flagged:
            # The histories fix only E/√(1−ν²), so the posterior mode has ν at the prior mean
            # exactly: optimise with ν held there (the curved E–ν valley is a trap for LM) and
            # fold the prior into the covariance afterwards.
            prior_held = True
            physical_free.remove("poisson")
            nu = poisson_prior[0]
    else:
        notes.append(f"ν held at {theta[inu]:g} as given; E/√(1−ν²) is what the data determine.")

    free_names = physical_free + [lay.names[i] for i in shift_cols]
    if lay.height_error:
        free_names += [lay.names[i] for i in np.arange(len(lay.names))[lay.dh_slice][fit_mask]]
    free_idx = np.array([lay.index(n) for n in free_names], dtype=int)
    free = np.zeros(len(lay.names), dtype=bool)
    free[free_idx] = True
    return Freedom(physical_free, free_names, free_idx, free, nu, prior_held, notes, ident_msg)


def prior_row(setup: FitSetup, freedom: Freedom, r) -> tuple[float, float, float]:
    """The ν prior's residual row (mean, std, unit) at the residuals ``r``; (0, 1, 0) without
    a prior on a free ν.

    The history rows are not whitened (their scale is 1/peak or 1/noise, and the noise is
    correlated), so the prior row is put in their units: one prior σ weighs as much as one
    σ̂√τ of the history residuals (σ̂, τ taken at the start of a round)."""
    poisson_prior = setup.poisson_prior
    if poisson_prior is None or "poisson" not in freedom.physical_free:
        return (0.0, 1.0, 0.0)
    hist = setup.problem.history_rows(r, setup.fit_mask)
    unit = math.sqrt(
        unc.integrated_autocorrelation(hist) * float(np.sum(hist**2)) / max(hist.size, 1)
    )
    return (poisson_prior[0], poisson_prior[1], unit)

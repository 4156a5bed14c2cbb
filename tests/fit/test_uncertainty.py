"""The fit's covariance (rbjax.fit.uncertainty) against the textbook linear least-squares one, and
at a failed solve (a Jacobian that is not finite): NaN that says so, never a numpy LinAlgError
raised inside a selection's worker."""

import numpy as np

from rbjax.fit import uncertainty as unc


def test_covariance_is_the_linear_least_squares_one():
    rng = np.random.default_rng(3)
    jac = rng.normal(size=(200, 3)) * np.array([1.0, 1e3, 1e-2])  # badly scaled columns
    r = rng.normal(size=200)
    tau = 2.5
    sigma2 = r @ r / (200 - 3)
    expected = tau * sigma2 * np.linalg.inv(jac.T @ jac)
    np.testing.assert_allclose(unc.covariance(jac, r, tau), expected, rtol=1e-10)


def test_a_prior_adds_its_precision():
    rng = np.random.default_rng(4)
    jac, r = rng.normal(size=(50, 2)), rng.normal(size=50)
    sigma2 = r @ r / 48
    info = jac.T @ jac / sigma2
    info[1, 1] += 7.0
    got = unc.covariance(jac, r, 1.0, prior_index=1, prior_precision=7.0)
    np.testing.assert_allclose(got, np.linalg.inv(info), rtol=1e-10)


def test_a_jacobian_that_is_not_finite_gives_nan_and_says_so():
    jac = np.ones((20, 2))
    jac[3, 1] = np.nan
    r = np.ones(20)
    cov = unc.covariance(jac, r, 1.0)
    assert cov.shape == (2, 2) and np.all(np.isnan(cov))
    note = unc.conditioning_note(jac, ["youngs_Pa", "alpha_s_per_m"], [], np.eye(0))
    assert "not finite" in note
    r[0] = np.inf
    assert np.all(np.isnan(unc.covariance(np.ones((20, 2)), r, 1.0)))

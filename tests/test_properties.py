"""Properties of the forward model over the valid parameter space (hypothesis).

Each hypothesis example is a batch of N random balls and drops (radius 3–15 cm, wall 10–50 % of
the radius, mass 0.2–5 kg, E 0.3–30 MPa, ν 0–0.5, drop height 1 mm–3 m), evaluated in ONE
``rbjax.simulate`` call of fixed shape (so the compile is shared by every example), together
with the same drops from twice the height, with twice the Young's modulus and with twice the mass:

* statuses: ok outputs are finite; every non-ok status has NaN outputs (README, "Failures are
  flagged, never plausible");
* energy is never gained: 0 < restitution ≤ 1 (paper §2.3: the momentum flux of Eq. 7 only
  dissipates; damping only dissipates);
* the elastic model (paper Eq. 7): contact time decreases and peak force increases with drop height
  (paper Figs. 5–6), contact time decreases with E (stiffer shell, Eqs. 1–3) and increases with mass.

The monotonic differences are at least 3e-5 relative over this space (a quadrature scan of 20 000
points), far above the 1e-9 solver error, so the strict comparisons test the model, not round-off.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rbjax

N = 16
SETTINGS = settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
OUTPUTS = ("contact_time_s", "peak_force_N", "peak_time_s", "restitution", "max_deflection_m")


def _log_uniform(lo, hi):
    return st.floats(0.0, 1.0).map(lambda u: math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))


PARAMS = st.tuples(
    st.floats(0.03, 0.15),  # radius_m
    st.floats(0.1, 0.5),  # wall / radius
    _log_uniform(0.2, 5.0),  # mass_kg
    _log_uniform(3e5, 3e7),  # youngs_Pa
    st.floats(0.0, 0.5),  # poisson
    _log_uniform(1e-3, 3.0),  # height_m
    st.floats(0.0, 5.0),  # damping ratio ζ (damped batch only)
)
BATCHES = st.lists(PARAMS, min_size=N, max_size=N)


def _columns(params):
    p = np.asarray(params, dtype=float).T
    radius, wall_ratio, mass, youngs, poisson, height, zeta = p
    return radius, wall_ratio * radius, mass, youngs, poisson, height, zeta


def _variants(params):
    """Rows: base, twice the height, twice E, twice the mass (shape (4, N) per field)."""
    radius, wall, mass, youngs, poisson, height, zeta = _columns(params)
    one = np.ones(4)[:, None]
    heights = np.stack([height, 2 * height, height, height])
    ball = rbjax.Ball(
        radius_m=one * radius,
        wall_m=one * wall,
        mass_kg=np.stack([mass, mass, mass, 2 * mass]),
        youngs_Pa=np.stack([youngs, youngs, 2 * youngs, youngs]),
        poisson=one * poisson,
    )
    return heights, ball, zeta


def _check_status_conventions(res):
    status = np.asarray(res.status)
    assert set(np.unique(status)) <= set(rbjax.STATUS_NAMES)
    ok = status == 0
    for name in OUTPUTS:
        value = np.asarray(getattr(res, name))
        assert np.all(np.isfinite(value[ok])), name
        assert np.all(np.isnan(value[~ok])), name
    e = np.asarray(res.restitution)[ok]
    assert np.all(e > 0.0)
    assert np.all(e <= 1.0 + 1e-12)
    assert np.all(np.asarray(res.contact_time_s)[ok] > 0.0)
    assert np.all(np.asarray(res.peak_force_N)[ok] > 0.0)


@SETTINGS
@given(BATCHES)
def test_elastic_model_properties(params):
    heights, ball, _ = _variants(params)
    res = rbjax.simulate(heights, ball)
    _check_status_conventions(res)
    ok = np.asarray(res.status) == 0
    tc = np.asarray(res.contact_time_s)
    force = np.asarray(res.peak_force_N)
    pairs = {"height": 1, "youngs": 2, "mass": 3}
    both = {k: ok[0] & ok[row] for k, row in pairs.items()}
    assert np.all(tc[1][both["height"]] < tc[0][both["height"]])  # higher drop: shorter contact
    assert np.all(force[1][both["height"]] > force[0][both["height"]])  # ... and harder hit
    assert np.all(tc[2][both["youngs"]] < tc[0][both["youngs"]])  # stiffer: shorter
    assert np.all(tc[3][both["mass"]] > tc[0][both["mass"]])  # heavier: longer


@SETTINGS
@given(BATCHES)
def test_damped_model_never_gains_energy(params):
    heights, ball, zeta = _variants(params)  # the elastic test's shapes: its compile is reused
    c = zeta * 2.0 * np.sqrt(np.asarray(ball.stiffness_N_per_m) * np.asarray(ball.mass_kg))
    res = rbjax.simulate(heights, ball, damping=rbjax.KelvinVoigt(c))
    _check_status_conventions(res)
    # damping only removes energy: never more rebound than the same ball without it
    elastic = rbjax.simulate(heights, ball)
    both = (np.asarray(res.status) == 0) & (np.asarray(elastic.status) == 0)
    assert np.all(np.asarray(res.restitution)[both] <= np.asarray(elastic.restitution)[both] + 1e-12)

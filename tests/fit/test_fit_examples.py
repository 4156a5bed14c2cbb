"""The fit on the bundled emulated recordings predicts heights it has not seen better than the
paper's unfitted model (issue #3).

The emulated data come from a model with physics rbjax does not contain (see the data's
README), so this is a test of prediction, not of recovery: heights 0.2 m and 0.8 m are left
out of the fit and compared with the unfitted paper model (JIS ball, E = 1.6 MPa, adiabatic
gas, paper blocked force) in contact time, peak force and octave-band L_FE.

Two fitted models are checked, each claim of docs/guides/fitting.md (the
paragraph "Where they fall short" below the held-out table) at its printed figure:
hunt-crossley/momentum cuts the history error to 0.54× and 0.22× the paper model's, brings every
tolerance band within 2.2 dB (the paper's model: 6–9 dB off at 500 Hz) but predicts the contact
time ~3 % long (the paper's unfitted model: 1–2 %); zener/momentum predicts the contact time
within 0.6 % but the peak force 2–5 % low; neither reproduces the 1 kHz band.
"""

from __future__ import annotations

import numpy as np
import pytest

from rbjax.data import examples_dir
from rbjax.fit import load_data
from rbjax.studies.selection.hold_out_comparison import held_out_comparison

FIT_HEIGHTS_M = (0.1, 0.4, 1.0, 1.6)
#: Octave bands 31.5–500 Hz: those the standard's tolerance table covers.
TOLERANCE_BANDS = slice(0, 5)


@pytest.fixture(scope="module")
def comparison():
    data = load_data(examples_dir())
    return held_out_comparison(
        data,
        FIT_HEIGHTS_M,
        candidates=["hunt-crossley", "zener"],
        blocked_forces=["momentum"],
        progress=False,
    )


def test_only_the_held_out_heights_are_compared(comparison):
    assert comparison.predict_heights_m == (0.2, 0.8)
    assert set(comparison.rows) == {"hunt-crossley/momentum", "zener/momentum", "paper (unfitted)"}


def _rows(comparison, label):
    return list(zip(comparison.rows[label], comparison.rows["paper (unfitted)"], strict=True))


@pytest.mark.parametrize("label", ["hunt-crossley/momentum", "zener/momentum"])
def test_fitted_models_predict_history_peak_and_bands_better_than_the_paper(comparison, label):
    assert all(r.converged for r in comparison.rows[label])
    for f, p in _rows(comparison, label):
        assert f.height_m == p.height_m
        assert f.history_error_pct < 0.6 * p.history_error_pct, (f, p)
        assert np.mean(np.abs(f.lfe_octave_dB[TOLERANCE_BANDS])) < np.mean(
            np.abs(p.lfe_octave_dB[TOLERANCE_BANDS])
        ), (f, p)
        assert np.all(np.abs(f.lfe_octave_dB[TOLERANCE_BANDS]) < 2.5), f  # measured ≤ 2.3 dB
        # docs/guides/fitting.md, "Where they fall short": neither model reproduces the 1 kHz band
        # (measured 4.8–11 dB off)
        assert abs(f.lfe_octave_dB[5]) > 3.0, f
    # The peak force, over the two held-out heights (docs/guides/fitting.md, the held-out table,
    # |Δpeak|: hunt-crossley 0.52, 1.52 %; zener 5.27, 2.41 %, mean 3.84 %; the paper's model 2.67,
    # 5.43 %, mean 4.05 %): zener is the further at 0.2 m, the nearer at 0.8 m, and the nearer on
    # average.
    mean_peak = lambda rows: np.mean([abs(r.peak_force_pct) for r in rows])  # noqa: E731
    fitted, paper = zip(*_rows(comparison, label), strict=True)
    assert mean_peak(fitted) < mean_peak(paper), (fitted, paper)


def test_hunt_crossley_claims(comparison):
    """docs/guides/fitting.md, "Where they fall short", hunt-crossley/momentum: the history
    error 0.54× and 0.22× the paper model's, every tolerance band within 2.2 dB (the paper's model
    6–9 dB off at 500 Hz), the contact time ~3 % long against the paper model's 1–2 %; its peak
    force nearer than the paper model's at each height (the table: +0.52, +1.52 % against +2.67,
    +5.43 %)."""
    stated_ratio = {0.2: 0.54, 0.8: 0.22}
    for f, p in _rows(comparison, "hunt-crossley/momentum"):
        assert f.history_error_pct / p.history_error_pct < stated_ratio[f.height_m] + 0.05, (f, p)
        assert np.all(np.abs(f.lfe_octave_dB[TOLERANCE_BANDS]) < 2.2), f
        assert 5.5 <= abs(p.lfe_octave_dB[4]) < 9.5, p
        assert 2.5 < f.contact_time_pct < 3.5, f
        assert 0.5 <= abs(p.contact_time_pct) < 2.5 and abs(f.contact_time_pct) > abs(
            p.contact_time_pct
        ), p
        assert abs(f.peak_force_pct) < abs(p.peak_force_pct), (f, p)


def test_zener_claims(comparison):
    """docs/guides/fitting.md, "Where they fall short", zener/momentum: the contact time
    within 0.6 % (better than the paper model's), the peak force 2–5 % low."""
    for f, p in _rows(comparison, "zener/momentum"):
        assert abs(f.contact_time_pct) < 0.6, f
        assert abs(f.contact_time_pct) < abs(p.contact_time_pct), (f, p)
        assert -5.5 < f.peak_force_pct < -1.5, f


#: docs/guides/fitting.md, the held-out table ("Fitted to 0.1, 0.4, 1.0 and 1.6 m and predicting
#: the two heights the fit never saw"): (model, h) → history err (%), Δt_c (%), Δpeak (%) and
#: ΔL 31.5 … 1000 Hz (dB), as printed.
HELD_OUT_TABLE = {
    ("hunt-crossley/momentum", 0.2): (3.50, 3.16, 0.52, (0.02, -0.48, -0.70, 0.33, -2.13, -11.45)),
    ("hunt-crossley/momentum", 0.8): (1.98, 2.77, 1.52, (0.03, -0.13, -0.93, 0.17, -0.55, -4.92)),
    ("zener/momentum", 0.2): (3.04, 0.34, -5.27, (-0.40, -0.60, 0.77, 2.29, -0.97, -10.84)),
    ("zener/momentum", 0.8): (1.56, -0.53, -2.41, (-0.14, -0.28, 0.50, 1.50, -0.01, -4.76)),
    ("paper (unfitted)", 0.2): (6.47, 2.21, 2.67, (0.18, -0.03, -1.03, -0.87, -5.95, -19.58)),
    ("paper (unfitted)", 0.8): (8.94, 0.93, 5.43, (0.28, 0.62, -2.80, -3.90, -9.41, -18.49)),
}


def test_the_held_out_table_at_its_printed_digits(comparison):
    """docs/guides/fitting.md, the held-out table: every figure within the rounding of its last
    printed digit (0.005), plus 0.001 for round-off."""
    for (label, h), (err, tc, peak, bands) in HELD_OUT_TABLE.items():
        (row,) = [r for r in comparison.rows[label] if abs(r.height_m - h) < 1e-9]
        got = (row.history_error_pct, row.contact_time_pct, row.peak_force_pct, *row.lfe_octave_dB)
        want = (err, tc, peak, *bands)
        np.testing.assert_allclose(got, want, rtol=0, atol=0.006, err_msg=f"{label} at {h} m")

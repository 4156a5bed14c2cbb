"""The fit on the bundled emulated recordings predicts heights it has not seen better than the
paper's unfitted model (issue #3).

The emulated data come from a model with physics rbjax does not contain (see the data's
README), so this is a test of prediction, not of recovery: heights 0.2 m and 0.8 m are left
out of the fit and compared with the unfitted paper model (JIS ball, E = 1.6 MPa, adiabatic
gas, paper blocked force) in contact time, peak force and octave-band L_FE.

Two fitted models are checked: hunt-crossley/momentum, the one `rbjax select` recommends on
these data (fewest parameters within a standard error of the best held-out history error),
and zener/momentum, the best held-out history error. Measured (README): the recommended model
beats the paper's in history, peak force and every tolerance band but predicts the contact
time ~3 % long (the paper's unfitted model: 1–2 %); zener/momentum beats it in all of them.
"""

from __future__ import annotations

import numpy as np
import pytest

from rbjax.data import examples_dir
from rbjax.fit import load_data
from rbjax.studies.selection import held_out_comparison

FIT_HEIGHTS_M = (0.1, 0.4, 1.0, 1.6)
#: Octave bands 31.5–500 Hz: those the standard's tolerance table covers.
TOLERANCE_BANDS = slice(0, 5)


@pytest.fixture(scope="module")
def comparison():
    data = load_data(examples_dir())
    return held_out_comparison(data, FIT_HEIGHTS_M, candidates=["hunt-crossley", "zener"], blocked_forces=["momentum"], progress=False)


def test_only_the_held_out_heights_are_compared(comparison):
    assert comparison.predict_heights_m == (0.2, 0.8)
    assert set(comparison.rows) == {"hunt-crossley/momentum", "zener/momentum", "paper (unfitted)"}


def _mean_band_error(row):
    return float(np.mean(np.abs(row.lfe_octave_dB[TOLERANCE_BANDS])))


@pytest.mark.parametrize("label", ["hunt-crossley/momentum", "zener/momentum"])
def test_fitted_models_predict_history_peak_and_bands_better_than_the_paper(comparison, label):
    fitted = comparison.rows[label]
    paper = comparison.rows["paper (unfitted)"]
    assert all(r.converged for r in fitted)
    for f, p in zip(fitted, paper):
        assert f.height_m == p.height_m
        assert f.history_error_pct < 0.6 * p.history_error_pct, (f, p)
        assert _mean_band_error(f) < _mean_band_error(p), (f, p)
        # every tolerance band within 2.5 dB (the unfitted model misses 500 Hz by 6–9 dB)
        assert np.all(np.abs(f.lfe_octave_dB[TOLERANCE_BANDS]) < 2.5), f
    mean_peak = lambda rows: np.mean([abs(r.peak_force_pct) for r in rows])  # noqa: E731
    assert mean_peak(fitted) < mean_peak(paper)


def test_zener_also_predicts_the_contact_time_better_than_the_paper(comparison):
    for f, p in zip(comparison.rows["zener/momentum"], comparison.rows["paper (unfitted)"]):
        assert abs(f.contact_time_pct) < abs(p.contact_time_pct), (f, p)
        assert abs(f.contact_time_pct) < 1.0, f

"""Model selection run end to end on the bundled recordings (docs/guides/fitting.md, "Model
selection on the bundled emulated recordings"; the README's validated table): every fit, every
leave-one-height-out fold and the rule, for the three candidates the page's recommendation turns on,
all with the ``momentum`` blocked force: the best model without the ball mode, the one with it, and
the runner-up, its massless limit (the series element: one parameter fewer, kept out by its paired
excess over the ball mode). The figures are the page's, each within the rounding of its last printed
digit.

The independent check of the rule itself (hand-worked candidates) is
``test_selection_rule.py``; this test checks that the fits feeding it give the stated
recommendation and held-out errors.
"""

from __future__ import annotations

import math
from statistics import fmean

import pytest

from rbjax.data import examples_dir
from rbjax.fit import load_data, prepare_data
from rbjax.studies import select_model

#: docs/guides/fitting.md, "Model selection on the bundled emulated recordings", the held-out
#: history err (%) column: the mean over the 6 folds ± its standard error.
README_HELD_OUT = {
    "hunt-crossley/momentum": (2.59, 0.36),
    "hunt-crossley+ball-mode/momentum": (1.03, 0.16),
    "hunt-crossley+series-kelvin-voigt/momentum": (1.07, 0.16),
}


@pytest.fixture(scope="module")
def selection():
    data = prepare_data(load_data(examples_dir()))
    return select_model(
        data,
        ["hunt-crossley", "hunt-crossley+ball-mode", "hunt-crossley+series-kelvin-voigt"],
        blocked_forces=("momentum",),
        progress=False,
        exhaustive=True,  # the page's table: every fold (the race drops hunt-crossley's)
    )


def test_the_ball_mode_is_recommended_and_neither_other_of_the_three_is_within_the_noise(
    selection,
):
    # docs/guides/fitting.md: recommended hunt-crossley+ball-mode/momentum, "no other
    # candidate is within the noise of the best": of these three here; of all twelve measured
    # (benchmarks/fitting.py --only selection_race, the exhaustive run on the bundled recordings)
    assert selection.recommended.label == "hunt-crossley+ball-mode/momentum"
    assert [c.label for c in selection.within_noise] == ["hunt-crossley+ball-mode/momentum"]


@pytest.mark.parametrize("label", sorted(README_HELD_OUT))
def test_held_out_errors_are_the_readme_table_within_their_standard_error(selection, label):
    # docs/guides/fitting.md, "Model selection" table, held-out history err (%) column
    stated, se = README_HELD_OUT[label]
    candidate = next(c for c in selection.candidates if c.label == label)
    assert candidate.fit.converged
    assert len(candidate.folds) == 6
    # the mean and its standard error from the fold errors, here (std with ddof 1 over √6)
    errors = [fold.history_error_pct for fold in candidate.folds]
    mean = sum(errors) / 6
    stderr = (sum((e - mean) ** 2 for e in errors) / 5) ** 0.5 / 6**0.5
    assert candidate.cv_error_pct == pytest.approx(mean, rel=1e-12)
    # each at its printed figure (two decimals): within the rounding of the last digit, plus
    # 0.001 for the round-off between this two-candidate run and the page's twelve
    assert abs(mean - stated) <= 0.006, (label, mean, stderr)
    assert abs(stderr - se) <= 0.006, (label, mean, stderr)


def test_the_runner_up_is_kept_out_by_its_paired_excess(selection):
    # docs/guides/fitting.md: the massless limit hunt-crossley+series-kelvin-voigt (one
    # parameter fewer) comes second, "but its fold-by-fold excess over the ball mode is +0.040 ±
    # 0.009 % (positive in all six folds)", so the rule keeps the ball mode. The excess and its
    # standard error from the fold errors, here, fold matched to fold by its held-out height.
    by_label = {c.label: c for c in selection.candidates}
    mode = by_label["hunt-crossley+ball-mode/momentum"]
    series = by_label["hunt-crossley+series-kelvin-voigt/momentum"]
    assert series.n_physical == mode.n_physical - 1
    folds = {f.height_m: f.history_error_pct for f in mode.folds}
    excess = [f.history_error_pct - folds[f.height_m] for f in series.folds]
    assert len(excess) == 6 and sorted(folds) == sorted(f.height_m for f in series.folds)
    mean = sum(excess) / 6
    stderr = (sum((d - mean) ** 2 for d in excess) / 5) ** 0.5 / 6**0.5
    assert all(d > 0 for d in excess), excess
    assert abs(mean - 0.040) <= 0.0006, (mean, stderr)
    assert abs(stderr - 0.009) <= 0.0006, (mean, stderr)
    ranked = sorted(selection.candidates, key=lambda c: c.cv_error_pct)
    assert [c.label for c in ranked[:2]] == [mode.label, series.label]


#: docs/guides/fitting.md, "Model selection on the bundled emulated recordings", the rest of the
#: rows of these three candidates and of the unfitted paper model: fitted params, history rms (N),
#: |Δt_c| (%), |Δpeak| (%) and |ΔL| 31.5 … 1000 Hz (dB), means of |Δ| over the folds.
PAGE_ROWS = {
    "hunt-crossley/momentum": (
        2,
        19.7,
        2.48,
        1.70,
        (0.06, 0.31, 0.74, 0.30, 1.19, 7.60),
    ),
    "hunt-crossley+ball-mode/momentum": (5, 8.7, 0.50, 0.67, (0.05, 0.13, 0.35, 0.91, 1.02, 7.43)),
    "hunt-crossley+series-kelvin-voigt/momentum": (
        4,
        8.7,
        0.55,
        0.75,
        (0.05, 0.14, 0.41, 0.83, 1.08, 7.47),
    ),
}
#: the unfitted paper model's row: history err (%), |Δt_c|, |Δpeak| (%), |ΔL| per band (dB)
PAGE_BASELINE = (8.22, 1.48, 4.72, (0.26, 0.49, 2.41, 3.02, 8.19, 19.18))
#: within the rounding of the printed digit, plus 0.001 (this run against the page's twelve)
TWO_DECIMALS = 0.006


@pytest.mark.parametrize("label", sorted(PAGE_ROWS))
def test_the_rest_of_the_rows_are_the_page_table(selection, label):
    params, rms, tc, peak, bands = PAGE_ROWS[label]
    candidate = next(c for c in selection.candidates if c.label == label)
    assert candidate.n_physical == params
    assert abs(candidate.fit.residual_rms_N - rms) <= 0.051, candidate.fit.residual_rms_N
    assert abs(candidate.mean_abs("contact_time_pct") - tc) <= TWO_DECIMALS, label
    assert abs(candidate.mean_abs("peak_force_pct") - peak) <= TWO_DECIMALS, label
    got = candidate.mean_abs("lfe_octave_dB")
    assert max(abs(g - b) for g, b in zip(got, bands, strict=True)) <= TWO_DECIMALS, (label, got)


def test_the_unfitted_paper_row_is_the_page_table(selection):
    err, tc, peak, bands = PAGE_BASELINE
    base = selection.baseline
    assert len(base) == 6
    assert abs(fmean([b.history_error_pct for b in base]) - err) <= TWO_DECIMALS
    assert abs(fmean([abs(b.contact_time_pct) for b in base]) - tc) <= TWO_DECIMALS
    assert abs(fmean([abs(b.peak_force_pct) for b in base]) - peak) <= TWO_DECIMALS
    for j, printed in enumerate(bands):
        assert abs(fmean([abs(b.lfe_octave_dB[j]) for b in base]) - printed) <= TWO_DECIMALS, j


def test_the_fitted_ball_mode_and_series_element_read_as_the_pages_say(selection):
    """docs/guides/fitting.md, "With the ball mode", for the six bundled heights: "a 530 g mass
    at the contact (M/μ) on a spring of 3.45e+05 N/m and a damper of 1.7e+03 N s/m (f = 128.3
    Hz, η = 3.99)", mode_loss_factor on the upper bound of its range; "The series element as a
    candidate": fitted on all six heights it converges from one start (rms 8.71 N; a spring of
    331 kN/m and a damper of 1.53 kN s/m, τ = 4.6 ms). docs/guides/physics.md: the ball mode's
    fit has k_b = m_b ω² and c_b = ηω m_b in 330–345 kN/m and 1.5–1.7 kN s/m, m_b 0.53 kg at
    η = 4."""
    by_label = {c.label: c for c in selection.candidates}
    mode_fit = by_label["hunt-crossley+ball-mode/momentum"].fit
    mode = mode_fit.model.ball_mode
    mass = float(mode_fit.ball.mass_kg) / float(mode.mode_mass_ratio)
    f, eta = float(mode.mode_frequency_Hz), float(mode.mode_loss_factor)
    omega = 2 * math.pi * f
    assert abs(1e3 * mass - 530) <= 5 and abs(mass - 0.53) <= 0.005, mass
    assert abs(omega**2 * mass - 3.45e5) <= 500, omega**2 * mass
    assert abs(eta * omega * mass - 1.7e3) <= 50, eta * omega * mass
    assert abs(f - 128.3) <= 0.05 and abs(eta - 3.99) <= 0.005, (f, eta)
    assert 329.5e3 <= omega**2 * mass < 345.5e3 and 1.45e3 <= eta * omega * mass < 1.75e3
    assert "mode_loss_factor" in mode_fit.identifiability and "upper bound" in (
        mode_fit.identifiability
    )
    series_fit = by_label["hunt-crossley+series-kelvin-voigt/momentum"].fit
    assert series_fit.converged and series_fit.n_starts == 1
    assert abs(series_fit.residual_rms_N - 8.71) <= 0.005, series_fit.residual_rms_N
    element = series_fit.model.series
    compliance = float(element.series_compliance_m_per_N)
    tau = float(element.series_time_constant_s)
    assert abs(1 / compliance - 331e3) <= 500, 1 / compliance
    assert abs(tau / compliance - 1.53e3) <= 5, tau / compliance
    assert abs(1e3 * tau - 4.6) <= 0.05, tau

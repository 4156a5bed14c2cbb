"""Growth of L_FE per doubling of the drop height (rbjax.studies.growth)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rbjax.spectrum.bands import OCTAVE_BANDS
from rbjax.spectrum.levels import lfe_octave_dB
from rbjax.studies.growth import (
    Growth,
    GrowthError,
    LINEAR_SOURCE_dB,
    growth_per_doubling_dB,
    growth_table,
    model_growth,
    recording_growth,
)

HEIGHTS_M = np.array([0.1, 0.2, 0.4, 0.8, 1.6])


def test_exact_recovery_of_synthetic_lines():
    b = np.array([3.0, 5.0, -1.5, 0.0, 7.25, 15.0])
    a = np.array([80.0, 77.0, 70.0, 60.0, 50.0, 40.0])
    h = np.repeat([0.1, 0.25, 0.5, 1.0, 1.6], 3)  # repeated heights, as for several drops
    lfe = a + np.log2(h)[:, None] * b
    g = growth_per_doubling_dB(h, lfe, OCTAVE_BANDS)
    np.testing.assert_allclose(g.slope_dB, b, atol=1e-12)
    np.testing.assert_allclose(g.intercept_dB, a, atol=1e-12)  # at h_ref = 1 m
    np.testing.assert_allclose(g.stderr_dB, 0.0, atol=1e-12)
    assert g.slope("1000") == pytest.approx(15.0)
    assert list(g.n_points) == [15] * 6
    # the reference height moves the intercept, not the slope
    g2 = growth_per_doubling_dB(h, lfe, ref_height_m=0.1)
    np.testing.assert_allclose(g2.slope_dB, b, atol=1e-12)
    np.testing.assert_allclose(g2.intercept_dB, a + b * math.log2(0.1), atol=1e-12)


def test_standard_error_matches_textbook_formula():
    rng = np.random.default_rng(1)
    h = np.repeat([0.1, 0.2, 0.4, 0.8, 1.6], 5)
    u = np.log2(h)
    y = 60 + 3 * u + rng.normal(0, 0.3, u.size)
    g = growth_per_doubling_dB(h, y)
    # numpy.polyfit's covariance (unscaled=False) is the same s² (XᵀX)⁻¹
    p, cov = np.polyfit(u, y, 1, cov=True)
    assert g.slope_dB[0] == pytest.approx(p[0], rel=1e-12)
    assert g.stderr_dB[0] == pytest.approx(math.sqrt(cov[0, 0]), rel=1e-10)


def test_nan_levels_are_left_out_and_two_points_have_no_stderr():
    h = np.array([0.1, 0.2, 0.4])
    lfe = np.array([[1.0, 10.0], [2.0, np.nan], [3.0, 13.0]])
    g = growth_per_doubling_dB(h, lfe)
    assert g.slope_dB[0] == pytest.approx(1.0)
    assert g.slope_dB[1] == pytest.approx(1.5)
    assert np.isnan(g.stderr_dB[1]) and list(g.n_points) == [3, 2]


@pytest.mark.parametrize(
    "h, lfe, match",
    [
        ([1.0, 1.0, 1.0], [[60.0], [61.0], [59.0]], "two distinct drop heights"),
        ([1.0], [[60.0]], "two distinct drop heights"),
        ([0.5, 1.0], [[60.0, 1.0]], "shape"),
        ([0.0, 1.0], [60.0, 61.0], "heights_m"),
    ],
)
def test_bad_inputs_raise_growth_error(h, lfe, match):
    with pytest.raises(GrowthError, match=match):
        growth_per_doubling_dB(h, lfe)
    assert issubclass(GrowthError, ValueError)


def test_single_height_model_is_refused_before_simulating():
    with pytest.raises(GrowthError, match="two distinct"):
        model_growth([1.0, 1.0])


def test_half_sine_linear_oscillator_grows_3_01_dB_in_every_band():
    # An undamped linear spring-mass contact: F(t) = v0 √(kM) sin(πt/T), T = π√(M/k), independent
    # of v0 = √(2gh): the pulse shape is fixed and F ∝ √h, so |F̂(f)|² ∝ h in every band:
    # 10·log10 2 dB per doubling, exactly.
    rate, k, M = 44_100.0, 49_100.0, 2.5
    T = math.pi * math.sqrt(M / k)
    t = np.arange(44_100) / rate
    v0 = np.sqrt(2 * 9.81 * HEIGHTS_M)
    force = v0[:, None] * math.sqrt(k * M) * np.where(t < T, np.sin(np.pi * t / T), 0.0)[None, :]
    g = growth_per_doubling_dB(HEIGHTS_M, np.asarray(lfe_octave_dB(force, rate)))
    np.testing.assert_allclose(g.slope_dB, LINEAR_SOURCE_dB, atol=1e-9)


@pytest.fixture(scope="module")
def paper_model_growth():
    # the paper's elastic model (gas on) at drop heights 0.1 mm … 1.6 mm and 10 cm … 160 cm
    # (one compilation: same model, same batch shape)
    return model_growth(HEIGHTS_M * 1e-3, label="tiny"), model_growth(HEIGHTS_M, label="paper")


def test_paper_model_is_linear_for_small_drops(paper_model_growth):
    # For drops of 0.1–1.6 mm δ_max is 0.3–1.3 mm, δ_max/2R < 0.8 %: the dynamic mass
    # M(1 − δ/2R), the momentum flux (∝ δ̇²/2R) and the gas force (∝ δ³) are below 1 % of the
    # linear terms, the contact time changes by < 0.2 %, restitution ≈ 1. The impact is then
    # the linear oscillator above, 3.01 dB per doubling in every band. Nonlinear corrections
    # of relative size ε ≈ δ/2R change a band level by O(10·log10(1 + ε)) ≈ 0.03 dB over the
    # whole range, i.e. well below 0.02 dB per doubling; 0.02 dB is the tolerance.
    tiny, _ = paper_model_growth
    np.testing.assert_allclose(tiny.slope_dB, LINEAR_SOURCE_dB, atol=0.02)


def test_paper_model_low_band_grows_about_3_dB(paper_model_growth):
    # 10–160 cm: δ_max/2R reaches 10 %; the 31.5 Hz band (22–45 Hz) lies below the pulse's first
    # notch (≈ 1.5/t_c ≈ 70 Hz), where the spectrum is close to the impulse ∫F dt ∝ v0(1 + e)
    # times a shape factor. Restitution falls by about 0.1 over these four doublings (gas off:
    # 0.96 → 0.86),
    # 20·log10(1.86/1.96)/4 ≈ −0.1 dB per doubling, and the shortening contact (≈ −2 % per
    # doubling) moves the band's shape factor by a similar amount the other way; the paper
    # reads "about 3 dB". Tolerance ±0.2 dB: twice the size of either effect.
    _, jis = paper_model_growth
    assert jis.slope("31.5") == pytest.approx(LINEAR_SOURCE_dB, abs=0.2)
    # and the 63 Hz band, which holds the moving contact resonance, grows faster (paper: ~5 dB)
    assert jis.slope("63") > jis.slope("31.5") + 0.3


def test_recording_growth_of_bundled_recordings():
    g = recording_growth()
    assert isinstance(g, Growth) and g.bands_Hz == OCTAVE_BANDS
    assert list(g.heights_m) == [0.1, 0.2, 0.4, 0.8, 1.0, 1.6]
    assert np.all(g.n_points == 30)
    # 31.5 Hz: the low band grows like a linear source's (paper's measurement: ~3 dB)
    assert g.slope("31.5") == pytest.approx(LINEAR_SOURCE_dB, abs=0.3)
    assert np.all(np.isfinite(g.stderr_dB)) and np.all(g.stderr_dB < 0.5)
    table = growth_table([g])
    assert "31.5 Hz" in table and "recordings" in table
    # docs/guides/fitting.md, "Growth of L_FE per doubling of drop height", the row "emulated
    # recordings (30 drops, 10–160 cm)": slope ± standard error per octave band, as printed
    np.testing.assert_allclose(
        g.slope_dB, [2.97, 3.34, 3.71, 4.39, 4.37, 2.55], rtol=0, atol=0.0051
    )
    np.testing.assert_allclose(
        g.stderr_dB, [0.01, 0.02, 0.03, 0.04, 0.04, 0.05], rtol=0, atol=0.0051
    )


def test_plot_growth_draws_data_and_models():
    from matplotlib.figure import Figure

    from rbjax.plot import plot_growth

    h = np.array([0.1, 0.2, 0.4, 0.8])
    data = growth_per_doubling_dB(
        np.repeat(h, 2),
        60 + 3 * np.log2(np.repeat(h, 2))[:, None] + np.arange(6) + np.tile([0, 0.1], 4)[:, None],
        label="data",
    )
    model = growth_per_doubling_dB(h, 60 + 3 * np.log2(h)[:, None] * np.ones(6), label="model")
    ax = Figure().subplots()
    fig = plot_growth([data, model], ax, paper=[3, 5, 3, 3, 3, 3], title="growth")
    assert fig is ax.figure
    assert sorted(t.get_text() for t in ax.get_legend().get_texts()) == [
        "data",
        "model",
        "paper (≈, §4.2)",
    ]
    with pytest.raises(ValueError, match="empty"):
        plot_growth([], ax)

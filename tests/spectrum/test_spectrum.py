"""rbjax.spectrum: Parseval, IEC 61260-1 bands, L_FE of a half-sine pulse against its
closed-form spectrum, the contact resonance, derivatives, and the per-doubling slope.

References are independent of the code under test: time-domain sums (Parseval), NumPy's
full complex FFT, the closed-form Fourier transform of a half-sine integrated with
scipy.integrate.quad, the IEC 61260-1 formulas written out here, analytic derivatives
and finite differences.
"""

from __future__ import annotations

import functools
import math

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.integrate import quad  # noqa: E402

from rbjax import spectrum as S  # noqa: E402

RATE = 44100  # Hz, the paper's sampling rate (§2.4)
N_1S = 44100  # a 1 s record
T_PULSE = 0.020  # s, contact time of the standard ball
F0 = 1000.0  # N


@functools.partial(jax.jit, static_argnames=("rate_Hz", "n"))
def half_sine(F0_N, T_s, rate_Hz=RATE, n=N_1S):
    """F(t) = F0 sin(pi t / T) on [0, T], zero after (JAX, differentiable in F0 and T)."""
    t = jnp.arange(n) / rate_Hz
    return jnp.where(t <= T_s, F0_N * jnp.sin(jnp.pi * jnp.clip(t, 0.0, T_s) / T_s), 0.0)


def half_sine_psd(f_Hz, F0_N=F0, T_s=T_PULSE):
    """Two-sided |F(f)|² of the half-sine, (N·s)²: (2F0T/pi)² cos²(pi f T)/(1 - 4f²T²)²,
    with its finite limit (F0 T/2)² at f = 1/(2T)."""
    den = 1.0 - 4.0 * f_Hz**2 * T_s**2
    if abs(den) < 1e-9:
        return (F0_N * T_s / 2.0) ** 2
    return (2.0 * F0_N * T_s / math.pi) ** 2 * math.cos(math.pi * f_Hz * T_s) ** 2 / den**2


def half_sine_band_energy(lo_Hz, hi_Hz, F0_N=F0, T_s=T_PULSE):
    """One-sided energy in [lo, hi]: 2 ∫ |F(f)|² df (scipy quad)."""
    value, _ = quad(
        half_sine_psd, lo_Hz, hi_Hz, args=(F0_N, T_s), limit=400, epsabs=0.0, epsrel=1e-11
    )
    return 2.0 * value


def iec_edges(fraction, band_numbers):
    """IEC 61260-1:2014 written out: f_m = 1000·10^(0.3 x/b), edges f_m·10^(∓0.3/(2b))."""
    x = np.asarray(band_numbers, dtype=float)
    fm = 1000.0 * 10.0 ** (0.3 * x / fraction)
    return fm, fm * 10.0 ** (-0.3 / (2 * fraction)), fm * 10.0 ** (0.3 / (2 * fraction))


OCTAVE_X = range(-5, 1)  # 31.5 Hz ... 1 kHz
THIRD_X = range(-16, 2)  # 25 Hz ... 1.25 kHz


@pytest.fixture(scope="module")
def pulse():
    return np.asarray(half_sine(F0, T_PULSE))


# --------------------------------------------------------------------------------------
# Parseval
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [4410, 4411])
def test_energy_spectrum_integrates_to_time_domain_energy(n):
    """sum(E)·Δf = ∫F² dt = sum(F²)/rate for even and odd n (DC/Nyquist handled)."""
    rng = np.random.default_rng(n)
    force = rng.standard_normal(n) * 100.0 + 30.0  # with a DC offset
    freq, esd = S.energy_spectrum(force, RATE)
    assert freq.shape == esd.shape == (n // 2 + 1,)
    delta_f = RATE / n
    np.testing.assert_allclose(freq, np.arange(n // 2 + 1) * delta_f, rtol=1e-14)
    np.testing.assert_allclose(float(jnp.sum(esd)) * delta_f, np.sum(force**2) / RATE, rtol=1e-12)


@pytest.mark.parametrize("n", [4410, 4411])
def test_energy_spectrum_is_folded_two_sided_spectrum(n):
    """Each one-sided bin holds |X(f)|² + |X(-f)|² (NumPy's full complex FFT), X = DFT/rate."""
    rng = np.random.default_rng(1 + n)
    force = rng.standard_normal(n)
    two_sided = np.abs(np.fft.fft(force) / RATE) ** 2
    folded = two_sided[: n // 2 + 1].copy()
    folded[1:] += two_sided[::-1][: n // 2]  # X(-f_k) = X_{n-k}
    if n % 2 == 0:
        folded[-1] = two_sided[n // 2]  # the Nyquist bin is its own mirror
    _, esd = S.energy_spectrum(force, RATE)
    np.testing.assert_allclose(esd, folded, rtol=1e-10, atol=1e-22)


def test_lfe_total_is_eq11(pulse):
    """L_FE = 10 log10(∫F²dt / (T0 F0²)); a half-sine of F0, T has ∫F² = F0² T/2."""
    expected = 10 * np.log10(np.sum(pulse**2) / RATE)
    assert float(S.lfe_total_dB(pulse, RATE)) == pytest.approx(expected, abs=1e-12)
    assert float(S.lfe_total_dB(pulse, RATE)) == pytest.approx(
        10 * np.log10(F0**2 * T_PULSE / 2), abs=1e-9
    )
    assert float(S.lfe_dB(4.0, T0_s=2.0, F0_N=2.0)) == pytest.approx(10 * np.log10(0.5), abs=1e-14)


@pytest.mark.parametrize("n", [44100, 44101])
def test_contiguous_bands_tiling_0_to_nyquist_add_up_to_total(n):
    rng = np.random.default_rng(7)
    force = rng.standard_normal((2, n))
    _, lo_oct, hi_oct = iec_edges(1, OCTAVE_X)
    cuts = np.concatenate([[0.0, 3.3, 17.0], lo_oct, [hi_oct[-1], 5000.0, RATE / 2 + 1.0]])
    energies = S.band_energies_N2s(force, RATE, cuts[:-1], cuts[1:])
    assert energies.shape == (2, cuts.size - 1)
    total = np.sum(force**2, axis=-1) / RATE
    np.testing.assert_allclose(jnp.sum(energies, axis=-1), total, rtol=1e-12)
    np.testing.assert_allclose(
        S.lfe_dB(jnp.sum(energies, axis=-1)), S.lfe_total_dB(force, RATE), atol=1e-10
    )


def test_band_membership_is_half_open():
    """A bin exactly on an edge belongs to the band above it (lower <= f < upper)."""
    n = 100  # Δf = 441 Hz
    force = np.zeros(n)
    force[0] = 1.0  # flat spectrum: every bin the same
    freq, esd = S.energy_spectrum(force, RATE)
    e = S.band_energies_N2s(force, RATE, [0.0, 441.0], [441.0, 1323.0])
    delta_f = RATE / n
    # band 1 = bin 0 (DC); band 2 = bins 1 and 2 (441 and 882 Hz), not bin 3 (1323 Hz)
    np.testing.assert_allclose(e, [esd[0] * delta_f, (esd[1] + esd[2]) * delta_f], rtol=1e-14)


def test_batching_on_leading_axes(pulse):
    batch = np.stack([pulse, 0.5 * pulse, np.roll(pulse, 300)]).reshape(3, 1, -1)
    got = S.lfe_octave_dB(batch, RATE)
    assert got.shape == (3, 1, len(S.OCTAVE_BANDS))
    for i in range(3):
        np.testing.assert_allclose(got[i, 0], S.lfe_octave_dB(batch[i, 0], RATE), atol=1e-10)
    # halving the force lowers every band by 20 log10 2
    np.testing.assert_allclose(got[0, 0] - got[1, 0], 20 * np.log10(2), atol=1e-10)
    # a delay changes the phase only
    np.testing.assert_allclose(got[2, 0], got[0, 0], atol=1e-9)
    vmapped = jax.jit(jax.vmap(lambda f: S.lfe_octave_dB(f, 44100.0)))(batch[:, 0])
    np.testing.assert_allclose(vmapped, got[:, 0], atol=1e-10)


# --------------------------------------------------------------------------------------
# half-sine against its closed-form spectrum
# --------------------------------------------------------------------------------------


def _bin_cell(lo_Hz, hi_Hz, delta_f_Hz):
    """The frequency interval covered by the bins k with lo <= kΔf < hi (each bin standing
    for [kΔf - Δf/2, kΔf + Δf/2]): what an ideal filter on a Δf-resolution spectrum sees."""
    k_first = math.ceil(lo_Hz / delta_f_Hz)
    k_last = math.ceil(hi_Hz / delta_f_Hz) - 1
    return (k_first - 0.5) * delta_f_Hz, (k_last + 0.5) * delta_f_Hz


@pytest.mark.parametrize("fraction,band_numbers", [(1, OCTAVE_X), (3, THIRD_X)])
def test_half_sine_band_energies_match_closed_form(pulse, fraction, band_numbers):
    """Band energies of the sampled 1 s record (44.1 kHz) against 2∫|F(f)|²df of the
    continuous half-sine over the same bins (quad).

    Tolerance 0.05 dB: the sampled pulse's DTFT is the continuous transform plus its
    aliases (Poisson summation). The half-sine has kinks at both ends, so |F| decays only
    as f⁻², and the aliases at 44.1 kHz ∓ f shift the energy below 1.4 kHz by about
    2·2(f/rate)² ≈ 0.5 %, i.e. ≲ 0.03 dB; the midpoint rule over 1 Hz bins adds
    ~(πTΔf)²/12 ≈ 3e-5. Observed: ≤ 0.013 dB (octaves), ≤ 0.023 dB (1.25 kHz third).
    """
    _, lo, hi = iec_edges(fraction, band_numbers)
    got = np.asarray(S.band_energies_N2s(pulse, RATE, lo, hi))
    cells = [_bin_cell(a, b, RATE / N_1S) for a, b in zip(lo, hi)]
    expected = np.array([half_sine_band_energy(a, b) for a, b in cells])
    np.testing.assert_allclose(10 * np.log10(got / expected), 0.0, atol=0.05)


def test_half_sine_lfe_octave_against_closed_form_nominal_edges(pulse):
    """lfe_octave_dB against the closed form over the exact IEC edges. Beyond the 0.05 dB
    above, the 1 Hz bins move each edge by up to half a bin: for the 31.5 Hz octave
    (22.4-44.7 Hz, 22 bins) up to ~2·0.5/22 ≈ 4.5 % of its energy (0.2 dB); bound it
    per band from the closed form and check the code stays inside."""
    _, lo, hi = iec_edges(1, OCTAVE_X)
    got = np.asarray(S.lfe_octave_dB(pulse, RATE))
    for i, (a, b) in enumerate(zip(lo, hi)):
        exact = half_sine_band_energy(a, b)
        edge_slack = 0.5 * (half_sine_psd(a) + half_sine_psd(b)) * 2.0 * 2.0  # 2 sided, ≤ 1/2 bin
        tol_dB = 10 * np.log10(1 + edge_slack / exact) + 0.05
        assert abs(got[i] - 10 * np.log10(exact)) <= tol_dB, (S.OCTAVE_BANDS[i], got[i], tol_dB)
    np.testing.assert_allclose(got, S.lfe_dB(S.band_energies_N2s(pulse, RATE, lo, hi)), atol=1e-12)


def test_lfe_third_octave_uses_iec_thirds(pulse):
    _, lo, hi = iec_edges(3, THIRD_X)
    got = S.lfe_third_octave_dB(pulse, RATE)
    assert got.shape == (len(S.THIRD_OCTAVE_BANDS),)
    np.testing.assert_allclose(
        got, 10 * np.log10(S.band_energies_N2s(pulse, RATE, lo, hi)), atol=1e-12
    )
    # three thirds make an octave (the edges coincide): energies add up
    oct_e = 10 ** (np.asarray(S.lfe_octave_dB(pulse, RATE)) / 10)
    thirds_e = 10 ** (np.asarray(got) / 10)  # (25, 31.5, 40) make the 31.5 Hz octave, ...
    np.testing.assert_allclose(thirds_e.reshape(6, 3).sum(1), oct_e, rtol=1e-10)


def test_force_spectrum_dB_matches_fft_and_closed_form(pulse):
    freq, level = S.force_spectrum_dB(pulse, RATE)
    np.testing.assert_allclose(freq, np.fft.rfftfreq(N_1S, 1 / RATE), rtol=1e-13)
    with np.errstate(divide="ignore"):
        ref = 20 * np.log10(np.abs(np.fft.rfft(pulse)) / RATE)
    ok = np.isfinite(ref) & (ref > -200)  # off the exact zeros
    np.testing.assert_allclose(level[ok], ref[ok], atol=1e-8)
    # arbitrary frequencies (a 0.1 Hz grid is possible): the closed form, off its zeros
    f_any = np.array([0.0, 10.05, 33.3, 61.7, 120.25, 333.3])
    f_out, level_any = S.force_spectrum_dB(pulse, RATE, f_any)
    np.testing.assert_allclose(f_out, f_any)
    closed = np.array([10 * np.log10(half_sine_psd(f)) for f in f_any])
    # aliases F(f ∓ rate) add a relative ~2(f/rate)²/|cos(pi f T)| ≈ 1e-4 at 333 Hz
    np.testing.assert_allclose(level_any, closed, atol=5e-3)
    # on the bins, the DTFT equals the FFT
    _, on_bins = S.force_spectrum_dB(pulse, RATE, freq[10:16])
    np.testing.assert_allclose(on_bins, level[10:16], atol=1e-9)


# --------------------------------------------------------------------------------------
# contact resonance (first notch) of a half-sine: 1.5/T
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("T_s", [0.020, 0.0213, 0.02001])
def test_contact_resonance_of_half_sine(T_s):
    """First spectral zero of a half-sine of duration T at 1.5/T (off the 0.1 Hz grid for
    T = 21.3 ms: 70.4225... Hz; the refinement must beat the grid)."""
    f = float(S.contact_resonance_Hz(half_sine(F0, T_s), RATE))
    assert f == pytest.approx(1.5 / T_s, abs=0.01)


def test_contact_resonance_batched_and_range():
    T = jnp.array([0.0227, 0.0205])  # 66 Hz and 73 Hz (paper §4.2, Fig. 12)
    forces = jax.vmap(lambda T_s: half_sine(F0, T_s))(T)
    f = S.contact_resonance_Hz(forces, RATE)
    assert f.shape == (2,)
    np.testing.assert_allclose(f, 1.5 / np.asarray(T), atol=0.05)
    # the second zero is at 2.5/T: searching above the first finds it
    f2 = S.contact_resonance_Hz(forces, RATE, fmin_Hz=90.0, fmax_Hz=200.0)
    np.testing.assert_allclose(f2, 2.5 / np.asarray(T), atol=0.05)
    # a band with no notch gives NaN
    assert np.isnan(float(S.contact_resonance_Hz(forces[0], RATE, fmin_Hz=20.0, fmax_Hz=40.0)))


def test_contact_resonance_gradient():
    """d(1.5/T)/dT = -1.5/T²."""
    T_s = 0.02001
    g = jax.jit(jax.grad(lambda T: S.contact_resonance_Hz(half_sine(F0, T), RATE)))(T_s)
    assert float(g) == pytest.approx(-1.5 / T_s**2, rel=1e-3)


# --------------------------------------------------------------------------------------
# IEC 61260-1:2014 bands
# --------------------------------------------------------------------------------------


def test_octave_mid_band_frequencies_are_exact_base_ten():
    fm, lo, hi = iec_edges(1, OCTAVE_X)
    got = S.band_centres_Hz(1, 31.5, 1000.0)
    np.testing.assert_allclose(got, fm, rtol=1e-14)
    np.testing.assert_allclose(np.round(got, 2), [31.62, 63.10, 125.89, 251.19, 501.19, 1000.0])
    g_lo, g_hi = S.band_edges_Hz(1, 31.5, 1000.0)
    np.testing.assert_allclose(g_lo, lo, rtol=1e-14)
    np.testing.assert_allclose(g_hi, hi, rtol=1e-14)
    np.testing.assert_allclose(g_hi / g_lo, 10**0.3, rtol=1e-14)  # G
    np.testing.assert_allclose(np.sqrt(g_lo * g_hi), got, rtol=1e-14)


def test_third_octave_mid_band_frequencies_are_exact_base_ten():
    fm, lo, hi = iec_edges(3, THIRD_X)
    np.testing.assert_allclose(S.band_centres_Hz(3, 25.0, 1250.0), fm, rtol=1e-14)
    g_lo, g_hi = S.band_edges_Hz(3, 25.0, 1250.0)
    np.testing.assert_allclose(g_lo, lo, rtol=1e-14)
    np.testing.assert_allclose(g_hi / g_lo, 10**0.1, rtol=1e-14)  # G^(1/3)


@pytest.mark.parametrize("fraction,fmin,fmax", [(1, 31.5, 1000.0), (3, 25.0, 1250.0)])
def test_band_edges_tile(fraction, fmin, fmax):
    lo, hi = S.band_edges_Hz(fraction, fmin, fmax)
    np.testing.assert_allclose(hi[:-1], lo[1:], rtol=1e-14)


def test_nominal_labels_as_in_the_standard():
    assert S.nominal_centres_Hz(1, 31.5, 1000.0) == ["31.5", "63", "125", "250", "500", "1000"]
    assert list(S.OCTAVE_BANDS) == ["31.5", "63", "125", "250", "500", "1000"]
    thirds = ["25", "31.5", "40", "50", "63", "80", "100", "125", "160", "200", "250",
              "315", "400", "500", "630", "800", "1000", "1250"]  # fmt: skip
    assert S.nominal_centres_Hz(3, 25.0, 1250.0) == thirds
    assert list(S.THIRD_OCTAVE_BANDS) == thirds
    assert S.nominal_centres_Hz(1, 16.0, 16000.0) == [
        "16", "31.5", "63", "125", "250", "500", "1000", "2000", "4000", "8000", "16000"
    ]  # fmt: skip
    assert S.nominal_centres_Hz(3, 10.0, 20.0) == ["10", "12.5", "16", "20"]
    # selection by nominal frequency: [31.5, 1000] includes 31.62 Hz and 1000 Hz
    assert len(S.band_centres_Hz(1, 40.0, 999.0)) == 4


def test_band_table_validation():
    with pytest.raises(ValueError, match="fraction"):
        S.band_centres_Hz(2, 31.5, 1000.0)
    with pytest.raises(ValueError, match="fmax_Hz"):
        S.band_edges_Hz(1, 1000.0, 31.5)
    with pytest.raises(ValueError, match="fmin_Hz"):
        S.nominal_centres_Hz(1, float("nan"), 1000.0)


def test_input_validation():
    with pytest.raises(ValueError, match="rate_Hz"):
        S.lfe_octave_dB(np.ones(10), 0.0)
    with pytest.raises(ValueError, match="force_N"):
        S.energy_spectrum(1.0, RATE)
    with pytest.raises(ValueError, match="lower_Hz"):
        S.band_energies_N2s(np.ones(10), RATE, [10.0, 20.0], [20.0])
    with pytest.raises(ValueError, match="band edges"):
        S.band_energies_N2s(np.ones(10), RATE, [10.0], [5.0])
    with pytest.raises(ValueError, match="fmax_Hz"):
        S.contact_resonance_Hz(np.ones(100), RATE, fmin_Hz=50.0, fmax_Hz=30.0)


# --------------------------------------------------------------------------------------
# differentiability
# --------------------------------------------------------------------------------------


def test_grad_lfe_octave_wrt_amplitude_is_analytic():
    """L_FE = 20 log10 F0 + const in every band: d/dF0 = 20/(F0 ln 10)."""
    F0_N = 700.0
    jac = jax.jit(jax.jacfwd(lambda a: S.lfe_octave_dB(half_sine(a, T_PULSE), RATE)))(F0_N)
    np.testing.assert_allclose(jac, np.full(6, 20 / (F0_N * np.log(10))), rtol=1e-10)
    g = jax.jit(jax.grad(lambda a: S.lfe_octave_dB(half_sine(a, T_PULSE), RATE)[1]))(F0_N)
    assert float(g) == pytest.approx(20 / (F0_N * np.log(10)), rel=1e-10)


def test_grad_lfe_octave_wrt_duration_matches_finite_differences():
    """T = 20.01 ms: T·rate = 882.44, so T ± 1e-7 s moves no sample across the pulse end
    (the sampled L_FE is smooth there) and central differences are O(h²) accurate."""
    T_s, h = 0.02001, 1e-7

    @jax.jit
    def lfe(T):  # the 6 octaves and the 63 Hz third
        force = half_sine(F0, T)
        return jnp.append(S.lfe_octave_dB(force, RATE), S.lfe_third_octave_dB(force, RATE)[4])

    jac = np.asarray(jax.jit(jax.jacfwd(lfe))(T_s))
    fd = (np.asarray(lfe(T_s + h)) - np.asarray(lfe(T_s - h))) / (2 * h)
    np.testing.assert_allclose(jac, fd, rtol=1e-5, atol=1e-3)
    g_third = jax.jit(jax.grad(lambda T: lfe(T)[-1]))(T_s)
    assert float(g_third) == pytest.approx(float(fd[-1]), rel=1e-5)


def test_grad_lfe_total_wrt_samples():
    """d/dF_n of 10 log10(sum F²/rate) = 20 F_n / (ln 10 · sum F²)."""
    rng = np.random.default_rng(3)
    force = rng.standard_normal(257)
    g = jax.jit(jax.grad(lambda f: S.lfe_total_dB(f, RATE)))(force)
    np.testing.assert_allclose(g, 20 * force / (np.log(10) * np.sum(force**2)), rtol=1e-10)

    # and through the band filter: the bands tile 0..Nyquist, so they sum to the total
    def total_from_bands(f):
        return 10 * jnp.log10(jnp.sum(S.band_energies_N2s(f, RATE, [0.0, 1000.0], [1000.0, RATE])))

    np.testing.assert_allclose(jax.jit(jax.grad(total_from_bands))(force), g, rtol=1e-9)


# --------------------------------------------------------------------------------------
# increase per doubling of drop height (paper Figs. 10-11)
# --------------------------------------------------------------------------------------


def test_lfe_increase_per_doubling_known_slopes():
    h = np.array([0.1, 0.2, 0.4, 0.8, 1.0, 1.2, 1.6])
    slopes = np.array([3.0, 5.0, 3.0, 7.5, 12.0, 14.9])
    intercepts = np.array([39.0, 31.0, 23.0, 17.0, 12.5, 5.0])
    lfe = intercepts + np.log2(h)[:, None] * slopes  # (heights, bands)
    got = S.lfe_increase_per_doubling_dB(h, lfe)
    np.testing.assert_allclose(got, slopes, rtol=1e-12)
    np.testing.assert_allclose(
        S.lfe_increase_per_doubling_dB(h, lfe, ref_height_m=0.1), slopes, rtol=1e-12
    )
    # with scatter: the least-squares slope, as np.polyfit computes it
    rng = np.random.default_rng(0)
    noisy = lfe + rng.normal(0, 0.5, lfe.shape)
    ref = np.polyfit(np.log2(h), noisy, 1)[0]
    np.testing.assert_allclose(S.lfe_increase_per_doubling_dB(h, noisy), ref, rtol=1e-10)


def test_lfe_increase_per_doubling_linear_source_is_3dB():
    """Force ∝ impact speed ∝ sqrt(h) (Eq. 10) at a fixed pulse shape: energy ∝ h, so
    10 log10 2 = 3.01 dB per doubling in every band (paper §4.2)."""
    h = np.array([0.1, 0.2, 0.4, 0.8, 1.2, 1.6])
    forces = np.sqrt(h)[:, None] * np.asarray(half_sine(F0, T_PULSE))[None, :]
    lfe = S.lfe_octave_dB(forces, RATE)
    np.testing.assert_allclose(S.lfe_increase_per_doubling_dB(h, lfe), 10 * np.log10(2), rtol=1e-9)
    one_band = S.lfe_increase_per_doubling_dB(h, lfe[:, 0])
    assert one_band.shape == ()


def test_lfe_increase_per_doubling_validation():
    with pytest.raises(ValueError, match="height_m"):
        S.lfe_increase_per_doubling_dB([1.0, 2.0], np.zeros((3, 6)))
    with pytest.raises(ValueError, match="height_m"):
        S.lfe_increase_per_doubling_dB([1.0, -2.0], np.zeros(2))
    with pytest.raises(ValueError, match="height_m"):
        S.lfe_increase_per_doubling_dB([1.0, 1.0], np.zeros(2))

"""rbjax.spectrum with ``n_record``: band energies and L_FE of a long record from its first
(non-zero) samples, the rest of the record being zero.

References are independent of the code under test: NumPy's rfft of the explicitly
zero-padded record with band masks and one-sided weights written out here, the time-domain
energy (Parseval), and central finite differences.
"""

from __future__ import annotations

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from rbjax import spectrum as S  # noqa: E402
from rbjax.spectrum import band_kernel  # noqa: E402

RATE = 44100.0  # Hz
N_1S = 44100  # the paper's 1 s record
OCTAVE_X = range(-5, 1)  # 31.5 Hz ... 1 kHz
THIRD_X = range(-16, 2)  # 25 Hz ... 1.25 kHz


def iec_edges(fraction, band_numbers):
    """IEC 61260-1:2014 base-ten band edges f_m·10^(∓0.3/(2b)), f_m = 1000·10^(0.3 x/b)."""
    fm = 1000.0 * 10.0 ** (0.3 * np.asarray(band_numbers, dtype=float) / fraction)
    half = 10.0 ** (0.3 / (2 * fraction))
    return fm / half, fm * half


def padded_band_energies(x, n_record, lower, upper, rate=RATE):
    """∫F_band² dt of the record zero-padded to n_record samples: NumPy rfft, one-sided
    weights (1 at DC and, for even n_record, Nyquist), bins lower <= f < upper."""
    x = np.asarray(x, dtype=float)
    zeros = np.zeros(x.shape[:-1] + (n_record - x.shape[-1],))
    spectrum = np.fft.rfft(np.concatenate([x, zeros], axis=-1), axis=-1)
    freq = np.fft.rfftfreq(n_record, 1.0 / rate)
    weight = np.full(freq.size, 2.0)
    weight[0] = 1.0
    if n_record % 2 == 0:
        weight[-1] = 1.0
    esd = weight * np.abs(spectrum) ** 2 / rate**2  # (N²·s)/Hz per bin
    per_band = [
        np.sum(esd[..., (freq >= lo) & (freq < hi)], axis=-1) for lo, hi in zip(lower, upper)
    ]
    return np.stack(per_band, axis=-1) * (rate / n_record)


def half_sine(n, T_s, F0_N=1000.0):
    t = np.arange(n) / RATE
    return np.where(t <= T_s, F0_N * np.sin(np.pi * np.clip(t, 0.0, T_s) / T_s), 0.0)


def records(kind, shape, n):
    """Random records, or half-sine pulses (5.5 ms in 256 samples) with a 400 Hz ringing."""
    rng = np.random.default_rng(n + len(shape))
    if kind == "random":
        return rng.standard_normal(shape + (n,)) * 100.0 + 20.0
    t = np.arange(n) / RATE
    pulse = half_sine(n, 0.95 * n / RATE) * (1.0 + 0.3 * np.sin(2 * np.pi * 400.0 * t))
    return pulse * rng.uniform(0.5, 2.0, shape + (1,))


# --------------------------------------------------------------------------------------
# against NumPy on the explicitly zero-padded record
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["random", "pulse"])
@pytest.mark.parametrize(
    "n_record",
    [256, 257, 600, 769, 2049, N_1S, N_1S + 1],  # = n, short pads (padded FFT), long ones
)
def test_band_energies_equal_the_zero_padded_record(kind, n_record):
    """Octave and third-octave band energies of 256 samples in an n_record-sample record
    (odd and even n_record, n_record = n), batch shape (2, 3), rtol 1e-12."""
    n = 256
    if n_record < n:
        pytest.skip("n_record < n")
    x = records(kind, (2, 3), n)
    for fraction, numbers in [(1, OCTAVE_X), (3, THIRD_X)]:
        lower, upper = iec_edges(fraction, numbers)
        expected = padded_band_energies(x, n_record, lower, upper)
        got = S.band_energies_N2s(x, RATE, lower, upper, n_record=n_record)
        assert got.shape == (2, 3, len(lower))
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0.0)


@pytest.mark.parametrize(
    "n,n_record", [(1, 10), (2, 7), (3, 44100), (37, 44101), (300, 1000), (513, 44100)]
)
def test_band_energies_small_and_odd_pulses(n, n_record):
    """Short and odd pulse lengths (odd FFT sizes inside), bands from DC to past Nyquist."""
    x = records("random", (2,), n)
    cuts = np.array([0.0, 3.0, 20.0, 150.0, 1000.0, 5000.0, RATE / 2 + 1.0])
    expected = padded_band_energies(x, n_record, cuts[:-1], cuts[1:])
    got = S.band_energies_N2s(x, RATE, cuts[:-1], cuts[1:], n_record=n_record)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0.0)


def test_lfe_levels_equal_the_zero_padded_record():
    x = records("pulse", (4,), 300)
    for fn, fraction, numbers in [
        (S.lfe_octave_dB, 1, OCTAVE_X),
        (S.lfe_third_octave_dB, 3, THIRD_X),
    ]:
        expected = 10 * np.log10(padded_band_energies(x, N_1S, *iec_edges(fraction, numbers)))
        np.testing.assert_allclose(fn(x, RATE, n_record=N_1S), expected, rtol=0.0, atol=1e-11)
    total = 10 * np.log10(np.sum(x**2, axis=-1) / RATE)
    np.testing.assert_allclose(S.lfe_total_dB(x, RATE, n_record=N_1S), total, atol=1e-12)


def test_energy_spectrum_of_the_zero_padded_record():
    x = records("random", (2,), 100)
    freq, esd = S.energy_spectrum(x, RATE, n_record=1001)
    np.testing.assert_allclose(freq, np.fft.rfftfreq(1001, 1.0 / RATE), rtol=1e-14)
    delta_f = RATE / 1001
    bins = np.stack([freq - delta_f / 2, freq + delta_f / 2], axis=-1)  # one bin per band
    expected = padded_band_energies(x, 1001, bins[:, 0], bins[:, 1]) / delta_f
    np.testing.assert_allclose(esd, expected, rtol=1e-10, atol=1e-12 * np.max(expected))


def test_jit_vmap_and_traced_rate():
    """Under jit/vmap (concrete rate) and with the rate traced (padded FFT inside): the same
    numbers as NumPy on the padded record."""
    x = records("pulse", (3,), 256)
    expected = 10 * np.log10(padded_band_energies(x, N_1S, *iec_edges(1, OCTAVE_X)))
    vmapped = jax.jit(jax.vmap(lambda f: S.lfe_octave_dB(f, RATE, n_record=N_1S)))(x)
    np.testing.assert_allclose(vmapped, expected, atol=1e-11)
    traced_rate = jax.jit(lambda f, r: S.lfe_octave_dB(f, r, n_record=N_1S))(x, RATE)
    np.testing.assert_allclose(traced_rate, expected, atol=1e-11)


def test_large_batch_in_blocks():
    """A batch bigger than one block of the short FFT (3 × 40 records of 1024 samples:
    blocks of 85 and a remainder), under jit and grad."""
    x = records("pulse", (3, 40), 1024)
    lower, upper = iec_edges(1, OCTAVE_X)
    expected = padded_band_energies(x, 8000, lower, upper)
    got = jax.jit(lambda f: S.band_energies_N2s(f, RATE, lower, upper, n_record=8000))(x)
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    grad = jax.grad(lambda f: jnp.sum(S.band_energies_N2s(f, RATE, lower, upper, n_record=8000)))(x)
    one = jax.grad(lambda f: jnp.sum(S.band_energies_N2s(f, RATE, lower, upper, n_record=8000)))(
        x[2, 7]
    )
    np.testing.assert_allclose(grad[2, 7], one, rtol=1e-12, atol=1e-12 * np.max(np.abs(one)))


def test_kernel_too_large_falls_back_to_the_padded_fft(monkeypatch):
    monkeypatch.setattr(band_kernel, "KERNEL_MAX_TERMS", 0)
    band_kernel.band_kernel.cache_clear()
    try:
        x = records("random", (2,), 64)
        lower, upper = iec_edges(1, OCTAVE_X)
        got = S.band_energies_N2s(x, RATE, lower, upper, n_record=5000)
        np.testing.assert_allclose(got, padded_band_energies(x, 5000, lower, upper), rtol=1e-12)
    finally:
        band_kernel.band_kernel.cache_clear()


# --------------------------------------------------------------------------------------
# Parseval
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("n,n_record", [(64, N_1S + 1), (256, N_1S), (256, 1000), (256, 600)])
def test_bands_tiling_0_to_nyquist_add_up_to_the_energy(n, n_record):
    x = records("pulse", (2,), n) + records("random", (2,), n)
    lower, upper = iec_edges(1, OCTAVE_X)
    cuts = np.concatenate([[0.0, 3.3, 17.0], lower, [upper[-1], 5000.0, RATE / 2 + 1.0]])
    energies = S.band_energies_N2s(x, RATE, cuts[:-1], cuts[1:], n_record=n_record)
    np.testing.assert_allclose(jnp.sum(energies, axis=-1), np.sum(x**2, axis=-1) / RATE, rtol=1e-12)


# --------------------------------------------------------------------------------------
# derivatives
# --------------------------------------------------------------------------------------


def test_grad_octave_lfe_wrt_samples_matches_finite_differences():
    x = records("pulse", (), 256)
    band = 3  # 250 Hz

    def lfe(f):
        return S.lfe_octave_dB(f, RATE, n_record=N_1S)[band]

    grad = np.asarray(jax.jit(jax.grad(lfe))(x))
    rng = np.random.default_rng(11)
    samples = np.concatenate([[0, 255], rng.choice(np.arange(1, 255), 8, replace=False)])
    h = 1e-2  # N; the samples are ~1e3 N
    for m in samples:
        step = np.zeros_like(x)
        step[m] = h
        fd = (float(lfe(x + step)) - float(lfe(x - step))) / (2 * h)
        assert grad[m] == pytest.approx(fd, rel=1e-6, abs=1e-9 * np.max(np.abs(grad)))
    jac = jax.jit(jax.jacfwd(lambda f: S.lfe_octave_dB(f, RATE, n_record=N_1S)))(x)
    np.testing.assert_allclose(jac[band], grad, rtol=1e-10, atol=1e-14)


# --------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [255, 0, -1, 44100.0, 300.5, True, "44100", None])
def test_bad_n_record_is_named_with_its_value_and_range(bad):
    x = np.ones(256)
    lower, upper = iec_edges(1, OCTAVE_X)
    calls = [
        lambda **kw: S.band_energies_N2s(x, RATE, lower, upper, **kw),
        lambda **kw: S.lfe_octave_dB(x, RATE, **kw),
        lambda **kw: S.lfe_third_octave_dB(x, RATE, **kw),
        lambda **kw: S.lfe_total_dB(x, RATE, **kw),
        lambda **kw: S.energy_spectrum(x, RATE, **kw),
    ]
    for call in calls:
        if bad is None:  # the default: the record as given
            call(n_record=bad)
            continue
        with pytest.raises(ValueError, match=r"n_record=.*must be an integer") as info:
            call(n_record=bad)
        assert repr(bad) in str(info.value) and "[256, inf)" in str(info.value)

"""The finite slab (``rbjax.room.finite_slab``, ``rbjax.room.mode_radiation``) against
references written here with numpy/scipy only: the modes of a simply supported plate in closed
form (Leissa 1969, §4.1), each mode's radiation efficiency by ``scipy.integrate.dblquad`` of
Wallace's (1972) integral in its printed form, the band energies by ``scipy.integrate.quad`` of
E_F Re Y_k with E_F from the samples' DTFT, and the infinite plate's band energy E_F,b/Z
(Cremer, Heckl & Petersson §5.3) for a large slab. No rbjax code enters a reference.

The force is a half-sine of 20 ms and 1.5 kN (the rubber ball's order: JIS A 1418-2), so no
impact is solved here; the chain's tests (``test_chain.py``) carry the ball's force.
"""

import math

import jax
import numpy as np
import pytest
import scipy.integrate as si

from rbjax.room import Chain, Slab
from rbjax.room.finite_slab import modal_band_energies_J, mode_indices, mode_orders, slab_modes
from rbjax.room.mode_radiation import mode_radiation_efficiency

RATE = 44100.0
C0, RHO0 = 343.0, 1.21  # ISO 12354-1 air
CONCRETE = dict(youngs_Pa=33e9, density_kg_per_m3=2300.0, poisson=0.2)  # C30/37 (materials.py)


def _force():
    t = np.arange(900) / RATE
    return np.where(t < 0.02, 1500.0 * np.sin(np.pi * t / 0.02), 0.0)


def _esd(force, f):
    """2|F(f)|², F the DTFT of the samples over the rate (numpy)."""
    n = np.arange(force.size)
    spec = np.exp(-2j * np.pi * np.outer(np.atleast_1d(f), n) / RATE) @ force / RATE
    return 2.0 * np.abs(spec) ** 2


def _re_y(f, fk, eta, inverse_mass):
    w, wk = 2 * np.pi * f, 2 * np.pi * fk
    return inverse_mass * eta * wk * w**2 / ((wk**2 - w**2) ** 2 + (eta * wk * w) ** 2)


def _wallace(f, m, n, a, b):
    """σ_mn by scipy's dblquad of Wallace (1972) Eq. 6 as printed (cos for odd, sin for even)."""
    k = 2 * math.pi * f / C0

    def integrand(theta, phi):
        al = k * a * math.sin(theta) * math.cos(phi)
        be = k * b * math.sin(theta) * math.sin(phi)
        fa = (math.cos(al / 2) if m % 2 else math.sin(al / 2)) / ((al / (m * math.pi)) ** 2 - 1)
        fb = (math.cos(be / 2) if n % 2 else math.sin(be / 2)) / ((be / (n * math.pi)) ** 2 - 1)
        return (fa * fb) ** 2 * math.sin(theta)

    value = si.dblquad(integrand, 0, math.pi / 2, 0, math.pi / 2, epsabs=0, epsrel=1e-11)[0]
    return 64 * k**2 * a * b / (math.pi**6 * m**2 * n**2) * value


@pytest.mark.parametrize(
    ("freq", "m", "n", "rtol"),
    [(30.0, 1, 1, 1e-8), (60.0, 2, 1, 1e-8), (80.0, 1, 3, 1e-8), (100.0, 3, 3, 1e-8)]
    + [(450.0, 6, 6, 1e-4)],
)
def test_mode_radiation_efficiency_against_wallace_by_dblquad(freq, m, n, rtol):
    # ka, kb ≤ 10 for the modal bands of a 4 m × 5 m slab; ka ≈ 33 at 450 Hz
    got = float(mode_radiation_efficiency(freq, m, n, 4.0, 5.0))
    assert got == pytest.approx(_wallace(freq, m, n, 4.0, 5.0), rel=rtol)


def test_mode_radiation_efficiency_limits():
    # acoustically small: σ_11 → 32 k² a b/(π⁵ m² n²) (Wallace 1972, Eq. 13), even modes far less
    k = 2 * math.pi * 0.1 / C0
    small = np.asarray(mode_radiation_efficiency(0.1, np.array([1, 3, 2]), 1, 4.0, 5.0))
    assert small[0] == pytest.approx(32 * k**2 * 20 / math.pi**5, rel=1e-5)
    assert small[1] == pytest.approx(32 * k**2 * 20 / (math.pi**5 * 9), rel=1e-5)
    assert small[2] < 1e-4 * small[0]
    # far above the mode's coincidence (k ≫ its wavenumber): σ → 1
    assert float(mode_radiation_efficiency(5000.0, 1, 1, 4.0, 5.0)) == pytest.approx(1.0, abs=2e-3)


def test_modes_of_the_simply_supported_slab_in_closed_form():
    # Leissa 1969 §4.1: ω_mn = √(B′/m″)((mπ/a)² + (nπ/b)²); 1/m_k = 4 φ²(x0, y0)/(m″ab)
    slab = Slab(
        0.18,
        **CONCRETE,
        length_x_m=4.2,
        length_y_m=5.5,
        drive_x_m=1.3,
        drive_y_m=2.1,
        edge="simply-supported",
    )
    orders = mode_orders(slab, 88.4)
    freq, inverse_mass, sigma, eta, eta_rad = (np.asarray(x) for x in slab_modes(slab, orders))
    bending = 33e9 * 0.18**3 / (12 * (1 - 0.2**2))
    mass = 2300 * 0.18
    m, n = np.meshgrid(np.arange(1, orders[0] + 1), np.arange(1, orders[1] + 1), indexing="ij")
    m, n = m.ravel(), n.ravel()
    expected = np.sqrt(bending / mass) * ((m * np.pi / 4.2) ** 2 + (n * np.pi / 5.5) ** 2)
    np.testing.assert_allclose(freq, expected / (2 * np.pi), rtol=1e-13)
    shape = np.sin(m * np.pi * 1.3 / 4.2) * np.sin(n * np.pi * 2.1 / 5.5)
    np.testing.assert_allclose(inverse_mass, 4 * shape**2 / (mass * 4.2 * 5.5), rtol=1e-13)
    # every mode below 4 × 88.4 Hz is in the set (a brute-force search over 50 × 50 orders)
    mm, nn = np.meshgrid(np.arange(1, 51), np.arange(1, 51), indexing="ij")
    f_all = np.sqrt(bending / mass) * ((mm * np.pi / 4.2) ** 2 + (nn * np.pi / 5.5) ** 2)
    below = f_all / (2 * np.pi) <= 4 * 88.4
    assert np.all(mm[below] <= orders[0]) and np.all(nn[below] <= orders[1])
    # the loss: η_s = f^-1/2 (Craik, in situ) and the radiation of both faces
    rad = RHO0 * C0 * sigma / (2 * np.pi * freq * mass)
    np.testing.assert_allclose(eta_rad, rad, rtol=1e-13)
    np.testing.assert_allclose(eta, freq**-0.5 + 2 * rad, rtol=1e-13)


def test_band_energies_against_an_independent_modal_sum():
    # a 4 m × 5 m, 150 mm slab driven off the centre: every mode of the set, the 31.5 and 63 Hz
    # octaves (and the 125 Hz octave: the tails), band energy Σ_k ∫_b E_F Re Y_k df by
    # scipy's adaptive quad, to 1e-6 relative per band
    slab = Slab(0.15, **CONCRETE, length_x_m=4.0, length_y_m=5.0, drive_x_m=1.1, drive_y_m=2.9)
    orders = mode_orders(slab, 88.4)
    freq, inverse_mass, _, eta, _ = (np.asarray(x) for x in slab_modes(slab, orders))
    lo, hi = np.array([22.1, 44.2, 88.4]), np.array([44.2, 88.4, 176.8])
    force = _force()
    got = np.asarray(modal_band_energies_J(force, RATE, freq, eta, inverse_mass, lo, hi))
    ref = np.zeros((freq.size, lo.size))
    for k in range(freq.size):
        for b in range(lo.size):
            inside = [freq[k]] if lo[b] < freq[k] < hi[b] else None
            ref[k, b] = si.quad(
                lambda f, k=k: _esd(force, f)[0] * _re_y(f, freq[k], eta[k], inverse_mass[k]),
                lo[b],
                hi[b],
                points=inside,
                limit=400,
                epsabs=0.0,
                epsrel=1e-11,
            )[0]
    np.testing.assert_allclose(got.sum(axis=0), ref.sum(axis=0), rtol=1e-6)
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-9 * ref.max())


@pytest.mark.parametrize("edge", ["simply-supported", "clamped"])
def test_large_slab_joins_the_infinite_plate(edge):
    # a 12 m × 15 m, 150 mm slab: high modal overlap above the 125 Hz octave (η f n(f) ≈ 4 at
    # 250 Hz), so the modal sum of the 250 and 500 Hz octaves, averaged over four drive points
    # away from the centre, is the infinite plate's band energy E_F,b/Z, Z = 8√(B′m″) (Cremer,
    # Heckl & Petersson §5.3), within 0.5 dB (measured +0.00, −0.25 dB simply supported; −0.23,
    # +0.03 dB clamped; one point alone scatters by up to ±0.5 dB). The modes up to 800 Hz
    # (520), 24 nodes a panel (the resonances are broad here): kept small for the suite's time
    lo, hi = np.array([176.8, 353.6]), np.array([353.6, 707.1])
    force = _force()
    modal = np.zeros((1, 2))
    for x0, y0 in [(2.76, 10.05), (6.0, 7.5), (4.1, 5.3), (8.3, 9.9)]:
        slab = Slab(
            0.15,
            **CONCRETE,
            length_x_m=12.0,
            length_y_m=15.0,
            drive_x_m=x0,
            drive_y_m=y0,
            edge=edge,
        )
        orders = mode_orders(slab, 200.0)
        freq, inverse_mass, _, eta, _ = slab_modes(slab, orders)
        modal = modal + 0.25 * np.asarray(
            modal_band_energies_J(force, RATE, freq, eta, inverse_mass, lo, hi, nodes=24)
        )
    # the force's energy spectral density on a 0.25 Hz grid by numpy's zero-padded FFT
    grid = np.fft.rfftfreq(4 * int(RATE), 1 / RATE)
    esd = 2 * np.abs(np.fft.rfft(force, n=4 * int(RATE)) / RATE) ** 2
    z = 8 * math.sqrt(33e9 * 0.15**3 / (12 * (1 - 0.04)) * 2300 * 0.15)
    plate = np.array([esd[(grid >= a) & (grid < b)].sum() * 0.25 for a, b in zip(lo, hi)]) / z
    difference_dB = 10 * np.log10(modal.sum(axis=0) / plate)
    assert np.all(np.abs(difference_dB) <= 0.5), difference_dB


def test_a_slab_of_a_material_in_millimetres_is_refused():
    with pytest.raises(ValueError, match=r"thickness_m=150.0 is outside the plausible range"):
        Slab.of_material("concrete", 150.0)


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        (dict(length_x_m=0.0), r"length_x_m=0.0 is outside the valid range \(0, inf\)"),
        (dict(length_y_m=-5.0), r"length_y_m=-5.0 is outside the valid range \(0, inf\)"),
        (dict(thickness_m=0.45), r"thickness_m=0.45 is outside the valid range \(0, 0.4\]"),
        (dict(drive_x_m=4.0), r"drive_x_m=4.0 is outside the valid range \(0, 4\)"),
        (dict(drive_y_m=-0.1), r"drive_y_m=-0.1 is outside the valid range \(0, 5\)"),
        (
            dict(edge="free"),
            r"edge='free' is not a known option; valid: 'simply-supported', 'clamped'",
        ),
    ],
)
def test_bad_slab(fields, match):
    args = dict(thickness_m=0.15, **CONCRETE, length_x_m=4.0, length_y_m=5.0) | fields
    with pytest.raises(ValueError, match=match):
        Slab(**args)


def test_bad_chain_and_traced_orders():
    with pytest.raises(ValueError, match="slab='plate' is not a known option"):
        Chain(slab="plate")
    with pytest.raises(ValueError, match="orders=mode_orders"):
        jax.jit(lambda t: mode_orders(Slab(t, **CONCRETE), 88.4))(0.15)


def test_mode_indices_are_m_major():
    m, n = mode_indices((2, 3))
    assert m.tolist() == [1, 1, 1, 2, 2, 2] and n.tolist() == [1, 2, 3, 1, 2, 3]


def test_centre_of_the_simply_supported_150_mm_slab_drives_no_mode_of_the_63_Hz_octave():
    # docs/guides/room.md: the modes of the 4 m × 5 m, 150 mm slab simply supported in
    # 44.2-88.4 Hz are (1,2) and (2,1), both with a node at the centre
    slab = Slab(0.15, **CONCRETE, length_x_m=4.0, length_y_m=5.0, edge="simply-supported")
    orders = mode_orders(slab, 88.4)
    freq, inverse_mass, *_ = (np.asarray(x) for x in slab_modes(slab, orders))
    m, n = mode_indices(orders)
    inside = (freq >= 44.2) & (freq < 88.4)
    assert sorted(zip(m[inside], n[inside])) == [(1.0, 2.0), (2.0, 1.0)]
    assert np.all(inverse_mass[inside] < 1e-30 * inverse_mass.max())

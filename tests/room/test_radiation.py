"""``rbjax.room.radiation`` against its closed forms, written out here from the printed
formulas (Cremer, Heckl & Petersson §6.2; ISO 12354-1:2017 Annex B / EN 12354-1:2000 Annex B),
branch by branch: the critical frequency, the radiation efficiency of a rectangular plate and
the radiation loss factor."""

import math

import numpy as np
import pytest

from rbjax.room import radiation as rad

C0, RHO0 = 343.0, 1.21
E, RHO, NU = 33e9, 2300.0, 0.2  # C30/37 (rbjax.terms.floors.materials)


def _fc(t):
    # f_c = c0²/(2π) √(m″/B′), B′ = E t³/(12(1 − ν²))
    return C0**2 / (2 * math.pi) * math.sqrt(RHO * t / (E * t**3 / (12 * (1 - NU**2))))


def test_critical_frequency():
    for t in (0.1, 0.15, 0.24):
        assert float(rad.critical_frequency_Hz(t, E, RHO, NU)) == pytest.approx(_fc(t), rel=1e-13)
    # ISO 12354-1 Eq. B.1: f_c ≈ c0²/(1.8 c_L t), c_L = √(E/(ρ(1 − ν²))): within 1 % (the exact
    # factor is 2π/√12 = 1.814); 112 Hz for 150 mm (module docstring)
    c_l = math.sqrt(E / (RHO * (1 - NU**2)))
    assert _fc(0.15) == pytest.approx(C0**2 / (1.8 * c_l * 0.15), rel=0.01)
    assert float(rad.critical_frequency_Hz(0.15, E, RHO, NU)) == pytest.approx(112.0, abs=0.5)
    assert float(rad.bending_stiffness_Nm(0.15, E, NU)) == pytest.approx(
        E * 0.15**3 / (12 * (1 - NU**2)), rel=1e-14
    )


def _edge(f, fc, l1, l2):
    """ISO 12354-1 Annex B, f11 < f < fc: (2(l1 + l2)c0/(l1 l2 fc)) δ1 + δ2."""
    lam = math.sqrt(f / fc)
    d1 = ((1 - lam**2) * math.log((1 + lam) / (1 - lam)) + 2 * lam) / (
        4 * math.pi**2 * (1 - lam**2) ** 1.5
    )
    d2 = (
        8 * C0**2 * (1 - 2 * lam**2) / (fc**2 * math.pi**4 * l1 * l2 * lam * math.sqrt(1 - lam**2))
        if f < fc / 2
        else 0.0
    )
    return 2 * (l1 + l2) * C0 / (l1 * l2 * fc) * d1 + d2


def test_radiation_efficiency_of_a_large_plate_branch_by_branch():
    fc, l1, l2 = _fc(0.15), 4.0, 5.0
    f11 = C0**2 / (4 * fc) * (1 / l1**2 + 1 / l2**2)
    assert f11 <= fc / 2  # the large-plate branch
    sigma = lambda f: float(rad.radiation_efficiency(f, fc, l1, l2))  # noqa: E731
    # below f11: σ2 = 4 l1 l2 (f/c0)² where it is the smaller
    f = 0.8 * f11
    assert sigma(f) == pytest.approx(
        min(4 * l1 * l2 * (f / C0) ** 2, _edge(f, fc, l1, l2)), rel=1e-12
    )
    # f11 < f < fc/2 (edge and corner modes) and fc/2 < f < fc (δ2 = 0)
    for f in (40.0, 50.0, 0.7 * fc, 0.95 * fc):
        assert sigma(f) == pytest.approx(min(_edge(f, fc, l1, l2), 2.0), rel=1e-12), f
    # above fc: σ1 = 1/√(1 − fc/f), at most σ3 = √(2π f (l1 + l2)/(16 c0)) near coincidence
    for f in (1.05 * fc, 2 * fc, 8 * fc):
        s1 = 1 / math.sqrt(1 - fc / f)
        s3 = math.sqrt(2 * math.pi * f * (l1 + l2) / (16 * C0))
        assert sigma(f) == pytest.approx(min(s1, s3, 2.0), rel=1e-12), f
    assert sigma(8 * fc) == pytest.approx(1 / math.sqrt(1 - 1 / 8), rel=1e-12)


def test_radiation_efficiency_of_a_small_plate():
    # f11 > fc/2 (a small thin plate): σ2 below fc, σ1 above where below σ3, σ3 otherwise
    t, l1, l2 = 0.012, 0.2, 0.25
    fc = C0**2 / (2 * math.pi) * math.sqrt(7850 * t / (210e9 * t**3 / (12 * (1 - 0.09))))
    f11 = C0**2 / (4 * fc) * (1 / l1**2 + 1 / l2**2)
    assert f11 > fc / 2
    for f in (0.3 * fc, 0.9 * fc):
        got = float(rad.radiation_efficiency(f, fc, l1, l2))
        s2 = 4 * l1 * l2 * (f / C0) ** 2
        s3 = math.sqrt(2 * math.pi * f * (l1 + l2) / (16 * C0))
        assert got == pytest.approx(min(s2, s3), rel=1e-12), f
    f = 3 * fc
    s1, s3 = 1 / math.sqrt(1 - fc / f), math.sqrt(2 * math.pi * f * (l1 + l2) / (16 * C0))
    assert float(rad.radiation_efficiency(f, fc, l1, l2)) == pytest.approx(min(s1, s3), rel=1e-12)


def test_radiation_efficiency_is_at_most_two_and_vectorised():
    fc = _fc(0.15)
    f = np.geomspace(10.0, 5000.0, 200)
    sigma = np.asarray(rad.radiation_efficiency(f, fc, 4.0, 5.0))
    assert sigma.shape == f.shape and np.all(sigma > 0) and np.all(sigma <= 2.0)
    # just above coincidence: Leppington's σ3 (the smaller of σ1 → ∞ and σ3)
    s3 = math.sqrt(2 * math.pi * fc * 9.0 / (16 * C0))
    assert float(rad.radiation_efficiency(fc * (1 + 1e-9), fc, 4.0, 5.0)) == pytest.approx(s3)


def test_radiation_loss_factor():
    # η_rad = ρ0 c0 σ/(ω m″) (Cremer, Heckl & Petersson §6.6)
    got = float(rad.radiation_loss_factor(63.0, 0.3, 345.0))
    assert got == pytest.approx(RHO0 * C0 * 0.3 / (2 * math.pi * 63.0 * 345.0), rel=1e-14)

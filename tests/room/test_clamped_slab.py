"""The clamped slab (``rbjax.room.clamped_slab``) against references written here with
numpy/scipy only: the beam roots as tabulated (Blevins 1979, Table 8-1), the beam functions in
their classical form (cosh, cos, sinh, sin) with their clamped ends and unit norm by
``scipy.integrate.quad``, Warburton's (1954) printed G and H, the plate's frequencies against a
finite-difference eigen-solve of the clamped biharmonic (``scipy.sparse.linalg.eigsh``, two
grids and Richardson's extrapolation) and Leissa's (1973) square plate, and each mode's
radiation efficiency by ``scipy.integrate.dblquad`` of the baffled plate's far-field integral
with the mode's wavenumber transform by ``quad``. No rbjax code enters a reference.
"""

import math

import numpy as np
import pytest
import scipy.integrate as si
import scipy.optimize as so
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from rbjax.room import Slab
from rbjax.room.clamped_slab import (
    beam_function,
    beam_root,
    clamped_frequencies_Hz,
    clamped_radiation_efficiency,
    slope_integral,
)
from rbjax.room.finite_slab import mode_indices, mode_orders, slab_modes

C0 = 343.0  # ISO 12354-1 air
CONCRETE = dict(youngs_Pa=33e9, density_kg_per_m3=2300.0, poisson=0.2)  # C30/37 (materials.py)
#: cos β cosh β = 1, as tabulated (Blevins, Formulas for Natural Frequency and Mode Shape, 1979,
#: Table 8-1, clamped-clamped)
BLEVINS_ROOTS = (4.73004074, 7.85320462, 10.9956078, 14.1371655, 17.2787597)


def _root(m):
    """β_m by scipy's brentq on cos β cosh β − 1 around the tabulated value."""
    b = BLEVINS_ROOTS[m - 1]
    return so.brentq(lambda x: math.cos(x) * math.cosh(x) - 1.0, b - 0.1, b + 0.1, xtol=1e-15)


def _classical(m, z):
    """X_m(z) = cosh βz − cos βz − s(sinh βz − sin βz), s from β (Blevins' form as printed)."""
    b = _root(m)
    s = (math.cosh(b) - math.cos(b)) / (math.sinh(b) - math.sin(b))
    return math.cosh(b * z) - math.cos(b * z) - s * (math.sinh(b * z) - math.sin(b * z))


def test_beam_roots_as_tabulated_and_asymptotic():
    roots = [beam_root(m) for m in range(1, 6)]
    np.testing.assert_allclose(roots, BLEVINS_ROOTS, rtol=0, atol=5e-8)  # the last printed digit
    for m in (6, 12, 30):  # β_m → (m + ½)π, the difference ~e^{−β}
        b = beam_root(m)
        assert math.cos(b) * math.cosh(b) == pytest.approx(1.0, abs=1e-6 * math.cosh(b))
        assert b == pytest.approx((m + 0.5) * math.pi, abs=1e-6)


@pytest.mark.parametrize("m", [1, 2, 3, 4])
def test_beam_function_against_the_classical_form(m):
    z = np.linspace(0.0, 1.0, 41)
    got = np.asarray(beam_function(np.full(z.shape, m), z))
    np.testing.assert_allclose(got, [_classical(m, x) for x in z], atol=1e-9)
    norm = si.quad(lambda x: _classical(m, x) ** 2, 0, 1, epsabs=0, epsrel=1e-12)[0]
    assert norm == pytest.approx(1.0, rel=1e-9)
    for other in range(1, m):
        cross = si.quad(lambda x: _classical(m, x) * _classical(other, x), 0, 1)[0]
        assert abs(cross) < 1e-7


@pytest.mark.parametrize("m", [8, 14])
def test_high_order_beam_function_keeps_its_clamped_ends_and_norm(m):
    # where cosh and sinh cancel to ~e^β·1e-16 in the classical form: the ends clamped
    # (value and central-difference slope 0), unit norm and X'''' = β⁴X (finite differences)
    order = np.array(m)
    assert float(beam_function(order, 0.0)) == pytest.approx(0.0, abs=1e-12)
    assert float(beam_function(order, 1.0)) == pytest.approx(0.0, abs=1e-12)
    h = 1e-6
    for end in (0.0, 1.0):
        slope = (float(beam_function(order, end + h)) - float(beam_function(order, end - h))) / (
            2 * h
        )
        assert abs(slope) < 1e-5 * beam_root(m)
    norm = si.quad(lambda x: float(beam_function(order, x)) ** 2, 0, 1, limit=200)[0]
    assert norm == pytest.approx(1.0, rel=1e-9)
    z, h4 = 0.37, 1e-3
    values = [float(beam_function(order, z + k * h4)) for k in (-2, -1, 0, 1, 2)]
    fourth = (values[0] - 4 * values[1] + 6 * values[2] - 4 * values[3] + values[4]) / h4**4
    assert fourth == pytest.approx(
        beam_root(m) ** 4 * values[2], rel=1e-3, abs=1e-3 * beam_root(m) ** 4
    )


def test_warburtons_printed_terms():
    # Warburton (1954), clamped-clamped: G1 = 1.506, H1 = J1 = 1.248; G = m + ½ and
    # H = G²(1 − 2/(Gπ)) above (printed to 3-4 digits)
    orders = np.arange(1, 7)
    g = np.array([beam_root(m) for m in orders]) / math.pi
    h = slope_integral(orders) / math.pi**2
    assert g[0] == pytest.approx(1.506, abs=5e-4)
    assert h[0] == pytest.approx(1.248, abs=2e-3)
    approx = (orders[1:] + 0.5) ** 2 * (1 - 2 / ((orders[1:] + 0.5) * math.pi))
    np.testing.assert_allclose(g[1:], orders[1:] + 0.5, rtol=1e-4)
    np.testing.assert_allclose(h[1:], approx, rtol=5e-3)
    # and I_m = ∫X'² against quad of the classical form's derivative
    for m in (1, 2, 3):
        b = _root(m)
        s = (math.cosh(b) - math.cos(b)) / (math.sinh(b) - math.sin(b))

        def slope(x, b=b, s=s):
            return b * (
                math.sinh(b * x) + math.sin(b * x) - s * (math.cosh(b * x) - math.cos(b * x))
            )

        assert slope_integral(np.array(m)) == pytest.approx(
            si.quad(lambda x: slope(x) ** 2, 0, 1, epsrel=1e-12)[0], rel=1e-7
        )


def _fd_eigenvalues(lx, ly, n, count):
    """The smallest ``count`` λ = ω²m″/B′ of the clamped plate by the 13-point biharmonic on a
    grid of spacing lx/n (w = 0 and zero slope by reflection at the edges)."""
    h = lx / n
    nx, ny = n - 1, int(round(ly / h)) - 1

    def d4(k):
        main = np.full(k, 6.0)
        main[[0, -1]] = 7.0  # the ghost node w₋₁ = w₁ of a clamped end
        return (
            sp.diags(
                [np.ones(k - 2), -4 * np.ones(k - 1), main, -4 * np.ones(k - 1), np.ones(k - 2)],
                [-2, -1, 0, 1, 2],
            )
            / h**4
        )

    def d2(k):
        return sp.diags([np.ones(k - 1), -2 * np.ones(k), np.ones(k - 1)], [-1, 0, 1]) / h**2

    ix, iy = sp.identity(nx), sp.identity(ny)
    op = sp.kron(d4(nx), iy) + 2 * sp.kron(d2(nx), d2(ny)) + sp.kron(ix, d4(ny))
    return np.sort(sla.eigsh(op.tocsc(), k=count, sigma=0, which="LM")[0])


def test_frequencies_against_a_finite_difference_eigen_solve():
    # the 4 m × 5 m, 200 mm concrete slab: its lowest eight modes by Rayleigh's quotient lie
    # above the plate's own (Richardson of grids 4/40 and 4/80 m) by 0-1 % (measured
    # 0.3-0.6 %; a one-term Rayleigh estimate is an upper bound)
    slab = Slab(0.2, **CONCRETE, length_x_m=4.0, length_y_m=5.0, edge="clamped")
    bending = 33e9 * 0.2**3 / (12 * (1 - 0.2**2))
    coarse, fine = _fd_eigenvalues(4.0, 5.0, 40, 12), _fd_eigenvalues(4.0, 5.0, 80, 12)
    exact = (4 * fine - coarse) / 3
    f_ref = np.sqrt(exact * bending / (2300 * 0.2)) / (2 * math.pi)
    freq = np.sort(np.asarray(slab_modes(slab, (4, 4))[0]))[:8]
    ratio = freq / f_ref[:8]
    assert np.all(ratio > 1.0 - 1e-4) and np.all(ratio < 1.01), ratio


def test_square_plate_against_leissa():
    # λ² = ωa²√(m″/B′) of the first mode of a clamped square plate: 35.992 (Leissa, JSV 31
    # (1973) 257, Table 1, Ritz with 36 terms); the one-term estimate lies above, within 0.5 %
    c = 1.0  # √(B′/m″) = 1 m²/s
    f = float(clamped_frequencies_Hz(c, np.array(1), np.array(1), 1.0, 1.0))
    lam = 2 * math.pi * f
    assert 35.992 < lam < 35.992 * 1.005


def _transform(m, q):
    re = si.quad(lambda x: _classical(m, x) * math.cos(q * x), 0, 1, epsabs=1e-13, limit=200)[0]
    im = si.quad(lambda x: _classical(m, x) * math.sin(q * x), 0, 1, epsabs=1e-13, limit=200)[0]
    return re * re + im * im


def _sigma_reference(f, shape_x, shape_y, a, b, norm=1.0):
    """σ = (k²ab/π²) ∫∫|X̂(ka sinθ cosψ)|²|Ŷ(kb sinθ sinψ)|² sinθ / (∫X² ∫Y²) by dblquad."""
    k = 2 * math.pi * f / C0

    def integrand(theta, psi):
        return (
            shape_x(k * a * math.sin(theta) * math.cos(psi))
            * shape_y(k * b * math.sin(theta) * math.sin(psi))
            * math.sin(theta)
        )

    value = si.dblquad(integrand, 0, math.pi / 2, 0, math.pi / 2, epsabs=0, epsrel=1e-9)[0]
    return k**2 * a * b / math.pi**2 * value / norm


def test_the_reference_integral_is_wallaces_for_sine_modes():
    # the reference's constant: for φ = sin(πx/a) sin(πy/b) (∫φ² = ab/4 → norm 1/4) it is
    # Wallace's small-plate limit 32k²ab/π⁵ at ka ≪ 1
    def sine(q):
        re = si.quad(lambda x: math.sin(math.pi * x) * math.cos(q * x), 0, 1)[0]
        im = si.quad(lambda x: math.sin(math.pi * x) * math.sin(q * x), 0, 1)[0]
        return re * re + im * im

    f, a, b = 1.0, 1.0, 1.2
    k = 2 * math.pi * f / C0
    got = _sigma_reference(f, sine, sine, a, b, norm=0.25)
    assert got == pytest.approx(32 * k**2 * a * b / math.pi**5, rel=1e-4)


@pytest.mark.parametrize(
    ("freq", "m", "n"), [(50.0, 1, 1), (90.0, 2, 1), (90.0, 1, 3), (60.0, 2, 2)]
)
def test_clamped_radiation_efficiency_by_dblquad(freq, m, n):
    ref = _sigma_reference(freq, lambda q: _transform(m, q), lambda q: _transform(n, q), 4.0, 5.0)
    got = float(clamped_radiation_efficiency(freq, np.array(m), np.array(n), 4.0, 5.0))
    assert got == pytest.approx(ref, rel=1e-6)


def test_clamped_radiation_small_plate_limit():
    # ka ≪ 1: a baffled monopole of volume velocity Q = ab∫X∫Y, σ → k²ab(∫X)²(∫Y)²/(2π)
    f, a, b = 2.0, 0.3, 0.4
    k = 2 * math.pi * f / C0
    q = si.quad(lambda x: _classical(1, x), 0, 1)[0]
    got = float(clamped_radiation_efficiency(f, np.array(1), np.array(1), a, b))
    assert got == pytest.approx(k**2 * a * b * q**4 / (2 * math.pi), rel=1e-5)


def test_mode_orders_cover_every_clamped_mode_below_the_cutoff():
    # the set is chosen from the simply supported frequencies, which lie below the clamped
    # ones of the same (m, n): every clamped mode below the cutoff is inside it
    slab = Slab(0.15, **CONCRETE, length_x_m=4.0, length_y_m=5.0, edge="clamped")
    orders = mode_orders(slab, 88.4)
    inside = np.asarray(slab_modes(slab, orders)[0])
    wider = (orders[0] + 3, orders[1] + 3)
    freq = np.asarray(slab_modes(slab, wider)[0])
    m, n = mode_indices(wider)
    below = freq < 4.0 * 88.4
    assert np.all((m[below] <= orders[0]) & (n[below] <= orders[1]))
    assert np.sum(inside < 4.0 * 88.4) == np.sum(below)


def test_drive_point_mass_of_the_clamped_slab():
    # 1/m_k = X_m(x₀/l_x)²X_n(y₀/l_y)²/(m″l_xl_y): at the centre of the first mode
    # X₁(½)² = 1.5882² (Blevins' form)
    slab = Slab(0.15, **CONCRETE, length_x_m=4.0, length_y_m=5.0, edge="clamped")
    _, inverse_mass, *_ = slab_modes(slab, (1, 1))
    expected = _classical(1, 0.5) ** 4 / (2300 * 0.15 * 20.0)
    assert float(inverse_mass[0]) == pytest.approx(expected, rel=1e-9)

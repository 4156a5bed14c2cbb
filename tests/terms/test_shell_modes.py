"""Eigenfrequencies of the hollow sphere (rbjax.terms.shell_modes) against closed forms and
published values; no expected value here comes from rbjax's own output."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rbjax
from rbjax.terms.shell_modes import (
    INCOMPRESSIBLE_POISSON,
    THEORIES,
    elastic_sphere_omega,
    membrane_omega,
    shell_density_kg_per_m3,
    shell_frequencies_Hz,
    thin_shell_omega,
)


def test_breathing_mode_closed_form():
    # n = 0 of a thin shell: ω = √(2E/(ρ(1−ν)))/a, i.e. Ω² = 2(1+ν) with Ω = ωa/c_p.
    ball = rbjax.JIS_RUBBER_BALL.replace(poisson=0.3)
    rho = shell_density_kg_per_m3(ball)
    a = 0.089 - 0.016
    expected = math.sqrt(2 * 1.6e6 / (rho * (1 - 0.3))) / a / (2 * math.pi)
    for theory in ("membrane", "thin"):
        assert shell_frequencies_Hz(ball, 0, theory).frequency(0) == pytest.approx(
            expected, rel=1e-12
        )


def test_density_of_jis_ball():
    # ρ = 2.5 kg / (4π/3 (0.089³ − 0.057³) m³)
    assert shell_density_kg_per_m3() == pytest.approx(
        2.5 / (4 * math.pi / 3 * (0.089**3 - 0.057**3)), rel=1e-12
    )


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.5])
@pytest.mark.parametrize("n", [1, 2, 3, 6])
def test_membrane_roots_solve_baker_equation_and_thin_shell_tends_to_it(n, nu):
    lam = n * (n + 1)
    for om in membrane_omega(n, nu):
        w2 = om**2
        assert w2**2 - (1 + 3 * nu + lam) * w2 + (lam - 2) * (1 - nu**2) == pytest.approx(
            0.0, abs=1e-10
        )
    # h → 0: the bending terms (∝ h²/12a²) vanish
    np.testing.assert_allclose(
        thin_shell_omega(n, nu, 1e-5), membrane_omega(n, nu), rtol=1e-6, atol=1e-9
    )


def test_n1_rigid_translation_and_membrane_values():
    # n = 1: Ω = 0 (rigid translation) and Ω² = 3(1 + ν), membrane and thin alike
    for om in (membrane_omega(1, 0.3), thin_shell_omega(1, 0.3, 0.0)):
        assert om[0] == 0.0
        assert om[1] == pytest.approx(math.sqrt(3 * 1.3), rel=1e-12)
    for theory in THEORIES:
        assert shell_frequencies_Hz(n_max=1, theory=theory).frequency(1, 0) == 0.0


def test_bending_raises_the_flexural_branch():
    thick = thin_shell_omega(4, 0.3, 0.2)
    assert thick[0] > membrane_omega(4, 0.3)[0] * 1.05


def test_solid_sphere_lamb():
    # Lamb (1882), solid sphere, ν = 1/4: n = 2 fundamental ωa/c_s = 2.6399 (Lamb: ka/π ≈ 0.84;
    # 2.6399 to four decimals in e.g. Sato & Usami 1962 and Saviot's tables).
    assert elastic_sphere_omega(2, 0.25, 0.0, n_roots=1)[0] == pytest.approx(2.6399, abs=2e-4)
    # n = 0, Lamb's Eq. (59): tan x = 4x / (4 − (c_p/c_s)² x²), x = ωa/c_p; solved independently
    from scipy.optimize import brentq

    ratio2 = 3.0  # (c_p/c_s)² = 2(1−ν)/(1−2ν) = 3 at ν = 1/4
    x = brentq(lambda x: math.sin(x) * (4 - ratio2 * x * x) - 4 * x * math.cos(x), 2.0, 3.0)
    assert elastic_sphere_omega(0, 0.25, 0.0, n_roots=1)[0] == pytest.approx(
        x * math.sqrt(ratio2), rel=1e-9
    )


def test_hollow_sphere_with_tiny_cavity_tends_to_solid():
    solid = elastic_sphere_omega(2, 0.25, 0.0, n_roots=2)
    hollow = elastic_sphere_omega(2, 0.25, 0.02, n_roots=2)
    np.testing.assert_allclose(hollow, solid, rtol=1e-4)


@pytest.mark.parametrize("n", [0, 2, 4, 6])
def test_elastic_tends_to_thin_shell(n):
    # R/h = 50: 3-D elasticity and Love's shell theory agree (both branches); the thin-shell
    # error is O(h/a), so a few 10⁻³ at most; at n = 6 bending matters (membrane is off by 3 %).
    nu, R, h = 0.3, 1.0, 0.02
    a = R - h / 2
    to_thin = math.sqrt((1 - nu**2) / (2 * (1 + nu))) * a / R  # Ω_s = ωR/c_s → Ω = ωa/c_p
    el = elastic_sphere_omega(n, nu, 1 - h, n_roots=2, omega_max=12) * to_thin
    th = thin_shell_omega(n, nu, h / a)
    k = len(th)
    np.testing.assert_allclose(el[:k], th, rtol=4e-3)
    if n == 6:
        assert abs(membrane_omega(n, nu)[0] / el[0] - 1) > 0.02


def test_incompressible_limit_converges():
    inner = 57 / 89
    roots = [
        elastic_sphere_omega(2, nu, inner, n_roots=2)
        for nu in (0.49, 0.499, INCOMPRESSIBLE_POISSON, 0.5)
    ]
    d1 = np.abs(roots[1] / roots[0] - 1)
    d2 = np.abs(roots[2] / roots[1] - 1)
    assert np.all(d2 < 0.2 * d1)  # linear in 0.5 − ν: each factor 10 closer shrinks the change ~10×
    assert np.all(d2 < 1e-3)
    np.testing.assert_array_equal(roots[3], roots[2])  # ν = 0.5 is evaluated at the substitute
    # docs/guides/physics.md: 0.4999 is "within ~2·10⁻⁵ of the incompressible limit": the limit
    # extrapolated linearly in 0.5 − ν from 0.499 and 0.4999 (asserted at 10×)
    limit = roots[2] + (roots[2] - roots[1]) * (0.5 - INCOMPRESSIBLE_POISSON) / 0.0009
    assert np.all(np.abs(roots[2] / limit - 1) < 2e-4), roots[2] / limit - 1


def test_jis_values_and_paper_60Hz():
    f = {t: shell_frequencies_Hz(n_max=4, theory=t) for t in THEORIES}
    for t in THEORIES:
        # the fundamental is the n = 2 flexural mode, within ±20 % of the paper's ~60 Hz
        assert f[t].fundamental_Hz == f[t].frequency(2, 0)
        assert 48.0 < f[t].fundamental_Hz < 72.0
        assert list(f[t].n) == sorted(f[t].n)
    assert f["elastic"].poisson_used == INCOMPRESSIBLE_POISSON
    assert "| 2 | 0 |" in f["thin"].table()
    # docs/guides/physics.md, the JIS ball's table, as printed (0.1 Hz): (n, branch) → membrane,
    # thin shell, exact 3-D; and the exact fundamental's period, 15.3 ms
    for (n, branch), printed in JIS_TABLE.items():
        for t, value in zip(("membrane", "thin", "elastic"), printed, strict=True):
            assert f[t].frequency(n, branch) == pytest.approx(value, abs=0.05), (n, branch, t)
    assert 1e3 / f["elastic"].fundamental_Hz == pytest.approx(15.3, abs=0.05)


#: docs/guides/physics.md, "Shell eigenfrequencies": (n, branch) → (membrane, thin shell, exact
#: 3-D) in Hz; n = 1, branch 1 is the first elastic mode (branch 0 is the rigid translation).
JIS_TABLE = {
    (2, 0): (57.1, 68.7, 65.2),
    (3, 0): (68.9, 125.2, 103.5),
    (0, 0): (162.8, 162.8, 172.3),
    (1, 1): (199.3, 200.9, 186.4),
    (2, 1): (268.0, 275.3, 229.7),
}


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"theory": "thick-ish"}, "theory"),
        ({"n_max": -1}, "n_max"),
        ({"n_max": 2.5}, "n_max"),
        ({"n_roots": 0}, "n_roots"),
    ],
)
def test_bad_inputs_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        shell_frequencies_Hz(**kwargs)


def test_bad_ball_and_low_level_inputs():
    with pytest.raises(TypeError, match="ball"):
        shell_frequencies_Hz("jis")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="ball"):
        shell_frequencies_Hz(rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=np.array([1e6, 2e6])))
    with pytest.raises(ValueError, match="poisson"):
        membrane_omega(2, 0.7)
    with pytest.raises(ValueError, match="inner_ratio"):
        elastic_sphere_omega(2, 0.3, 1.0)
    with pytest.raises(ValueError, match="thickness_ratio"):
        thin_shell_omega(2, 0.3, -0.1)
    with pytest.raises(KeyError):
        shell_frequencies_Hz(n_max=1, theory="thin").frequency(3, 0)

"""Free-vibration eigenfrequencies of a hollow elastic sphere: the ball's axisymmetric modes.

The paper's elastic impact model has no shell modes; its §4.1 blames the measured ringing and
the L_FE excess above 125 Hz on them and quotes the fundamental axisymmetric mode of the
undeformed ball "around 60 Hz" from a thin-shell estimate (its ref. [20]); Park et al. measured
24 Hz and 89 Hz on the ball deformed against the floor. This module computes the modes of the
free, undeformed ball (axisymmetric, Legendre order n = 0, 1, 2, ...) by three theories:

``"membrane"``
    Membrane (extensional) theory of a thin spherical shell, closed form (Lamb 1882 §13;
    Baker, J. Acoust. Soc. Am. 33 (1961) 1749; Junger & Feit, *Sound, Structures and Their
    Interaction*, 2nd ed. 1986, ch. 7, the in-vacuo spherical shell): with λ_n = n(n+1),

        Ω⁴ − (1 + 3ν + λ_n) Ω² + (λ_n − 2)(1 − ν²) = 0,   Ω = ω a / c_p,  c_p = √(E/(ρ(1−ν²))),

    a the radius of the middle surface. n = 0 has one root, the breathing mode Ω² = 2(1 + ν)
    (ω = √(2E/(ρ(1−ν)))/a); n = 1 has Ω = 0 (rigid translation) and Ω² = 3(1 + ν).
``"thin"``
    Love's first-approximation (Kirchhoff) shell theory, membrane + bending, as in Kraus,
    *Thin Elastic Shells* (1967) ch. 8 and Kalnins, J. Acoust. Soc. Am. 36 (1964) 74. For each
    n the exact mode shapes are u_θ = U dP_n/dθ, w = W P_n (P_n Legendre), so the equations of
    motion reduce to a 2 × 2 generalized eigenproblem; it is assembled here from the strain
    and kinetic energies (Rayleigh–Ritz with these exact shapes, integrals by Gauss–Legendre
    quadrature, exact for the polynomial integrands):

        ε_θ = (u_θ' + w)/a, ε_φ = (u_θ cot θ + w)/a, β = (u_θ − w')/a,
        κ_θ = β'/a, κ_φ = β cot θ / a,
        U = ½∫[K(ε_θ² + ε_φ² + 2ν ε_θ ε_φ) + D(κ_θ² + κ_φ² + 2ν κ_θ κ_φ)] dA,
        T = ½ ρ h ω² ∫(u_θ² + w²) dA,  K = Eh/(1−ν²), D = Eh³/(12(1−ν²)).

    In Ω = ω a/c_p the bending terms carry the factor h²/(12a²); h → 0 gives the membrane
    equation above exactly. The lower root of each n ≥ 2 is the bending-dominated (flexural)
    branch, the upper the membrane-dominated (extensional) one. No shear deformation, no rotary
    inertia: for R/h ≈ 3 (the JIS ball: a/h = 2.3) this theory is outside its range.
``"elastic"``
    Exact three-dimensional linear elasticity of the hollow sphere (Lamb 1882 for the solid
    sphere; Shah, Ramkrishnan & Datta, J. Appl. Mech. 36 (1969) 431 for the hollow one), the
    thick-shell reference. Spheroidal modes of order n: u = ∇φ + ∇×∇×(r χ) with
    φ = [A₁ j_n(k_p r) + A₂ y_n(k_p r)] P_n, χ = [B₁ j_n(k_s r) + B₂ y_n(k_s r)] P_n,
    k_p = ω/c_p', k_s = ω/c_s (c_p' = √((λ+2μ)/ρ) the dilatational, c_s = √(μ/ρ) the shear wave
    speed); the tractions σ_rr and σ_rθ vanish on the inner (R − h) and outer (R) surface: a
    4 × 4 determinant (2 × 2 for n = 0, where χ gives no displacement; 2 × 2 for the solid
    sphere, no y_n). Its roots are bracketed by a sign scan (columns scaled to unit maximum,
    which keeps the sign) and refined by Brent's method. For ν → 0.5 the determinant stays
    regular (λ_L k_p² = μ k_s² ν/(1−ν) stays finite) while k_p → 0, where the dilatational
    potential becomes harmonic; ν = 0.5 itself (incompressible rubber, the paper's value) is
    evaluated at ν = 0.5 − 10⁻⁴ (``INCOMPRESSIBLE_POISSON``). The frequencies converge
    linearly in 0.5 − ν (ν = 0.49 → 0.499 → 0.4999 changes the JIS n = 2 root by 1.7·10⁻³,
    then 1.8·10⁻⁴), so the substitute is within about 2·10⁻⁵ of the limit (tested).

Density: ρ = M / (4π/3 (R³ − (R − h)³)), the mass over the shell's volume (the gas inside is
neglected). The shell theories use the middle surface a = R − h/2 and the thickness h.

Units are in the names; all functions are plain NumPy/SciPy (no JAX: the modes are a property
of the ball, computed once).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.polynomial.legendre import Legendre, leggauss

from .._validate import as_float, check_choice
from .ball import JIS_RUBBER_BALL, Ball

__all__ = [
    "THEORIES",
    "INCOMPRESSIBLE_POISSON",
    "PAPER_FUNDAMENTAL_Hz",
    "PARK_DEFORMED_Hz",
    "ShellModes",
    "shell_density_kg_per_m3",
    "shell_frequencies_Hz",
    "membrane_omega",
    "thin_shell_omega",
    "elastic_sphere_omega",
]

#: The theories of :func:`shell_frequencies_Hz`.
THEORIES = ("membrane", "thin", "elastic")
#: ν used by the elastic solution where ν is within 10⁻⁴ of 0.5 (the incompressible limit).
INCOMPRESSIBLE_POISSON = 0.5 - 1e-4
#: The paper's thin-shell estimate of the fundamental axisymmetric mode (§4.1, ref. [20]).
PAPER_FUNDAMENTAL_Hz = 60.0
#: Park et al.'s measured modes of the ball deformed against the floor (paper §4.1, ref. [19]).
PARK_DEFORMED_Hz = (24.0, 89.0)


# --------------------------------------------------------------------------------------
# validation and material
# --------------------------------------------------------------------------------------


def _scalar_ball(ball: Ball) -> dict[str, float]:
    if not isinstance(ball, Ball):
        raise TypeError(f"ball={ball!r} must be an rbjax.Ball")
    try:
        vals = {
            f: as_float(getattr(ball, f))
            for f in ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")
        }
    except (TypeError, ValueError) as exc:
        raise ValueError(f"ball must have scalar fields (one ball, not a batch): {exc}") from None
    return vals


def _check_n_max(n_max) -> int:
    if (
        isinstance(n_max, bool)
        or not isinstance(n_max, (int, np.integer))
        or n_max < 0
        or n_max > 40
    ):
        raise ValueError(f"n_max={n_max!r} must be an integer in [0, 40]")
    return int(n_max)


def _check_count(name, value, upper=20) -> int:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, np.integer))
        or not 1 <= value <= upper
    ):
        raise ValueError(f"{name}={value!r} must be an integer in [1, {upper}]")
    return int(value)


def _check_poisson(nu: float, upper_closed: bool) -> None:
    ok = -1.0 < nu <= 0.5 if upper_closed else -1.0 < nu < 0.5
    if not (math.isfinite(nu) and ok):
        raise ValueError(
            f"poisson={nu!r} is outside the valid range (-1, 0.5{']' if upper_closed else ')'}"
        )


def shell_density_kg_per_m3(ball: Ball = JIS_RUBBER_BALL) -> float:
    """ρ = M / (4π/3 (R³ − (R − h)³)): the ball's mass over its shell's volume (kg/m³).

    1148 kg/m³ for the JIS ball (R = 89 mm, h = 32 mm, M = 2.5 kg).
    """
    b = _scalar_ball(ball)
    r_in = b["radius_m"] - b["wall_m"]
    return b["mass_kg"] / (4.0 * math.pi / 3.0 * (b["radius_m"] ** 3 - r_in**3))


# --------------------------------------------------------------------------------------
# thin shells: membrane (closed form) and Love/Kirchhoff (2 x 2 Ritz with exact shapes)
# --------------------------------------------------------------------------------------


def membrane_omega(n: int, poisson: float) -> np.ndarray:
    """Ω = ω a/c_p of the membrane spherical shell, order n (ascending; one root for n = 0).

    Roots of Ω⁴ − (1 + 3ν + λ)Ω² + (λ − 2)(1 − ν²) = 0, λ = n(n + 1) (Baker 1961); n = 0
    keeps only the positive root Ω² = 2(1 + ν); n = 1 gives 0 and √(3(1 + ν)).
    """
    _check_poisson(poisson, True)
    lam = n * (n + 1.0)
    b = 1.0 + 3.0 * poisson + lam
    c = (lam - 2.0) * (1.0 - poisson**2)
    disc = math.sqrt(b * b - 4.0 * c)
    roots = [(b - disc) / 2.0, (b + disc) / 2.0]
    if n == 0:
        roots = [roots[1]]
    return np.sqrt(np.clip(roots, 0.0, None))


def _thin_matrices(n: int, poisson: float, thickness_ratio: float):
    """Stiffness and mass matrices (2 × 2, unknowns (U, W)) of the Love shell, per unit
    K·2π (stiffness) and ρh·2πa² (mass); thickness_ratio = h/a."""
    x, wq = leggauss(2 * n + 8)
    p = Legendre.basis(n)
    P, dP = p(x), p.deriv()(x)
    lam = n * (n + 1.0)
    s2 = 1.0 - x**2
    # In x = cos θ, with u_θ = U·dP_n/dθ = −U sinθ P', w = W P (derivation in the module doc):
    # a ε_θ = U(xP' − λP) + W P, a ε_φ = −U xP' + W P,
    # a² κ_θ = −(xP' − λP)(W − U), a² κ_φ = xP'(W − U).
    e_t = np.stack([x * dP - lam * P, P])  # coefficients of (U, W)
    e_p = np.stack([-x * dP, P])
    k_t = np.stack(
        [(x * dP - lam * P), -(x * dP - lam * P)]
    )  # (U, W) coefficients of −(xP'−λP)(W−U)
    k_p = np.stack([-x * dP, x * dP])

    def form(a, b):
        return np.einsum("iq,jq,q->ij", a, b, wq)

    nu = poisson
    stretch = form(e_t, e_t) + form(e_p, e_p) + nu * (form(e_t, e_p) + form(e_p, e_t))
    bend = form(k_t, k_t) + form(k_p, k_p) + nu * (form(k_t, k_p) + form(k_p, k_t))
    stiff = stretch + thickness_ratio**2 / 12.0 * bend
    mass = np.diag([np.sum(wq * s2 * dP**2), np.sum(wq * P**2)])
    return stiff, mass


def thin_shell_omega(n: int, poisson: float, thickness_ratio: float) -> np.ndarray:
    """Ω = ω a/c_p of the Love (membrane + bending) spherical shell, order n, ascending.

    ``thickness_ratio`` = h/a (a: middle-surface radius). n = 0: the breathing mode only
    (no bending, Ω² = 2(1 + ν)); n = 1: 0 (rigid translation) and the extensional mode.
    """
    _check_poisson(poisson, True)
    if not (math.isfinite(thickness_ratio) and thickness_ratio >= 0.0):
        raise ValueError(f"thickness_ratio={thickness_ratio!r} must be finite and >= 0")
    if n == 0:
        return np.array([math.sqrt(2.0 * (1.0 + poisson))])
    # lazy: scipy.linalg costs 0.3 s at import
    from scipy.linalg import eigh

    stiff, mass = _thin_matrices(n, poisson, thickness_ratio)
    w2 = eigh(stiff, mass, eigvals_only=True)
    w2 = np.where(np.abs(w2) < 1e-12 * np.max(np.abs(w2)), 0.0, w2)
    return np.sqrt(np.clip(np.sort(w2), 0.0, None))


# --------------------------------------------------------------------------------------
# exact 3-D elasticity (Lamb 1882; Shah, Ramkrishnan & Datta 1969)
# --------------------------------------------------------------------------------------


def _bessel(kind: str, n: int, z: np.ndarray):
    """z_n(z), z_n'(z), z_n''(z) for z_n = j_n ('j') or y_n ('y')."""
    # lazy: scipy.special costs 0.2 s at import
    from scipy.special import spherical_jn, spherical_yn

    fn = spherical_jn if kind == "j" else spherical_yn
    f, d = fn(n, z), fn(n, z, derivative=True)
    dd = -2.0 / z * d - (1.0 - n * (n + 1.0) / z**2) * f  # the spherical Bessel equation
    return f, d, dd


def _traction_columns(n: int, r: float, omega, gamma: float, poisson: float) -> np.ndarray:
    """Rows (σ_rr/μ, σ_rθ/μ) at radius r for the four potentials (P-j, P-y, S-j, S-y).

    Shape (..., 2, 4) for ``omega`` of shape (...). Units: outer radius 1, c_s = 1, so
    k_s = Ω and k_p = γΩ with γ = c_s/c_p'. u_r = U(r) P_n, u_θ = V(r) dP_n/dθ;
    φ = f(r)P_n gives U = f', V = f/r; χ = g(r)P_n gives U = λ g/r, V = (r g)'/r
    (λ = n(n+1)). σ_rr = −λ_L k_p² f P_n + 2μ U' P_n, σ_rθ = μ (U/r + V' − V/r) dP_n/dθ,
    with λ_L/μ = 2ν/(1 − 2ν).
    """
    omega = np.asarray(omega, dtype=float)
    lam = n * (n + 1.0)
    lame_ratio = 2.0 * poisson / (1.0 - 2.0 * poisson)
    cols = []
    for kind in ("j", "y"):  # dilatational potential
        k = gamma * omega
        z, dz, ddz = _bessel(kind, n, k * r)
        f, f1, f2 = z, k * dz, k * k * ddz
        u, u1 = f1, f2
        v, v1 = f / r, f1 / r - f / r**2
        cols.append((-lame_ratio * k * k * f + 2.0 * u1, u / r + v1 - v / r))
    for kind in ("j", "y"):  # shear potential
        k = omega
        z, dz, ddz = _bessel(kind, n, k * r)
        g, g1, g2 = z, k * dz, k * k * ddz
        u = lam * g / r
        u1 = lam * (g1 / r - g / r**2)
        v = g / r + g1
        v1 = g1 / r - g / r**2 + g2
        cols.append((2.0 * u1, u / r + v1 - v / r))
    # cols[c][row] has shape omega.shape → (..., 2 rows, 4 columns)
    return np.stack([np.stack(c, axis=-1) for c in cols], axis=-1)


def _elastic_det(omega, n: int, inner_ratio: float, gamma: float, poisson: float):
    """The traction determinant (columns scaled to unit maximum modulus), vectorised in Ω."""
    rows = [_traction_columns(n, 1.0, omega, gamma, poisson)]
    hollow = inner_ratio > 0.0
    if hollow:
        rows.append(_traction_columns(n, inner_ratio, omega, gamma, poisson))
    m = np.concatenate(rows, axis=-2)
    keep_cols = [0, 1, 2, 3] if hollow else [0, 2]
    keep_rows = list(range(m.shape[-2]))
    if n == 0:  # χ gives no displacement; σ_rθ ≡ 0
        keep_cols = [c for c in keep_cols if c < 2]
        keep_rows = [r for r in keep_rows if r % 2 == 0]
    m = m[..., keep_rows, :][..., keep_cols]
    scale = np.max(np.abs(m), axis=-2, keepdims=True)
    return np.linalg.det(m / scale)


def elastic_sphere_omega(
    n: int,
    poisson: float,
    inner_ratio: float,
    *,
    n_roots: int = 2,
    omega_max: float = 40.0,
    step: float = 0.005,
) -> np.ndarray:
    """The lowest ``n_roots`` roots Ω = ω R/c_s of the spheroidal frequency equation, order n.

    ``inner_ratio`` = inner/outer radius (0: solid sphere, Lamb 1882). c_s = √(μ/ρ). Roots
    are bracketed by sign changes on a grid of spacing ``step`` from ``step`` to
    ``omega_max`` and refined by Brent's method; fewer than ``n_roots`` come back if the
    range holds fewer. ν within 10⁻⁴ of 0.5 is evaluated at ``INCOMPRESSIBLE_POISSON``.
    The rigid translation of n = 1 (Ω = 0) is not a root of the scan.
    """
    # lazy: scipy.optimize costs 0.3–0.8 s at import
    from scipy.optimize import brentq

    _check_poisson(poisson, True)
    if not (math.isfinite(inner_ratio) and 0.0 <= inner_ratio < 1.0):
        raise ValueError(f"inner_ratio={inner_ratio!r} must be in [0, 1)")
    nu = min(poisson, INCOMPRESSIBLE_POISSON)
    gamma = math.sqrt((1.0 - 2.0 * nu) / (2.0 * (1.0 - nu)))
    grid = np.arange(step, omega_max + step / 2, step)
    vals = _elastic_det(grid, n, inner_ratio, gamma, nu)
    roots: list[float] = []
    for i in np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0):
        root = brentq(
            lambda w: float(_elastic_det(w, n, inner_ratio, gamma, nu)),
            grid[i],
            grid[i + 1],
            xtol=1e-13,
            rtol=1e-13,
        )
        roots.append(float(root))
        if len(roots) == n_roots:
            break
    return np.array(roots)


# --------------------------------------------------------------------------------------
# the public entry
# --------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class ShellModes:
    """Axisymmetric eigenfrequencies of a free hollow sphere (one theory).

    Attributes:
        theory: ``"membrane"``, ``"thin"`` or ``"elastic"``.
        n: Legendre order of each mode.
        branch: 0, 1, ... in ascending frequency within its n (thin/membrane, n ≥ 2: 0 the
            bending-dominated, 1 the membrane-dominated branch; elastic: the k-th root).
            n = 1, branch 0 is the rigid translation, 0 Hz, in every theory.
        frequency_Hz: eigenfrequency of each mode, Hz.
        poisson_used: ν the computation used (differs from the ball's for ν = 0.5, elastic).
        density_kg_per_m3: ρ = M over the shell's volume.
    """

    theory: str
    n: tuple[int, ...]
    branch: tuple[int, ...]
    frequency_Hz: tuple[float, ...]
    poisson_used: float
    density_kg_per_m3: float

    def frequency(self, n: int, branch: int = 0) -> float:
        """The frequency of mode (n, branch), Hz; ``KeyError`` if it was not computed."""
        for nn, bb, f in zip(self.n, self.branch, self.frequency_Hz):
            if nn == n and bb == branch:
                return f
        raise KeyError(f"mode n={n}, branch={branch} not in this {self.theory} result")

    @property
    def fundamental_Hz(self) -> float:
        """The lowest elastic (non-zero) frequency."""
        return min(f for f in self.frequency_Hz if f > 0.0)

    def table(self) -> str:
        """A Markdown table: n, branch, frequency."""
        lines = [f"| n | branch | f ({self.theory}) (Hz) |", "|---|---|---|"]
        lines += [
            f"| {n} | {b} | {f:.1f} |" for n, b, f in zip(self.n, self.branch, self.frequency_Hz)
        ]
        return "\n".join(lines)


def shell_frequencies_Hz(
    ball: Ball = JIS_RUBBER_BALL, n_max: int = 4, theory: str = "elastic", *, n_roots: int = 2
) -> ShellModes:
    """Axisymmetric free-vibration frequencies of the ball's shell, n = 0 … ``n_max``.

    Args:
        ball: the ball (scalar fields): outer radius R, wall h, mass M (for ρ), E, ν.
        n_max: highest Legendre order (0 … 40).
        theory: ``"membrane"`` (thin, extensional only), ``"thin"`` (Love: membrane + bending)
            or ``"elastic"`` (exact 3-D elasticity of the hollow sphere); see the module doc.
        n_roots: roots per n of the elastic solution (the shell theories have two per n ≥ 1).

    Returns:
        :class:`ShellModes`, sorted by n then frequency. For the JIS ball (E = 1.6 MPa,
        ν = 0.5) the fundamental is n = 2, branch 0: 57.1 Hz (membrane), 68.7 Hz (thin) and
        65.2 Hz (exact elasticity), beside the paper's "around 60 Hz" (§4.1).
    """
    check_choice("theory", theory, THEORIES)
    n_max = _check_n_max(n_max)
    n_roots = _check_count("n_roots", n_roots)
    b = _scalar_ball(ball)
    R, h, E, nu = b["radius_m"], b["wall_m"], b["youngs_Pa"], b["poisson"]
    if not (R > 0 and 0 < h < R and E > 0 and b["mass_kg"] > 0):
        raise ValueError(
            f"ball: need R > 0, 0 < h < R, E > 0, M > 0; got R={R}, h={h}, E={E}, M={b['mass_kg']}"
        )
    _check_poisson(nu, True)
    rho = shell_density_kg_per_m3(ball)
    rows: list[tuple[int, int, float]] = []
    if theory in ("membrane", "thin"):
        a = R - h / 2.0
        c_p = math.sqrt(E / (rho * (1.0 - nu**2)))
        for n in range(n_max + 1):
            om = membrane_omega(n, nu) if theory == "membrane" else thin_shell_omega(n, nu, h / a)
            rows += [(n, k, float(w * c_p / (2.0 * math.pi * a))) for k, w in enumerate(om)]
        used = nu
    else:
        used = min(nu, INCOMPRESSIBLE_POISSON)
        c_s = math.sqrt(E / (2.0 * (1.0 + used)) / rho)
        for n in range(n_max + 1):
            om = elastic_sphere_omega(n, nu, (R - h) / R, n_roots=n_roots)
            freqs = [float(w * c_s / (2.0 * math.pi * R)) for w in om]
            if n == 1:
                freqs = [0.0, *freqs[: n_roots - 1]] if n_roots > 1 else [0.0]
            rows += [(n, k, f) for k, f in enumerate(freqs)]
    return ShellModes(
        theory=theory,
        n=tuple(r[0] for r in rows),
        branch=tuple(r[1] for r in rows),
        frequency_Hz=tuple(r[2] for r in rows),
        poisson_used=used,
        density_kg_per_m3=rho,
    )

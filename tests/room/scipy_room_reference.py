"""An independent numpy/scipy room chain: the rubber ball on a bare rectangular concrete slab,
heard in the room below. Nothing here calls rbjax (the ball is read by field name in
``scipy_floor_reference``); each step is written again from the physics, in a form of its own:

* **force**: the ball on the slab's infinite plate of the section, a dashpot of point impedance
  Z = 8√(B′m″) (Cremer, Heckl & Petersson, *Structure-Borne Sound*, §5.3), by
  ``scipy_floor_reference`` (its own ODE, DOP853), sampled at 44.1 kHz over the contact; its
  one-sided energy spectrum E_F(f) = 2|Σ F_n e^{−2πjfn/rate}/rate|².
* **bands**: octaves 31.5 Hz–1 kHz, IEC 61260-1 base ten (centres 1000·10^{3k/10} Hz, edges
  ×10^{∓3/20}); the 31.5 and 63 Hz octaves (nominal ≤ 100 Hz) follow the finite slab's modes,
  the others the infinite plate.
* **infinite plate**: the band energy W_b = ∫_b E_F df / Z, as the chain defines it: the rfft
  bins of the 1 s record (1 Hz apart, lower ≤ f < upper) summed; or (``band_rule="exact"``) by
  Simpson's rule on the DTFT (401 points a band), which differs from the bins by up to 1.3 %
  (0.06 dB) at 125 Hz and 2.4 % (0.1 dB) at 63 Hz: the bins cover [⌈f_lower⌉ − ½, ⌈f_upper⌉ − ½]
  where E_F falls steeply. It radiates with σ of ISO 12354-1:2017 Annex B (the large-plate
  branch, written out from the printed formulas) at the exact centre,
  η_rad = ρ₀c₀σ/(ωm″), decaying at ω(f^{−1/2} + 2η_rad) (in-situ loss of heavy structures,
  Craik 1996).
* **finite slab**: the modes (m, n ≤ ``ORDERS``) as products of beam functions
  φ = X_m(x/l_x) X_n(y/l_y), normalised ∫₀¹X² = 1: simply supported √2 sin mπz, clamped the
  classical cosh/cos/sinh/sin form with the roots of cos β cosh β = 1 by ``brentq``
  (Warburton 1954; Blevins 1979, Table 8-1). Each frequency by the plate's full Rayleigh
  quotient (bending energy with the Poisson terms over kinetic energy, every 1-D integral by
  ``quad``; exact for the sine modes), 1/m_k = φ(x₀, y₀)²/(m″l_xl_y), σ_k by the baffled
  plate's far-field integral (Williams, *Fourier Acoustics*, ch. 2) with the shape's
  wavenumber transform by Gauss–Legendre quadrature (a cubic spline in q), η_k =
  f_k^{−1/2} + 2η_rad,k, and the energy each takes in a band W_kb = ∫_b E_F Re Y_k df (Simpson
  on 1001 points a band), Re Y_k = η_kω_kω²/m_k / ((ω_k² − ω²)² + (η_kω_kω)²).
* **room and detector**: per source, the floor energy W e^{−at}, the radiated power into a
  diffuse field of energy E_r with dE_r/dt = P − bE_r, b = 6 ln 10/T (Sabine), p² = ρ₀c₀²E_r/V,
  the Fast detector dy/dt = (p² − y)/τ, τ = 0.125 s (IEC 61672-1): y is the convolution of
  three exponentials in partial fractions Σ_j e^{−r_jt}/Π_{l≠j}(r_l − r_j) (checked against
  ``solve_ivp`` in ``tests/room/test_chain.py``); its maximum over a grid refined by Brent's
  method; L_i,Fmax = 10 lg(max y/p₀²).
* **rating**: L_iA,Fmax = 10 lg Σ 10^{(L_k + A_k)/10} over the octaves 63–500 Hz with the
  A-weighted reference values of ISO 717-2:2020 Table D.3 (−26.2, −16.2, −8.7, −3.2 dB;
  Formula (D.1)).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
from scipy.integrate import quad, simpson
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq, minimize_scalar

from scipy_floor_reference import reference_floor_impact

#: Air (ISO 12354-1:2017: ρ₀ = 1.21 kg/m³, c₀ = 343 m/s), p₀ = 20 µPa, the Fast τ (s).
RHO0, C0, P0, TAU = 1.21, 343.0, 20e-6, 0.125
#: C30/37 concrete: E_cm (EN 1992-1-1 Table 3.1), ν (EN 1992-1-1 §3.1.3), ρ (EN ISO 10456).
YOUNGS, POISSON, DENSITY = 33e9, 0.2, 2300.0
RATE = 44100.0
CENTRES = 1000.0 * 10.0 ** (0.3 * np.arange(-5, 1))  # 31.6 … 1000 Hz
LOWER, UPPER = CENTRES * 10.0**-0.15, CENTRES * 10.0**0.15
MODAL = CENTRES < 100.0  # the 31.5 and 63 Hz octaves
#: ISO 717-2:2020 Table D.3, octaves 63–500 Hz, as printed.
TABLE_D3 = np.array([-26.2, -16.2, -8.7, -3.2])
RATING = slice(1, 5)
#: The mode set: m, n ≤ ORDERS (beyond four times the 63 Hz octave's upper edge for the slabs
#: of the tests: the modes left out add only the tails of their resonances).
ORDERS = 6


def plate_constants(thickness_m):
    """(B′, m″, Z, f_c): bending stiffness, mass per area, the infinite plate's point impedance
    8√(B′m″) and the critical frequency (c₀²/2π)√(m″/B′)."""
    bending = YOUNGS * thickness_m**3 / (12.0 * (1.0 - POISSON**2))
    mass = DENSITY * thickness_m
    return (
        bending,
        mass,
        8.0 * math.sqrt(bending * mass),
        C0**2 / (2 * math.pi) * math.sqrt(mass / bending),
    )


class Force:
    """The ball's force on the plate of ``thickness_m`` from ``height_m`` and its spectrum."""

    def __init__(self, ball, height_m, thickness_m):
        self.impedance = plate_constants(thickness_m)[2]
        ref = reference_floor_impact(height_m, ball, ("dashpot", self.impedance), grid=50)
        self.contact_time_s = ref.contact_time_s
        self.injected_energy_J = ref.injected_energy_J
        n = int(math.ceil(ref.contact_time_s * RATE)) + 2
        self.samples = ref.force_N(np.arange(n) / RATE)
        self._grids = {}

    def esd(self, freq_Hz):
        """E_F(f) = 2|F(f)|², N²·s/Hz, of the samples (their DTFT)."""
        freq = np.asarray(freq_Hz, dtype=float)
        phase = np.exp(-2j * np.pi * np.outer(freq.ravel(), np.arange(self.samples.size)) / RATE)
        return (2.0 * np.abs(phase @ self.samples / RATE) ** 2).reshape(freq.shape)

    def record_band_energy(self, band):
        """∫_b E_F df as the band energy of the 1 s record: its rfft bins (1 Hz apart,
        lower ≤ f < upper, weight 2 but 1 at DC) summed, times 1 Hz (the definition of the
        chain's infinite-plate bands, ``tests/room/test_chain.py``)."""
        n = int(RATE)
        freq = np.fft.rfftfreq(n, 1 / RATE)
        esd = 2 * np.abs(np.fft.rfft(self.samples, n=n) / RATE) ** 2
        esd[0] /= 2
        inside = (freq >= LOWER[band]) & (freq < UPPER[band])
        return esd[inside].sum() * RATE / n

    def band_grid(self, band, points):
        """(f, E_F(f)) on ``points`` equally spaced frequencies over the octave ``band``."""
        key = (band, points)
        if key not in self._grids:
            f = np.linspace(LOWER[band], UPPER[band], points)
            self._grids[key] = (f, self.esd(f))
        return self._grids[key]


def band_sigma(freq_Hz, critical_Hz, lx, ly):
    """σ of ISO 12354-1:2017 Annex B (EN 12354-1:2000 Annex B) of a baffled plate lx × ly."""
    f, fc = float(freq_Hz), critical_Hz
    f11 = C0**2 / (4 * fc) * (1 / lx**2 + 1 / ly**2)
    sigma1 = 1 / math.sqrt(1 - fc / f) if f > fc else math.inf
    sigma2 = 4 * lx * ly * (f / C0) ** 2
    sigma3 = math.sqrt(2 * math.pi * f * (lx + ly) / (16 * C0))
    if f11 > fc / 2:  # a small or thin plate: σ2 below f_c, σ1 above, at most σ3
        return min(sigma2 if f < fc else sigma1, sigma3, 2.0)
    if f > fc:
        return min(sigma1, sigma3, 2.0)
    lam = math.sqrt(f / fc)
    d1 = ((1 - lam**2) * math.log((1 + lam) / (1 - lam)) + 2 * lam) / (
        4 * math.pi**2 * (1 - lam**2) ** 1.5
    )
    d2 = (
        8 * C0**2 * (1 - 2 * lam**2) / (fc**2 * math.pi**4 * lx * ly * lam * math.sqrt(1 - lam**2))
        if f < fc / 2
        else 0.0
    )
    sigma = 2 * (lx + ly) * C0 / (lx * ly * fc) * d1 + d2
    if f < f11 and sigma2 < sigma:
        sigma = sigma2
    return min(sigma, 2.0)


@cache
def gauss_legendre(nodes):
    return np.polynomial.legendre.leggauss(nodes)


@cache
def beam(edge, order):
    """(X, X′, X″) of the normalised beam function of ``order`` with ``edge`` ends, and the
    integrals (∫X², ∫X′², ∫X″², ∫XX″) over [0, 1], and X̂(q) = ∫X e^{−iqz} dz as a spline."""
    if edge == "simply-supported":
        k = order * math.pi
        r2 = math.sqrt(2.0)

        def x(z):
            return r2 * np.sin(k * z)

        def dx(z):
            return r2 * k * np.cos(k * z)

        def ddx(z):
            return -r2 * k**2 * np.sin(k * z)

    else:
        guess = (order + 0.5) * math.pi
        b = brentq(lambda v: math.cos(v) * math.cosh(v) - 1.0, guess - 0.4, guess + 0.4, xtol=1e-15)
        s = (math.cosh(b) - math.cos(b)) / (math.sinh(b) - math.sin(b))
        raw = lambda z: np.cosh(b * z) - np.cos(b * z) - s * (np.sinh(b * z) - np.sin(b * z))  # noqa: E731
        norm = 1.0 / math.sqrt(quad(lambda z: raw(z) ** 2, 0, 1, limit=200, epsabs=0)[0])

        def x(z):
            return norm * raw(z)

        def dx(z):
            return (
                norm * b * (np.sinh(b * z) + np.sin(b * z) - s * (np.cosh(b * z) - np.cos(b * z)))
            )

        def ddx(z):
            return (
                norm
                * b**2
                * (np.cosh(b * z) + np.cos(b * z) - s * (np.sinh(b * z) + np.sin(b * z)))
            )

    def integral(g):
        return quad(g, 0.0, 1.0, limit=200, epsabs=0)[0]

    moments = (
        integral(lambda z: x(z) ** 2),
        integral(lambda z: dx(z) ** 2),
        integral(lambda z: ddx(z) ** 2),
        integral(lambda z: x(z) * ddx(z)),
    )
    zn, wn = gauss_legendre(160)
    z, w = 0.5 * (zn + 1.0), 0.5 * wn
    q = np.linspace(0.0, 160.0, 3201)
    transform = (np.exp(-1j * np.outer(q, z)) * (w * x(z))).sum(axis=1)
    return x, moments, CubicSpline(q, transform.real), CubicSpline(q, transform.imag)


def modes(thickness_m, edge, lx=4.0, ly=5.0, drive=None):
    """Per mode (m, n ≤ ORDERS): f_k (Hz), 1/m_k at the drive point (1/kg), σ_k, η_k, η_rad,k."""
    bending, mass, _, _ = plate_constants(thickness_m)
    x0, y0 = (lx / 2, ly / 2) if drive is None else drive
    an, aw = gauss_legendre(64)
    angle, weight = 0.25 * math.pi * (an + 1.0), 0.25 * math.pi * aw
    theta, psi = angle[:, None], angle[None, :]
    out = []
    for m in range(1, ORDERS + 1):
        xm, (a0, a1, a2, a02), xr, xi = beam(edge, m)
        for n in range(1, ORDERS + 1):
            yn, (b0, b1, b2, b02), yr, yi = beam(edge, n)
            # Rayleigh's quotient: B′∫∫[(w_xx + w_yy)² − 2(1 − ν)(w_xx w_yy − w_xy²)] / m″∫∫w²
            stiff = (
                a2 * b0 / lx**4
                + a0 * b2 / ly**4
                + 2 * a02 * b02 / (lx * ly) ** 2
                - 2 * (1 - POISSON) * (a02 * b02 - a1 * b1) / (lx * ly) ** 2
            )
            omega = math.sqrt(bending / mass * stiff / (a0 * b0))
            f = omega / (2 * math.pi)
            inverse_mass = float(xm(x0 / lx) * yn(y0 / ly)) ** 2 / (mass * lx * ly)
            # σ = (k² l_x l_y/π²) ∫∫ |X̂(k l_x sin θ cos ψ)|² |Ŷ(k l_y sin θ sin ψ)|² sin θ dθ dψ
            k = omega / C0
            qx = k * lx * np.sin(theta) * np.cos(psi)
            qy = k * ly * np.sin(theta) * np.sin(psi)
            integrand = (xr(qx) ** 2 + xi(qx) ** 2) * (yr(qy) ** 2 + yi(qy) ** 2) * np.sin(theta)
            sigma = k**2 * lx * ly / math.pi**2 * (weight @ integrand @ weight)
            eta_rad = RHO0 * C0 * sigma / (omega * mass)
            out.append((f, inverse_mass, sigma, f**-0.5 + 2 * eta_rad, eta_rad))
    return np.array(out).T


def cascade_peak(amplitudes, rates, room_rate):
    """max_t of y(t) = Σ_i A_i conv(e^{−a_i t}, e^{−bt}, e^{−t/τ}) (partial fractions) and its
    time."""
    g = 1.0 / TAU
    amplitudes, rates = np.asarray(amplitudes, float), np.asarray(rates, float)

    def y(t):
        t = np.atleast_1d(np.asarray(t, float))[:, None]
        a, b = rates[None, :], room_rate
        h = (
            np.exp(-a * t) / ((b - a) * (g - a))
            + np.exp(-b * t) / ((a - b) * (g - b))
            + np.exp(-g * t) / ((a - g) * (b - g))
        )
        return (h * amplitudes[None, :]).sum(axis=1)

    grid = np.linspace(0.0, 2.0, 4001)
    i = int(np.argmax(y(grid)))
    best = minimize_scalar(
        lambda t: -float(y(t)[0]),
        bounds=(grid[max(i - 1, 0)], grid[i + 1]),
        method="bounded",
        options={"xatol": 1e-10},
    )
    return -float(best.fun), float(best.x)


def levels(force, thickness_m, *, edge="clamped", volume=50.0, reverberation=0.5, drive=None,
           slab="modal", lx=4.0, ly=5.0, band_rule="record"):  # fmt: skip
    """L_i,Fmax per octave 31.5 Hz–1 kHz (dB) of ``force`` on the bare slab; the infinite
    plate's band energies by the 1 s record's bins (``band_rule="record"``) or by Simpson's
    rule on the DTFT (``"exact"``)."""
    _, mass, z, fc = plate_constants(thickness_m)
    b = 6.0 * math.log(10.0) / reverberation
    kappa = RHO0 * C0**2 / volume
    if slab == "modal":
        fk, inv_m, _, eta, eta_rad = modes(thickness_m, edge, lx, ly, drive)
        wk = 2 * np.pi * fk
    out = []
    for band, centre in enumerate(CENTRES):
        if slab == "modal" and MODAL[band]:
            f, esd = force.band_grid(band, 1001)
            w = 2 * np.pi * f[None, :]
            re_y = (
                inv_m[:, None]
                * eta[:, None]
                * wk[:, None]
                * w**2
                / ((wk[:, None] ** 2 - w**2) ** 2 + (eta[:, None] * wk[:, None] * w) ** 2)
            )
            energy = simpson(esd[None, :] * re_y, x=f, axis=1)
            decay, radiate = wk * eta, wk * eta_rad
        else:
            if band_rule == "record":
                energy = np.array([force.record_band_energy(band) / z])
            else:
                f, esd = force.band_grid(band, 401)
                energy = np.array([simpson(esd, x=f) / z])
            sigma = band_sigma(centre, fc, lx, ly)
            omega = 2 * math.pi * centre
            eta_rad = RHO0 * C0 * sigma / (omega * mass)
            decay = np.array([omega * (centre**-0.5 + 2 * eta_rad)])
            radiate = np.array([omega * eta_rad])
        peak, _ = cascade_peak(kappa / TAU * radiate * energy, decay, b)
        out.append(10 * math.log10(peak / P0**2))
    return np.array(out)


def rating(levels_dB):
    """L_iA,Fmax unrounded: 10 lg Σ 10^{(L + A)/10} over 63–500 Hz (ISO 717-2 Formula (D.1))."""
    return 10 * math.log10(np.sum(10 ** ((np.asarray(levels_dB)[RATING] + TABLE_D3) / 10)))

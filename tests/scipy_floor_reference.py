"""An independent scipy reference for the rubber ball on a floor that moves under it.

Nothing here calls rbjax (floors and balls are read by field name only). The equations are
written again from the physics, in state variables of their own: the position X and velocity
Ẋ of the ball's moving part (downward positive, from first contact), the floor's surface
displacement u (a dashpot floor) or its modal coordinates q_k, q̇_k (a modal floor), and the
work W = ∫F u̇ dt done on the floor. rbjax integrates the deflection δ and δ̇ and solves its
closed form for δ̈; here δ and δ̇ are outputs only.

* The ball (paper §2, Eqs. 1–9): the shell force k δ (Reissner, Eq. 3 corrected) and the
  adiabatic gas force (Eq. 4 corrected) of ``scipy_reference``; the flattened cap
  M_c = Mδ/2R rests on the floor and moves with it, so the moving part of mass M − M_c obeys

      (M − M_c) Ẍ = −F_c(δ) + (M/2R) δ̇² H(−δ̇),      δ = X − u,  δ̇ = Ẋ − u̇.

* The floor receives F = F_c(δ) + w (M/2R) δ̇² H(δ̇) (w = 0 "paper", w = 1 "momentum": the
  floor also stops the mass joining the cap).
* Dashpot floor (massless, real point impedance Z; an infinite thin plate has
  Z = 8√(B′m″), Cremer–Heckl): u̇ = F/Z. F depends on δ̇ = Ẋ − u̇ (the momentum share), so
  u̇ is the root of g(s) = Z s − F(δ, Ẋ − s), found by ``scipy.optimize.brentq`` in every
  right-hand-side call: g increases with s, and the root lies between 0 and F(δ, Ẋ)/Z.
* Modal floor: u = Σ q_k, m_k (q̈_k + η_k ω_k q̇_k + ω_k² q_k) = F, every q_k(0) = q̇_k(0) = 0.

Contact starts at X = u = 0 with Ẋ = √(2 g h). The solve is split at maximum compression
(δ̇ = 0, a terminal event) and ends at δ = 0. Outputs: contact time, peak floor force (the
global maximum of F over the contact: every local maximum of F on a fine grid of the dense
output refined by Brent's method, with t = 0 and maximum compression as candidates),
restitution −(M − M_c)Ẋ_end/(M v0), and the injected energy W = ∫F u̇ dt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from scipy_reference import RTOL, STANDARD_GRAVITY, ball_parameters, gas_force, shell_stiffness


def floor_spec(floor):
    """('rigid',) | ('dashpot', Z) | ('modal', masses, frequencies, loss factors) from an rbjax
    floor (read by field name) or such a tuple. An infinite plate becomes a dashpot of
    Z = 8√(B′m″), B′ = E t³/(12(1 − ν²)), m″ = ρ t, computed here."""
    if isinstance(floor, tuple):
        return floor
    if floor is None or type(floor).__name__ == "Rigid":
        return ("rigid",)
    if hasattr(floor, "floor_impedance_Ns_per_m"):
        return ("dashpot", float(floor.floor_impedance_Ns_per_m))
    if hasattr(floor, "plate_thickness_m"):
        t, e, rho, nu = (
            float(getattr(floor, f"plate_{n}"))
            for n in ("thickness_m", "youngs_Pa", "density_kg_per_m3", "poisson")
        )
        return ("dashpot", 8.0 * math.sqrt(e * t**3 / (12.0 * (1.0 - nu**2)) * rho * t))
    if hasattr(floor, "frequency_Hz"):
        return (
            "modal",
            np.asarray(floor.mass_kg, float),
            np.asarray(floor.frequency_Hz, float),
            np.asarray(floor.loss_factor, float),
        )
    raise TypeError(f"unknown floor {floor!r}")


@dataclass
class FloorReference:
    """Scalar results of one reference impact on a floor, and its dense solution."""

    height_m: float
    contact_time_s: float
    peak_force_N: float
    peak_time_s: float
    restitution: float
    injected_energy_J: float
    impact_energy_J: float
    max_deflection_m: float
    max_compression_time_s: float
    force_maxima_N: list
    phases: list = field(repr=False)
    kinematics: object = field(repr=False)

    def state(self, t):
        """The state (X, Ẋ, floor states..., W) at one time in [0, t_c]."""
        for t0, t1, sol in self.phases:
            if t <= t1:
                return sol(min(max(t, t0), t1))
        return self.phases[-1][2](self.phases[-1][1])

    def force_N(self, times_s):
        """The floor force at the given times (0 outside the contact)."""
        t = np.atleast_1d(np.asarray(times_s, dtype=float))
        out = np.zeros(t.size)
        for i, ti in enumerate(t):
            if 0.0 <= ti < self.contact_time_s:
                out[i] = self.kinematics(self.state(ti))[2]
        return out


def reference_floor_impact(
    height_m,
    ball,
    floor,
    *,
    gas="adiabatic",
    blocked_force="paper",
    rtol=RTOL,
    method="DOP853",
    grid=4000,
):
    """Solve one drop of ``ball`` from ``height_m`` on ``floor`` (see the module docstring)."""
    if gas not in ("adiabatic", "none"):
        raise ValueError(gas)
    weight = {"paper": 0.0, "momentum": 1.0}[blocked_force]
    spec = floor_spec(floor)
    kind = spec[0]
    radius, wall, mass, youngs, poisson = ball_parameters(ball)
    k = shell_stiffness(radius, wall, youngs, poisson)
    c = mass / (2.0 * radius)
    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * float(height_m))

    def contact_force(d):
        f = k * d
        if gas == "adiabatic":
            f = f + gas_force(d, radius)
        return f

    def floor_force(d, dd):
        return contact_force(d) + (weight * c * dd * dd if dd > 0.0 else 0.0)

    if kind == "rigid":
        n_floor = 0
    elif kind == "dashpot":
        z = spec[1]
        n_floor = 1
    elif kind == "modal":
        mk, fk, eta = (np.asarray(a, float) for a in spec[1:])
        eta = np.broadcast_to(eta, mk.shape)
        wk = 2.0 * math.pi * fk
        n_modes = mk.size
        n_floor = 2 * n_modes
    else:
        raise ValueError(kind)

    def kinematics(y):
        """(δ, δ̇, F, u̇) of state y = (X, Ẋ, floor states, W)."""
        x, xd = y[0], y[1]
        if kind == "rigid":
            return x, xd, floor_force(x, xd), 0.0
        if kind == "dashpot":
            d = x - y[2]
            f0 = floor_force(d, xd)
            if f0 == 0.0 or weight == 0.0 or xd <= 0.0:
                # F does not depend on δ̇ here (δ̇ ≤ Ẋ ≤ 0 or no momentum share): explicit
                s = f0 / z
            else:
                # widened by 1e-12 so that round-off cannot put the root on the bracket's end
                lo, hi = sorted((0.0, f0 / z * (1.0 + 1e-12)))
                s = brentq(
                    lambda s: z * s - floor_force(d, xd - s),
                    lo,
                    hi,
                    xtol=1e-300,
                    rtol=8.9e-16,
                    maxiter=200,
                )
            return d, xd - s, z * s, s
        q, qd = y[2 : 2 + n_modes], y[2 + n_modes : 2 + 2 * n_modes]
        ud = float(np.sum(qd))
        d, dd = x - float(np.sum(q)), xd - ud
        return d, dd, floor_force(d, dd), ud

    def rhs(t, y):
        d, dd, f, ud = kinematics(y)
        thrust = c * dd * dd if dd < 0.0 else 0.0
        xdd = (thrust - contact_force(d)) / (mass * (1.0 - d / (2.0 * radius)))
        rates = [y[1], xdd]
        if kind == "dashpot":
            rates.append(ud)
        elif kind == "modal":
            q, qd = y[2 : 2 + n_modes], y[2 + n_modes : 2 + 2 * n_modes]
            rates.extend(qd)
            rates.extend(f / mk - eta * wk * qd - wk**2 * q)
        rates.append(f * ud)
        return np.asarray(rates, dtype=float)

    omega = math.sqrt(k / mass)
    x_scale = v0 / omega
    scales = (
        [x_scale, v0]
        + ([x_scale] * (n_floor // 2 or n_floor))
        + ([v0] * (n_floor // 2 if kind == "modal" else 0))
        + [0.5 * mass * v0**2]
    )
    atol = np.asarray(scales) * rtol * 1e-3
    t_span = 1e3 / omega

    def max_compression(t, y):
        return kinematics(y)[1]

    def separation(t, y):
        return kinematics(y)[0]

    max_compression.terminal, max_compression.direction = True, -1.0
    separation.terminal, separation.direction = True, -1.0

    def solve(t0, y0, event):
        sol = solve_ivp(
            rhs,
            (t0, t0 + t_span),
            y0,
            method=method,
            rtol=rtol,
            atol=atol,
            events=[event],
            dense_output=True,
        )
        if sol.status != 1:
            raise RuntimeError(f"reference solve did not reach its terminal event: {sol.message}")
        return sol

    y0 = np.zeros(3 + n_floor)
    y0[1] = v0
    sol1 = solve(0.0, y0, max_compression)
    t_max = float(sol1.t[-1])
    sol2 = solve(t_max, sol1.y[:, -1].copy(), separation)
    t_end = float(sol2.t[-1])
    y_end = sol2.y[:, -1]
    phases = [(0.0, t_max, sol1.sol), (t_max, t_end, sol2.sol)]

    def force_at(t):
        for t0, t1, sol in phases:
            if t <= t1:
                return kinematics(sol(min(max(t, t0), t1)))[2]
        return 0.0

    # Local maxima of F: a fine grid, then Brent's method between the grid neighbours.
    ts = np.linspace(0.0, t_end, grid + 1)
    fs = np.array([force_at(t) for t in ts])
    candidates = [(0.0, fs[0]), (t_max, force_at(t_max))]
    maxima = []
    for i in range(1, grid):
        if fs[i] >= fs[i - 1] and fs[i] > fs[i + 1]:
            opt = minimize_scalar(
                lambda t: -force_at(t),
                bounds=(ts[i - 1], ts[i + 1]),
                method="bounded",
                options={"xatol": 1e-14 * t_end},
            )
            tm, fm = float(opt.x), -float(opt.fun)
            if fm < fs[i]:
                tm, fm = float(ts[i]), float(fs[i])
            maxima.append(fm)
            candidates.append((tm, fm))
    best = max(candidates, key=lambda p: p[1])
    d_end = kinematics(y_end)[0]
    restitution = -(mass * (1.0 - d_end / (2.0 * radius))) * y_end[1] / (mass * v0)
    return FloorReference(
        height_m=float(height_m),
        contact_time_s=t_end,
        peak_force_N=float(best[1]),
        peak_time_s=float(best[0]),
        restitution=float(restitution),
        injected_energy_J=float(y_end[-1]),
        impact_energy_J=0.5 * mass * v0**2,
        max_deflection_m=float(kinematics(sol1.y[:, -1])[0]),
        max_compression_time_s=t_max,
        force_maxima_N=maxima,
        phases=phases,
        kinematics=kinematics,
    )


def linear_oscillator_on_dashpot(height_m, mass_kg, stiffness_N_per_m, impedance_Ns_per_m):
    """Closed form for a mass M on a linear spring k, the spring's foot on a dashpot Z
    (no cap terms, no gas): M Ẍ = −kδ, Z u̇ = kδ, δ = X − u, so

        δ̈ + (k/Z) δ̇ + (k/M) δ = 0,   δ(0) = 0, δ̇(0) = v0   (u̇(0) = kδ(0)/Z = 0),

    a damped oscillator with ω0² = k/M, ζ = √(kM)/(2Z) (underdamped: ζ < 1):
    δ = (v0/ω_d) e^(−ζω0 t) sin ω_d t. Contact ends at δ = 0, t_c = π/ω_d; the force kδ peaks
    at δ̇ = 0, tan ω_d t = ω_d/(ζω0); the rebound speed is −Ẋ(t_c) = −δ̇(t_c) = v0 e^(−ζω0 t_c)
    (restitution e^(−πζ/√(1−ζ²))), and the floor took the energy lost, ½Mv0²(1 − e²).
    """
    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * height_m)
    w0 = math.sqrt(stiffness_N_per_m / mass_kg)
    zeta = math.sqrt(stiffness_N_per_m * mass_kg) / (2.0 * impedance_Ns_per_m)
    if zeta >= 1.0:
        raise ValueError("overdamped: the spring never returns to zero length")
    wd = w0 * math.sqrt(1.0 - zeta**2)
    a = zeta * w0
    t_peak = math.atan2(wd, a) / wd
    peak = stiffness_N_per_m * v0 / wd * math.exp(-a * t_peak) * math.sin(wd * t_peak)
    e = math.exp(-a * math.pi / wd)
    return {
        "contact_time_s": math.pi / wd,
        "peak_force_N": peak,
        "peak_time_s": t_peak,
        "restitution": e,
        "injected_energy_J": 0.5 * mass_kg * v0**2 * (1.0 - e**2),
        "damping_ratio": zeta,
    }


def linear_oscillator_expm(height_m, mass_kg, stiffness_N_per_m, impedance_Ns_per_m, times_s):
    """The same system by the matrix exponential of its state matrix in (X, Ẋ, u): the
    deflection X − u at the given times (a cross-check of the closed form)."""
    from scipy.linalg import expm

    m, k, z = mass_kg, stiffness_N_per_m, impedance_Ns_per_m
    a = np.array([[0.0, 1.0, 0.0], [-k / m, 0.0, k / m], [k / z, 0.0, -k / z]])
    y0 = np.array([0.0, math.sqrt(2.0 * STANDARD_GRAVITY * height_m), 0.0])
    return np.array([(lambda y: y[0] - y[2])(expm(a * t) @ y0) for t in np.atleast_1d(times_s)])

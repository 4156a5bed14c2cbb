"""An independent scipy reference for a contact layer in series with the shell and the arrest
of the wall column, on the rigid floor. Nothing here calls rbjax; the shell and gas forces are
``scipy_reference``'s (the paper's §2, written again there).

* The layer: a massless spring F = K y^p, K = F_ref / y_ref^p (F_ref = 1 kN), pressed in
  series with the shell and the gas: δ = u + y and F_e(u) = K y^p, F_e(u) = k u (+ F_G(u)).
  The shell's compression u is the root of g(u) = K(δ − u)^p − F_e(u) on [0, δ] (brentq; g
  falls from Kδ^p to −F_e(δ)), F(δ) = F_e(u). Its stiffness is that of two springs in series,
  dF/dδ = k_s k_l / (k_s + k_l), k_s = F_e′(u), k_l = K p y^(p−1).
* The arrest: the column of wall above the contact area 2πRδ, of density
  ρ = M / (4π(R³ − (R − h)³)/3), has the mass μ = 2πRhρ per unit deflection; the floor
  receives the share s = x^n / (1 + x^n), x = δ̇/v_a, of its flux μδ̇² while δ̇ > 0.
* Equation of motion (Eq. 7, Eqs. 6, 8, 9 as in ``scipy_reference``), with the cap's mass per
  unit deflection m′ = M/2R (the paper's thin shell) or, with an arrest, the column μ:
  (M − m′δ) δ̈ = −F_c + m′ δ̇² H(−δ̇),  F_c = F(δ) + c δ̇ (Kelvin–Voigt, c ≥ 0);
  the floor force is F_c + s μ δ̇² H(δ̇).

Phases and outputs, defined as rbjax defines them (``rbjax.solve.ode``):

* compression from δ = 0, δ̇ = √(2 g h_D) to δ̇ = 0; every fall of dF/dt through 0 in it
  (dF/dt written out along the flow: dF/dδ δ̇ + (c + dflux/dδ̇) δ̈) is a local maximum of the
  floor force; the peak force is the largest of the floor force at these, at maximum compression
  and at first contact (a steep arrest share makes a first local maximum where δ̇ passes v_a);
* restitution from rest at maximum compression to the first fall of F_c (or of δ) through 0:
  the contact time;
* restitution coefficient (M − m′δ_end)(−δ̇_end) / (M v0).

``ReferenceImpact.global_peak_N`` is the largest floor force over the compression on a dense
grid and at the maxima, to check that the peak so defined is the maximum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from scipy_reference import ball_parameters, gas_force, shell_stiffness

STANDARD_GRAVITY = 9.80665
REFERENCE_FORCE_N = 1000.0
RTOL = 1e-12
_COMPLEX_STEP = 1e-30


def column_mass_rate(radius_m, wall_m, mass_kg):
    """μ = 2πRhρ, ρ = M / (4π(R³ − (R − h)³)/3): the wall's mass per unit deflection (kg/m)."""
    density = mass_kg / (4.0 * math.pi * (radius_m**3 - (radius_m - wall_m) ** 3) / 3.0)
    return 2.0 * math.pi * radius_m * wall_m * density


def arrest_share(velocity, speed, exponent):
    """s = x^n / (1 + x^n), x = δ̇/v_a, for δ̇ > 0; 0 otherwise."""
    if velocity <= 0.0:
        return 0.0
    x = (velocity / speed) ** exponent
    return x / (1.0 + x)


def arrest_share_rate(velocity, speed, exponent):
    """ds/dδ̇ = (n/v_a) x^(n−1) / (1 + x^n)² for δ̇ > 0; 0 otherwise."""
    if velocity <= 0.0:
        return 0.0
    x = velocity / speed
    return exponent / speed * x ** (exponent - 1.0) / (1.0 + x**exponent) ** 2


class SeriesLaw:
    """The elastic law F(δ) of a layer F = K y^p in series with the shell (and the gas)."""

    def __init__(self, ball, layer_deflection_m, layer_exponent, gas="adiabatic"):
        if gas not in ("adiabatic", "none"):
            raise ValueError(gas)
        self.radius, self.wall, self.mass, youngs, poisson = ball_parameters(ball)
        self.k = shell_stiffness(self.radius, self.wall, youngs, poisson)
        self.gas = gas == "adiabatic"
        self.p = float(layer_exponent)
        self.stiff = REFERENCE_FORCE_N / float(layer_deflection_m) ** self.p  # K

    def shell(self, u):
        """F_e(u) = k u (+ F_G(u))."""
        return self.k * u + (gas_force(u, self.radius) if self.gas else 0.0)

    def shell_stiffness(self, u):
        """F_e′(u), the gas's by a complex step."""
        if not self.gas:
            return self.k
        h = _COMPLEX_STEP
        return self.k + float(np.imag(gas_force(complex(u, h), self.radius)) / h)

    def compression(self, deflection_m):
        """u, the shell's compression under δ (0 for δ ≤ 0)."""
        d = float(deflection_m)
        if d <= 0.0:
            return 0.0

        def g(u):
            return self.stiff * max(d - u, 0.0) ** self.p - self.shell(u)

        return brentq(g, 0.0, d, xtol=1e-300, rtol=4.0 * np.finfo(float).eps, maxiter=500)

    def force(self, deflection_m):
        """F(δ) (0 for δ ≤ 0)."""
        return self.shell(self.compression(deflection_m)) if deflection_m > 0.0 else 0.0

    def stiffness(self, deflection_m):
        """dF/dδ = k_s k_l / (k_s + k_l) (k_l(0) = K for p = 1, 0 for p > 1)."""
        d = max(float(deflection_m), 0.0)
        u = self.compression(d)
        y = max(d - u, 0.0)
        k_l = self.stiff * self.p * y ** (self.p - 1.0) if (y > 0.0 or self.p == 1.0) else 0.0
        k_s = self.shell_stiffness(u)
        return k_s * k_l / (k_s + k_l)


@dataclass
class ReferenceImpact:
    height_m: float
    contact_time_s: float
    peak_force_N: float
    peak_time_s: float
    first_force_N: float
    restitution: float
    max_deflection_m: float
    global_peak_N: float
    end_state: np.ndarray
    rebound_energy_J: float
    flux_loss_J: float
    contact_work_J: float
    phases: list = field(repr=False)


def reference_impact(
    height_m,
    ball,
    layer=None,
    arrest=None,
    *,
    damping_Ns_per_m=0.0,
    gas="adiabatic",
    rtol=RTOL,
    column_cap=None,
):
    """One impact: ``layer`` = (y_ref, p) or None (F_e alone), ``arrest`` = (v_a, n), ``"full"``
    (s = 1: the column's whole flux μδ̇²) or None (the paper's blocked force, no flux on the
    floor), Kelvin–Voigt ``damping_Ns_per_m``; ``column_cap`` (default: whether an arrest is
    given) takes the column μ for the cap's mass per unit deflection m′, else M/2R.

    The state carries two integrals besides (δ, δ̇): ∫½m′|δ̇|³ dt and ∫F_c δ̇ dt.
    """
    radius, wall, mass, youngs, poisson = ball_parameters(ball)
    c = float(damping_Ns_per_m)
    if layer is None:
        k = shell_stiffness(radius, wall, youngs, poisson)
        law = None

        def elastic(d):
            return k * d + (gas_force(d, radius) if gas == "adiabatic" and d > 0 else 0.0)

        def elastic_rate(d):
            if gas != "adiabatic":
                return k
            return k + float(np.imag(gas_force(complex(d, _COMPLEX_STEP), radius)) / _COMPLEX_STEP)
    else:
        law = SeriesLaw(ball, layer[0], layer[1], gas)
        elastic, elastic_rate = law.force, law.stiffness

    mu = column_mass_rate(radius, wall, mass)
    if column_cap is None:
        column_cap = arrest is not None
    per_speed = mu if column_cap else mass / (2.0 * radius)

    def share(v):
        return 1.0 if arrest == "full" else arrest_share(v, *arrest)

    def share_rate(v):
        return 0.0 if arrest == "full" else arrest_share_rate(v, *arrest)

    def flux(v):
        if arrest is None or v <= 0.0:
            return 0.0
        return share(v) * mu * v * v

    def flux_rate(v):
        if arrest is None or v <= 0.0:
            return 0.0
        return mu * (share_rate(v) * v * v + 2.0 * share(v) * v)

    def contact_force(y):
        return elastic(y[0]) + c * y[1]

    def floor_force(y):
        return contact_force(y) + flux(y[1])

    def rhs(flux_on):
        def f(t, y):
            d, v = y[0], y[1]
            force = contact_force(y)
            thrust = per_speed * v * v if (flux_on and v < 0.0) else 0.0
            accel = (thrust - force) / (mass - per_speed * d)
            return np.array([v, accel, 0.5 * per_speed * abs(v) ** 3, force * v])

        return f

    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * float(height_m))
    omega = math.sqrt(shell_stiffness(radius, wall, youngs, poisson) / mass)
    d_scale = v0 / omega
    energy = 0.5 * mass * v0**2
    atol = np.array([d_scale, v0, energy, energy]) * rtol * 1e-3
    t_span = 1e3 / omega
    f1, f2 = rhs(False), rhs(True)

    def force_rate(t, y):
        accel = f1(t, y)[1]
        return elastic_rate(y[0]) * y[1] + (c + flux_rate(y[1])) * accel

    force_rate.terminal, force_rate.direction = False, -1.0

    def max_compression(t, y):
        return y[1]

    max_compression.terminal, max_compression.direction = True, -1.0

    y0 = np.array([0.0, v0, 0.0, 0.0])
    sol1 = solve_ivp(
        f1,
        (0.0, t_span),
        y0,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        events=[max_compression, force_rate],
        dense_output=True,
    )
    if sol1.status != 1:
        raise RuntimeError(f"compression did not reach maximum compression: {sol1.message}")
    t_max = float(sol1.t[-1])
    y_max = sol1.y[:, -1].copy()
    y_max[1] = 0.0
    first = floor_force(y0)
    maxima = [t for t in sol1.t_events[1] if 0.0 < t < t_max]
    candidates = [(floor_force(sol1.sol(t)), t) for t in maxima] + [(floor_force(y_max), t_max)]
    peak, t_peak = max(candidates)
    if first > peak:
        peak, t_peak = first, 0.0
    grid = np.linspace(0.0, t_max, 4001)
    global_peak = max(floor_force(sol1.sol(t)) for t in grid)
    global_peak = max(global_peak, *(floor_force(sol1.sol(t)) for t in maxima), first)

    def deflection(t, y):
        return y[0]

    def contact(t, y):
        return contact_force(y)

    deflection.terminal, deflection.direction = True, -1.0
    contact.terminal, contact.direction = True, -1.0
    sol2 = solve_ivp(
        f2,
        (t_max, t_max + t_span),
        y_max,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        events=[deflection, contact] if c > 0.0 else [deflection],
        dense_output=True,
    )
    if sol2.status != 1:
        raise RuntimeError(f"restitution did not reach the end of contact: {sol2.message}")
    t_end = float(sol2.t[-1])
    y_end = sol2.y[:, -1]
    moving = mass - per_speed * y_end[0]
    return ReferenceImpact(
        height_m=float(height_m),
        contact_time_s=t_end,
        peak_force_N=float(peak),
        peak_time_s=float(t_peak),
        first_force_N=float(first),
        restitution=moving * (-y_end[1]) / (mass * v0),
        max_deflection_m=float(y_max[0]),
        global_peak_N=float(global_peak),
        end_state=np.asarray(y_end),
        rebound_energy_J=0.5 * moving * y_end[1] ** 2,
        flux_loss_J=float(y_end[2]),
        contact_work_J=float(y_end[3]),
        phases=[sol1, sol2],
    )

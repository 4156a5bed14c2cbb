"""An independent reference for the rubber-ball impact, written from the physics with scipy.

Nothing here calls rbjax: the force terms, the equation of motion and the phase logic are
written again from the paper (Schoenwald, Zeitler & Nightingale 2011, §2) so that the tests
compare two implementations, not one implementation with itself.

* Shell force, Eqs. 1–3 (Eq. 3 corrected, h_r = h/√(12(1−ν²))): F_B = k δ,
  k = 8B/(R h_r) = 4 E h² / (R √(3(1−ν²))), B = E h³/(12(1−ν²)).
* Gas force, Eq. 4 (corrected): adiabatic over-pressure p_a((V0/V)^γ − 1) of the vented cavity
  V0 = 4πR³/3 that loses the cap volume πδ²(3R−δ)/3, acting on the flattened area πδ(2R−δ).
* Damping extensions: Kelvin–Voigt F_d = c δ̇; Hunt–Crossley (n = 1) F_d = α k δ δ̇;
  Zener: a Maxwell branch F_M with dF_M/dt = r k δ̇ − F_M/τ, F_d = F_M.
* Equation of motion, Eq. 7 with Eqs. 6, 8, 9:
  M(1 − δ/2R) δ̈ − (M/2R) δ̇² H(−δ̇) = −(F_B + F_G + F_d), δ(0) = 0, δ̇(0) = √(2 g h_D) (Eq. 10).

The solve is split at maximum compression (δ̇ = 0, a terminal event), where the momentum
flux term switches on. Contact ends at δ = 0 (elastic) or where the contact force returns to
zero or δ = 0 (damped). The floor-force maxima are located by a non-terminal event on dF/dt,
with dF/dt evaluated exactly along the flow by a complex-step derivative.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

AMBIENT_PRESSURE_Pa = 101_325.0
GAMMA_AIR = 1.4
STANDARD_GRAVITY = 9.80665
RTOL = 1e-12
_COMPLEX_STEP_S = 1e-30


def ball_parameters(ball):
    """(R, h, M, E, ν) as floats from any object with the rbjax Ball field names."""
    return tuple(
        float(getattr(ball, name))
        for name in ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")
    )


def shell_stiffness(radius_m, wall_m, youngs_Pa, poisson):
    """Reissner's k = 8B/(R h_r) with B = Eh³/(12(1−ν²)), h_r = h/√(12(1−ν²)) (Eqs. 1–3)."""
    return 4.0 * youngs_Pa * wall_m**2 / (radius_m * math.sqrt(3.0 * (1.0 - poisson**2)))


def gas_force(deflection_m, radius_m):
    """Adiabatic gas force of the vented cavity (Eq. 4, corrected); complex-safe."""
    d, r = deflection_m, radius_m
    v0 = 4.0 * math.pi * r**3 / 3.0
    cap = math.pi * d**2 * (3.0 * r - d) / 3.0
    return (
        AMBIENT_PRESSURE_Pa * ((v0 / (v0 - cap)) ** GAMMA_AIR - 1.0) * math.pi * d * (2.0 * r - d)
    )


def damping_spec(damping):
    """Normalise a damping description to ('kv', c) | ('hc', α) | ('zener', r, τ) | None.

    Accepts the rbjax damping pytrees (read by field name only) or such tuples.
    """
    if isinstance(damping, tuple) and all(hasattr(d, "force_N") for d in damping):  # a Model's laws
        if len(damping) > 1:
            raise NotImplementedError("the reference has one damping law at a time")
        damping = damping[0] if damping else None
    if damping is None or isinstance(damping, tuple):
        return damping
    if hasattr(damping, "damping_Ns_per_m"):
        return ("kv", float(damping.damping_Ns_per_m))
    if hasattr(damping, "alpha_s_per_m"):
        if float(getattr(damping, "exponent", 1.0)) != 1.0:
            raise NotImplementedError("the reference has Hunt–Crossley with n = 1 only")
        return ("hc", float(damping.alpha_s_per_m))
    if hasattr(damping, "relaxation_time_s"):
        return ("zener", float(damping.stiffness_ratio), float(damping.relaxation_time_s))
    raise TypeError(f"unknown damping {damping!r}")


@dataclass
class _Phase:
    t0: float
    t1: float
    solution: object  # scipy OdeSolution
    flux_on: bool


@dataclass
class ReferenceImpact:
    """Scalar results of one reference impact and its dense solution."""

    height_m: float
    contact_time_s: float
    peak_force_N: float
    peak_time_s: float
    restitution: float
    max_deflection_m: float
    max_compression_time_s: float
    impact_velocity_m_per_s: float
    end_state: np.ndarray
    phases: list = field(repr=False)
    floor_force: object = field(repr=False)

    def state(self, times_s):
        """State (δ, δ̇[, F_M]) at the given times; zeros outside the contact [0, t_c)."""
        t = np.atleast_1d(np.asarray(times_s, dtype=float))
        n = self.phases[0].solution(0.0).shape[0]
        y = np.zeros((n, t.size))
        first, second = self.phases
        in1 = (t >= 0.0) & (t <= first.t1)
        in2 = (t > first.t1) & (t < second.t1)
        if np.any(in1):
            y[:, in1] = first.solution(t[in1])
        if np.any(in2):
            y[:, in2] = second.solution(t[in2])
        return y

    def force_N(self, times_s):
        """The blocked floor force at the given times (0 outside the contact)."""
        t = np.atleast_1d(np.asarray(times_s, dtype=float))
        y = self.state(t)
        inside = (t >= 0.0) & (t < self.contact_time_s)
        return np.where(inside, self.floor_force(y), 0.0)


def reference_impact(
    height_m,
    ball,
    *,
    gas="adiabatic",
    blocked_force="paper",
    damping=None,
    rtol=RTOL,
    method="DOP853",
):
    """Solve Eq. 7 for one drop with scipy (see the module docstring).

    Returns a ``ReferenceImpact`` with the contact time, peak floor force (and its time),
    restitution coefficient M(1 − δ_end/2R)|δ̇_end| / (M v0), maximum deflection, and a dense
    solution for the force history.
    """
    if gas not in ("adiabatic", "none"):
        raise ValueError(gas)
    if blocked_force not in ("paper", "momentum"):
        raise ValueError(blocked_force)
    radius, wall, mass, youngs, poisson = ball_parameters(ball)
    k = shell_stiffness(radius, wall, youngs, poisson)
    spec = damping_spec(damping)
    kind = None if spec is None else spec[0]
    flux_coeff = mass / (2.0 * radius)
    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * float(height_m))

    def contact_force(y):
        d, v = y[0], y[1]
        force = k * d
        if gas == "adiabatic":
            force = force + gas_force(d, radius)
        if kind == "kv":
            force = force + spec[1] * v
        elif kind == "hc":
            force = force + spec[1] * k * d * v
        elif kind == "zener":
            force = force + y[2]
        return force

    def floor_force(y):
        force = contact_force(y)
        if blocked_force == "momentum":
            v = y[1]
            force = force + np.where(np.real(v) > 0.0, flux_coeff * v**2, 0.0)
        return force

    def rhs(flux_on):
        def f(t, y):
            d, v = y[0], y[1]
            force = contact_force(y)
            if flux_on:
                force = force - flux_coeff * v**2
            accel = -force / (mass * (1.0 - d / (2.0 * radius)))
            rates = [v, accel]
            if kind == "zener":
                rates.append(spec[1] * k * v - y[2] / spec[2])
            return np.array(rates)

        return f

    def force_rate(f):
        # dF/dt = ∇F · f(y), exact to round-off by a complex step along the flow.
        def event(t, y):
            yc = np.asarray(y, dtype=complex) + 1j * _COMPLEX_STEP_S * f(t, y)
            return float(np.imag(floor_force(yc)) / _COMPLEX_STEP_S)

        event.terminal = False
        event.direction = -1.0
        return event

    # Scales for the absolute tolerance: deflection, velocity, force of the linear oscillator.
    omega = math.sqrt(k / mass)
    d_scale = v0 / omega
    scales = [d_scale, v0] + ([k * d_scale] if kind == "zener" else [])
    atol = np.asarray(scales) * rtol * 1e-3
    t_span = 1e3 / omega

    def solve(f, t0, y0, terminal_events):
        events = list(terminal_events) + [force_rate(f)]
        sol = solve_ivp(
            f,
            (t0, t0 + t_span),
            y0,
            method=method,
            rtol=rtol,
            atol=atol,
            events=events,
            dense_output=True,
        )
        if sol.status != 1:
            raise RuntimeError(f"reference solve did not reach its terminal event: {sol.message}")
        t_end = sol.t[-1]
        maxima = [t for t in sol.t_events[-1] if t < t_end]
        return sol, t_end, maxima

    # Compression: δ̇ > 0, no flux term (Eq. 9).
    def max_compression(t, y):
        return y[1]

    max_compression.terminal, max_compression.direction = True, -1.0
    f1 = rhs(False)
    y0 = np.array([0.0, v0] + ([0.0] if kind == "zener" else []))
    sol1, t_max, maxima1 = solve(f1, 0.0, y0, [max_compression])
    y_max = sol1.y[:, -1].copy()
    y_max[1] = 0.0

    # Restitution: δ̇ ≤ 0, flux term on (Eq. 8), until δ = 0 or the contact force vanishes.
    def deflection(t, y):
        return y[0]

    deflection.terminal, deflection.direction = True, -1.0
    ends = [deflection]
    if kind is not None:

        def contact(t, y):
            return contact_force(y)

        contact.terminal, contact.direction = True, -1.0
        ends.append(contact)
    f2 = rhs(True)
    sol2, t_end, maxima2 = solve(f2, t_max, y_max, ends)
    y_end = sol2.y[:, -1]

    phases = [_Phase(0.0, t_max, sol1.sol, False), _Phase(t_max, t_end, sol2.sol, True)]
    candidates = [(0.0, y0), (t_max, y_max)]
    candidates += [(t, sol1.sol(t)) for t in maxima1] + [(t, sol2.sol(t)) for t in maxima2]
    forces = [float(floor_force(y)) for _, y in candidates]
    best = int(np.argmax(forces))
    momentum_out = mass * (1.0 - y_end[0] / (2.0 * radius)) * abs(y_end[1])
    return ReferenceImpact(
        height_m=float(height_m),
        contact_time_s=float(t_end),
        peak_force_N=forces[best],
        peak_time_s=float(candidates[best][0]),
        restitution=momentum_out / (mass * v0),
        max_deflection_m=float(y_max[0]),
        max_compression_time_s=float(t_max),
        impact_velocity_m_per_s=v0,
        end_state=np.asarray(y_end),
        phases=phases,
        floor_force=floor_force,
    )


def reference_scalars(heights_m, ball, **options):
    """contact_time_s, peak_force_N, restitution, max_deflection_m as arrays over heights."""
    results = [reference_impact(h, ball, **options) for h in np.atleast_1d(heights_m)]
    return {
        name: np.array([getattr(r, name) for r in results])
        for name in (
            "contact_time_s",
            "peak_force_N",
            "peak_time_s",
            "restitution",
            "max_deflection_m",
        )
    }


#: Shared by the test modules so that each model configuration compiles once per session:
#: rbjax jits per (configuration, batch shape, time-grid shape).
HEIGHTS_M = np.array([0.1, 0.5, 1.0, 1.6])
#: The paper's 44.1 kHz grid over the first 50 ms (longer than every contact tested).
HISTORY_RATE_Hz = 44_100.0
HISTORY_TIMES_S = np.arange(2205) / HISTORY_RATE_Hz

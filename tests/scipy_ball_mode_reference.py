"""An independent scipy reference for the ball with one mode in series with the shell, on the
rigid floor. Nothing here calls rbjax; the force laws are those of ``scipy_reference`` (the
paper's §2, written again there), the two-degree-of-freedom dynamics are written here.

State (X, Ẋ, w, ẇ), all downward positive, from first contact:

* X: displacement of the ball's moving part (its rigid motion);
* w: displacement of the contact zone relative to it, one mode of the ball with mass
  m_b = M/μ at the contact, natural frequency ω = 2πf and loss factor η (viscous, ηω m_b);
* the shell is pressed by δ = X + w (the floor does not move), δ̇ = Ẋ + ẇ.

Equations (the momentum flux of Eq. 7 acts on the moving part while the cap shrinks, δ̇ < 0):

    M(1 − δ/2R) Ẍ = −F_c(δ, δ̇[, F_M]) + (M/2R) δ̇² H(−δ̇)
    m_b (ẅ + ηω ẇ + ω² w) = −F_c
    X(0) = w(0) = ẇ(0) = 0,  Ẋ(0) = √(2 g h_D)

F_c: the contact force F_B + F_G (+ damping; Hunt–Crossley and Kelvin–Voigt act on δ̇).
The floor force is F_c, plus the momentum flux (M/2R)δ̇² while δ̇ > 0 with the ``momentum``
blocked force. One right-hand side throughout (no phase switch in the equations: the flux
term is H(−δ̇)δ̇², C¹ at δ̇ = 0); the solve is split only for the end-of-contact logic:

* up to the first maximum of δ (δ̇ = 0 falling), no end of contact is possible;
* after it, contact ends at the first return of δ to 0 (falling), or, for a damped contact,
  of the contact force to 0; a ringing contact zone may make δ̇ and the force oscillate
  before that, and the solve goes on through every such local extremum.

Outputs: contact time; the floor force's first local maximum (the scalar rbjax reports) and
its global maximum over the contact (the history's maximum); the restitution
M(1 − δ_end/2R)(−Ẋ_end)/(M v0), the moving part's rebound momentum (the mode's own momentum
m_b ẇ is not counted, as in rbjax); a dense solution for histories.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from scipy_reference import ball_parameters, damping_spec, gas_force, shell_stiffness

STANDARD_GRAVITY = 9.80665
RTOL = 1e-12


@dataclass
class BallModeReference:
    height_m: float
    contact_time_s: float
    first_peak_force_N: float
    first_peak_time_s: float
    max_force_N: float
    max_force_time_s: float
    restitution: float
    end_force_N: float
    n_force_maxima: int
    solutions: list = field(repr=False)
    floor_force: object = field(repr=False)

    def state(self, times_s):
        """(X, Ẋ, w, ẇ) at the given times (zeros outside [0, t_c))."""
        t = np.atleast_1d(np.asarray(times_s, dtype=float))
        y = np.zeros((4, t.size))
        (t1, s1), (t2, s2) = self.solutions
        a = (t >= 0.0) & (t <= t1)
        b = (t > t1) & (t < t2)
        if np.any(a):
            y[:, a] = s1(t[a])
        if np.any(b):
            y[:, b] = s2(t[b])
        return y

    def force_N(self, times_s):
        t = np.atleast_1d(np.asarray(times_s, dtype=float))
        inside = (t >= 0.0) & (t < self.contact_time_s)
        return np.where(inside, self.floor_force(self.state(t)), 0.0)


def reference_ball_mode_impact(
    height_m,
    ball,
    mode_mass_ratio,
    mode_frequency_Hz,
    mode_loss_factor,
    *,
    gas="adiabatic",
    blocked_force="paper",
    damping=None,
    rtol=RTOL,
    method="DOP853",
):
    """Solve the two-degree-of-freedom impact (module docstring) with scipy."""
    radius, wall, mass, youngs, poisson = ball_parameters(ball)
    k = shell_stiffness(radius, wall, youngs, poisson)
    spec = damping_spec(damping)
    if spec is not None and spec[0] == "zener":
        raise NotImplementedError(
            "the ball-mode reference has Kelvin–Voigt and Hunt–Crossley damping only"
        )
    mu, omega, eta = (
        float(mode_mass_ratio),
        2.0 * math.pi * float(mode_frequency_Hz),
        float(mode_loss_factor),
    )
    flux = mass / (2.0 * radius)
    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * float(height_m))

    def shell(y):
        return y[0] + y[2], y[1] + y[3]  # δ, δ̇

    def contact_force(y):
        d, dd = shell(y)
        f = k * d + (gas_force(d, radius) if gas == "adiabatic" else 0.0)
        if spec is not None and spec[0] == "kv":
            f = f + spec[1] * dd
        elif spec is not None and spec[0] == "hc":
            f = f + spec[1] * k * d * dd
        return f

    def floor_force(y):
        f = contact_force(y)
        if blocked_force == "momentum":
            dd = y[1] + y[3]
            f = f + np.where(dd > 0.0, flux * dd**2, 0.0)
        return f

    def rhs(t, y):
        d, dd = shell(y)
        fc = contact_force(y)
        thrust = flux * dd**2 if dd < 0.0 else 0.0
        x_acc = (thrust - fc) / (mass * (1.0 - d / (2.0 * radius)))
        w_acc = -mu * fc / mass - eta * omega * y[3] - omega**2 * y[2]
        return np.array([y[1], x_acc, y[3], w_acc])

    t_scale = math.pi * math.sqrt(mass / k)
    d_scale = v0 * t_scale / math.pi
    atol = np.array([d_scale, v0, d_scale, v0]) * rtol * 1e-3
    span = 50.0 * t_scale
    max_step = min(0.05 / max(float(mode_frequency_Hz), 1.0), t_scale / 20.0)

    def first_max(t, y):
        return y[1] + y[3]

    first_max.terminal, first_max.direction = True, -1.0
    y0 = np.array([0.0, v0, 0.0, 0.0])
    s1 = solve_ivp(
        rhs,
        (0.0, span),
        y0,
        method=method,
        rtol=rtol,
        atol=atol,
        events=[first_max],
        dense_output=True,
        max_step=max_step,
    )
    if s1.status != 1:
        raise RuntimeError(f"reference compression did not reach δ̇ = 0: {s1.message}")
    t1, y1 = s1.t[-1], s1.y[:, -1]

    def back_to_zero(t, y):
        return (y[0] + y[2]) / d_scale

    back_to_zero.terminal, back_to_zero.direction = True, -1.0
    ends = [back_to_zero]
    if spec is not None:

        def force_zero(t, y):
            return contact_force(y) / (k * d_scale)

        force_zero.terminal, force_zero.direction = True, -1.0
        ends.append(force_zero)
    s2 = solve_ivp(
        rhs,
        (t1, t1 + span),
        y1,
        method=method,
        rtol=rtol,
        atol=atol,
        events=ends,
        dense_output=True,
        max_step=max_step,
    )
    if s2.status != 1:
        raise RuntimeError(f"reference restitution did not reach the end of contact: {s2.message}")
    t2, y2 = s2.t[-1], s2.y[:, -1]
    ref = BallModeReference(
        float(height_m),
        float(t2),
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        float(floor_force(y2)),
        0,
        [(t1, s1.sol), (t2, s2.sol)],
        floor_force,
    )

    # Force maxima: a fine grid, refined by a bounded scalar search around each grid maximum.
    grid = np.linspace(0.0, t2, 40001)
    f = ref.force_N(grid[:-1])
    f = np.append(f, floor_force(y2))
    local = [i for i in range(1, grid.size - 1) if f[i] >= f[i - 1] and f[i] > f[i + 1]]
    if f[0] > f[1]:
        local = [0] + local

    def refine(i):
        lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        r = minimize_scalar(
            lambda t: -float(ref.force_N(t)[0]),
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": 1e-13},
        )
        return (
            (float(r.x), -float(r.fun)) if -float(r.fun) >= f[i] else (float(grid[i]), float(f[i]))
        )

    maxima = [refine(i) for i in local]
    ref.first_peak_time_s, ref.first_peak_force_N = maxima[0]
    ref.max_force_time_s, ref.max_force_N = max(maxima, key=lambda m: m[1])
    ref.n_force_maxima = len(maxima)
    ref.restitution = float(
        mass * (1.0 - (y2[0] + y2[2]) / (2.0 * radius)) * (-y2[1]) / (mass * v0)
    )
    return ref

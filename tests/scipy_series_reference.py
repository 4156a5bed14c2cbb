"""An independent scipy reference for the ball with a massless spring and damper in series
with the shell, on the rigid floor. Nothing here calls rbjax; the force laws are those of
``scipy_reference`` (the paper's §2, written again there).

Not the formulation rbjax solves: rbjax carries δ̇ as a state and solves for δ̈ in closed
form; here the state is (X, Ẋ, w), all downward positive, and the element's velocity is
found at every right-hand side by a scalar root (the implicit equation as written):

    X: the ball's moving part; w: the element's compression; δ = X + w, δ̇ = Ẋ + ẇ;
    M(1 − δ/2R) Ẍ = −F_c(δ, δ̇) + (M/2R) δ̇² H(−δ̇)
    c_b ẇ + k_b w = −F_c(δ, Ẋ + ẇ)          (solved for ẇ by brentq)
    X(0) = w(0) = 0,  Ẋ(0) = √(2 g h_D)

with k_b = 1/C and c_b = τ/C. F_c: F_B + F_G (+ Kelvin–Voigt or Hunt–Crossley on δ̇). The
floor force is F_c, plus the momentum flux (M/2R)δ̇² while δ̇ > 0 with the ``momentum``
blocked force. Contact ends at the first return of δ (or, damped, of F_c) to 0 after the
first maximum of δ. Restitution: M(1 − δ_end/2R)(−Ẋ_end)/(M v0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from scipy_reference import ball_parameters, damping_spec, gas_force, shell_stiffness

STANDARD_GRAVITY = 9.80665
RTOL = 1e-12


@dataclass
class SeriesReference:
    height_m: float
    contact_time_s: float
    max_force_N: float
    restitution: float
    solutions: list = field(repr=False)
    floor_force: object = field(repr=False)

    def force_N(self, times_s):
        """The floor force at the given times (0 outside [0, t_c))."""
        t = np.atleast_1d(np.asarray(times_s, dtype=float))
        out = np.zeros(t.size)
        (t1, s1), (t2, s2) = self.solutions
        for i, ti in enumerate(t):
            if 0.0 <= ti <= t1:
                out[i] = self.floor_force(s1(ti))
            elif t1 < ti < t2:
                out[i] = self.floor_force(s2(ti))
        return out


def reference_series_impact(
    height_m,
    ball,
    compliance_m_per_N,
    time_constant_s,
    *,
    gas="adiabatic",
    blocked_force="paper",
    damping=None,
    rtol=RTOL,
):
    """Solve the impact with the series element (module docstring) with scipy."""
    radius, wall, mass, youngs, poisson = ball_parameters(ball)
    k = shell_stiffness(radius, wall, youngs, poisson)
    spec = damping_spec(damping)
    if spec is not None and spec[0] == "zener":
        raise NotImplementedError(
            "the series reference has Kelvin–Voigt and Hunt–Crossley damping only"
        )
    k_b = 1.0 / float(compliance_m_per_N)
    c_b = float(time_constant_s) * k_b
    flux = mass / (2.0 * radius)
    v0 = math.sqrt(2.0 * STANDARD_GRAVITY * float(height_m))

    def contact_force(d, dd):
        f = k * d + (gas_force(d, radius) if gas == "adiabatic" else 0.0)
        if spec is not None and spec[0] == "kv":
            f = f + spec[1] * dd
        elif spec is not None and spec[0] == "hc":
            f = f + spec[1] * k * d * dd
        return f

    def element_rate(y):
        """ẇ with c_b ẇ + k_b w + F_c(δ, Ẋ + ẇ) = 0 (increasing in ẇ)."""
        d = y[0] + y[2]

        def g(s):
            return c_b * s + k_b * y[2] + contact_force(d, y[1] + s)

        lo, hi = -1.0, 1.0
        while g(lo) > 0.0:
            lo *= 2.0
        while g(hi) < 0.0:
            hi *= 2.0
        return brentq(g, lo, hi, xtol=1e-16, rtol=4 * np.finfo(float).eps, maxiter=200)

    def shell(y):
        s = element_rate(y)
        return y[0] + y[2], y[1] + s, s

    def floor_force(y):
        d, dd, _ = shell(y)
        f = contact_force(d, dd)
        if blocked_force == "momentum" and dd > 0.0:
            f = f + flux * dd**2
        return f

    def rhs(t, y):
        d, dd, s = shell(y)
        thrust = flux * dd**2 if dd < 0.0 else 0.0
        x_acc = (thrust - contact_force(d, dd)) / (mass * (1.0 - d / (2.0 * radius)))
        return np.array([y[1], x_acc, s])

    t_scale = math.pi * math.sqrt(mass / k)
    d_scale = v0 * t_scale / math.pi
    atol = np.array([d_scale, v0, d_scale]) * rtol * 1e-3
    span = 50.0 * t_scale
    max_step = t_scale / 50.0

    def first_max(t, y):
        return shell(y)[1]

    first_max.terminal, first_max.direction = True, -1.0
    s1 = solve_ivp(
        rhs,
        (0.0, span),
        np.array([0.0, v0, 0.0]),
        method="DOP853",
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
            d, dd, _ = shell(y)
            return contact_force(d, dd) / (k * d_scale)

        force_zero.terminal, force_zero.direction = True, -1.0
        ends.append(force_zero)
    s2 = solve_ivp(
        rhs,
        (t1, t1 + span),
        y1,
        method="DOP853",
        rtol=rtol,
        atol=atol,
        events=ends,
        dense_output=True,
        max_step=max_step,
    )
    if s2.status != 1:
        raise RuntimeError(f"reference restitution did not reach the end of contact: {s2.message}")
    t2, y2 = s2.t[-1], s2.y[:, -1]
    ref = SeriesReference(
        float(height_m), float(t2), 0.0, 0.0, [(t1, s1.sol), (t2, s2.sol)], floor_force
    )
    grid = np.linspace(0.0, t2, 4001)[:-1]
    ref.max_force_N = float(np.max(ref.force_N(grid)))
    ref.restitution = float((1.0 - (y2[0] + y2[2]) / (2.0 * radius)) * (-y2[1]) / v0)
    return ref

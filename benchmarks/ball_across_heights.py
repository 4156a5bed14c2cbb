"""The ball across drop heights (issue 43, item 1): every candidate mechanism for the paper's
measured ball, measured against the issue's bars on one chart.

The paper (Schoenwald, Zeitler & Nightingale 2011, §4) measured its ball from 0.1 to 1.6 m:
contact time 21.3 / 19.6 / 19.3 ms at 0.1 / 1.0 / 1.6 m, peak ~500 N and ~1800 N at 0.1 and
1.6 m, L_FE at 1 m within the standard's table, and L_FE growing per doubling of drop height by
~3 dB at 31.5 Hz rising to almost 15 dB at 1 kHz (Fig. 11). Each candidate below is evaluated at
0.1, 0.2, 0.4, 0.8, 1.0 and 1.6 m: contact time, peak, restitution, L_FE at 1 m (octave bands,
the force sampled at 44.1 kHz over a 1 s record, ``rbjax.spectrum.lfe_octave_dB``) and the
least-squares slope of L_FE against log2 of the height per band (31.5 Hz–1 kHz).

The candidates that are not rbjax terms are small numpy/scipy vector fields here (the lead's
prototypes of 2026-11-29, ``solve_ivp``); the composite that rbjax implements runs through
``rbjax.simulate(..., path="ode")``. Every parameter set is written below with where it came
from. The page that quotes the figures: docs/guides/ball-across-heights.md.

Prints one table (candidate × figures, pass/fail per bar of issue 43), writes
``results/ball_across_heights.json`` and the chart ``results/ball_across_heights.png`` (copied to
docs/images/). ``--quick``: three candidates at two heights, no chart copy (``_quick`` files).
"""

from __future__ import annotations

import shutil
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import rbjax
from rbjax.report import MEASURED_BALL, MEASURED_BALL_MODEL
from rbjax.spectrum import lfe_octave_dB
from rbjax.terms import gas_force_N, reissner_stiffness_N_per_m

from _common import (
    REPO,
    RESULTS_DIR,
    finish_machine_info,
    machine_info,
    parse_args,
    table,
    write_json,
)

# ------------------------------------------------------------------------------------------------
# the ball, the record and the bars

R, H, M, NU = 0.089, 0.032, 2.5, 0.5  # the JIS ball (rbjax.JIS_RUBBER_BALL) but for E
PA, GAMMA = 101325.0, 1.4
FS = 44100.0  # the paper's rate; 1 s record
HEIGHTS = np.array([0.1, 0.2, 0.4, 0.8, 1.0, 1.6])
#: --quick: two heights the composite's default ODE solves (no retries: one compile each)
QUICK_HEIGHTS = np.array([0.2, 1.0])
BANDS = ("31.5", "63", "125", "250", "500", "1000")
#: ISO 16283-2 Table A.1 (= ISO 10140-5 F.1 = JIS A 1418-2 A.2): L_FE at 1 m, 31.5–500 Hz
TABLE_dB = np.array([39.0, 31.0, 23.0, 17.0, 12.5])
TABLE_TOL_dB = np.array([1.0, 1.5, 1.5, 2.0, 2.0])
#: the paper's measured ball (§4): contact times (ms) and peaks (N)
PAPER_TC_ms = {0.1: 21.3, 1.0: 19.6, 1.6: 19.3}
PAPER_PEAK_N = {0.1: 500.0, 1.6: 1800.0}
#: the paper's statement of the growth per doubling (Fig. 11, read): ~3 dB at 31.5 Hz, almost
#: 15 dB at 1 kHz
PAPER_GROWTH_dB = {"31.5": 3.0, "1000": 15.0}
MU_PAPER = M / (2 * R)  # the paper's mass rate of the arrested cap (kg/m)
MU_COLUMN = 3 * M * R * H / (2 * (R**3 - (R - H) ** 3))  # the wall column's (1.46 M/2R)
RHO_RUBBER = M / (4 / 3 * np.pi * (R**3 - (R - H) ** 3))


def ball_of(E: float) -> rbjax.Ball:
    return rbjax.Ball(radius_m=R, wall_m=H, mass_kg=M, youngs_Pa=E, poisson=NU)


def kshell(E: float) -> float:
    """The Reissner stiffness (Eq. 1), from rbjax."""
    return float(reissner_stiffness_N_per_m(ball_of(E)))


def gas(d: float) -> float:
    """The corrected adiabatic gas force (Eq. 4) in numpy (checked against rbjax at start)."""
    vr = 1.0 - (3.0 - d / R) * (d / (2 * R)) ** 2
    return PA * (vr**-GAMMA - 1.0) * np.pi * d * (2 * R - d)


def _check_gas():
    d = np.array([1e-4, 3e-3, 1e-2, 2.5e-2])
    ref = np.asarray(gas_force_N(d, ball_of(1.6e6)))
    assert np.allclose([gas(x) for x in d], ref, rtol=1e-10), (d, ref)


# ------------------------------------------------------------------------------------------------
# the candidates: each a dict with its kind, parameters and their source


CANDIDATES = {
    # Schoenwald et al. 2011 as published: shell + gas, the floor receives no flux (Eq. 6/7)
    "paper": dict(kind="flux_share", params=dict(E=1.6e6, wmax=0.0), source="the paper, §2"),
    # the same with the paper's whole flux (M/2R)δ̇² on the floor (blocked_force="momentum")
    "momentum": dict(kind="flux_share", params=dict(E=1.6e6, wmax=1.0), source="the paper, §2.3"),
    # the note's candidate 1: the column stopped at the local edge Mach number
    # M_e = Rδ̇/(a c), a water-hammer force ρcδ̇πa² M_e^q/(1+M_e^q); c = √(E/3ρ) = 21 m/s the
    # rubber's shear wave speed, q = 8 the sharper of the lead's two exponents (scan c = 5–37
    # m/s, q = 2 or 8, with and without the paper's flux: scratch study 2026-11-29, proto3.py)
    "local-Mach arrest": dict(
        kind="local_mach",
        params=dict(E=1.6e6, c=21.0, q=8.0, wf=1.0),
        source="hand scan, scratch study 2026-11-29 (proto3.py)",
    ),
    # the note's candidate 2 alone: a Hertz layer F = K y^p (K = 4/3 E* √R, p = 3/2, a damper
    # c_l = 5 N s/m in parallel) in series with the paper's shell (layer.py's first set)
    "layer alone": dict(
        kind="layer_alone",
        params=dict(E=1.6e6, p=1.5, cl=5.0),
        source="Hertz from E*, scratch study 2026-11-29 (layer.py)",
    ),
    # a share w(v) = w_max s^m/(1+s^m), s = δ̇/c_a, of the flux (M/2R)δ̇² on the floor during
    # compression, Kelvin–Voigt c δ̇; no layer (fam.py)
    "speed-share flux": dict(
        kind="flux_share",
        params=dict(E=1.689e6, wmax=1.416, ca=3.793, m=932.1, ckv=11.11),
        source="Nelder–Mead on the bars, scratch study 2026-11-29 (fam.py, fam1.log best)",
    ),
    # the share of the flux passed through the wall's thickness resonance (q'' + 2ζωq' + ω²q
    # = ω²·flux), f_w = 400 Hz, ζ = 0.2, on the layer + share + KV/HC model fitted with
    # w_max = 1 (compD.log best): a representative point of the lead's scan (f_w 300–500 Hz,
    # ζ 0.1–0.3, w_max ≤ 1), not an optimum
    "thickness resonance": dict(
        kind="layer_share",
        params=dict(
            E=1.76e6,
            y1k=6.782e-4,
            p=2.55,
            ca=2.59,
            m=5.86,
            ckv=5.0,
            wmax=1.0,
            lam=0.05,
            fw=400.0,
            zeta=0.2,
        ),
        source="hand scan on compD's optimum, scratch study 2026-11-29 (comp2.py)",
    ),
    # a cap mass M/μ on a hardening layer K y^p (Hunt–Crossley λ), in series with the shell and
    # the body: a nonlinear ball mode (cap.py)
    "cap mass on a layer": dict(
        kind="cap",
        params=dict(E=1.933e6, mu=21.15, y1k=2.696e-3, p=2.026, lam=0.4936, ckv=10.44),
        source="Nelder–Mead on the bars, scratch study 2026-11-29 (cap.py, capA.log best)",
    ),
    # layer in series + speed share of the flux + Kelvin–Voigt + Hunt–Crossley-like λF_eδ̇ and a
    # softening cubic (comp.py, compE.log best)
    "layer + speed-share flux": dict(
        kind="layer_share",
        params=dict(
            E=1.929e6,
            y1k=1.425e-3,
            p=2.416,
            ca=3.168,
            m=10.87,
            ckv=2.455,
            wmax=1.758,
            lam=0.06421,
            sb=0.03258,
        ),
        source="Nelder–Mead on the bars, scratch study 2026-11-29 (comp.py, compE.log best)",
    ),
    # the family rbjax implements: HuntCrossley + ContactLayer + WaveLimitedArrest, with the
    # paper's thin-shell cap M/2R in the equation of motion (rbjax before 2026-11-29, cbb9cd9)
    "composite, cap M/2R": dict(
        kind="composite_scipy",
        params=dict(E=1.95e6, y1k=1.526e-3, p=3.056, va=2.487, n=6.934, alpha=0.0488),
        source="Nelder–Mead on the bars, scratch study 2026-11-29 (exact.py, exactA.log best)",
    ),
    # the composite with a smooth softening beyond δ_c (Hubbard's buckled regime, §2.1): the
    # stiffness falls to r·k past δ_c (exact2.py), the cap M/2R
    "composite + buckling": dict(
        kind="composite_scipy",
        params=dict(
            E=1.981e6,
            y1k=1.494e-3,
            p=2.621,
            va=2.610,
            n=8.942,
            alpha=0.02685,
            dc=0.02373,
            r=0.5666,
        ),
        source="Nelder–Mead on the bars, scratch study 2026-11-29 (exact2.py, exactB.log end)",
    ),
    # the composite as rbjax has it: the arrest's column μ is the cap's mass (cbb9cd9), the
    # arrest's exponent up to 100; the measured ball that `rbjax reproduce` writes
    # (rbjax.report.MEASURED_BALL, MEASURED_BALL_MODEL): the point of largest smallest margin
    # over the bars, each a fraction of its bar's width (Nelder–Mead on the scipy twin from the
    # scan's edge point)
    "composite (rbjax)": dict(
        kind="rbjax",
        params=dict(
            E=float(MEASURED_BALL.youngs_Pa),
            y1k=float(MEASURED_BALL_MODEL.layer.layer_deflection_m),
            p=float(MEASURED_BALL_MODEL.layer.layer_exponent),
            va=float(MEASURED_BALL_MODEL.arrest.arrest_speed_m_per_s),
            n=float(MEASURED_BALL_MODEL.arrest.arrest_exponent),
            alpha=float(MEASURED_BALL_MODEL.damping[0].alpha_s_per_m),
        ),
        source=(
            "Nelder–Mead on the smallest margin over the bars (each a fraction of its bar's "
            "width), the scipy twin with the column as the cap, from the scan's edge point; "
            "scratch study 2026-11-29 (edge3.py), rounded to four digits"
        ),
    ),
}
QUICK = ("paper", "momentum", "composite (rbjax)")

# The scan of the page's last table: the composite with the column cap near the bars' edge
# (scipy, cap="column"), each row a change from its starting point.
_N12 = dict(E=1.877e6, y1k=1.332e-3, p=3.011, va=3.195, n=11.65, alpha=0.0716, cap="column")
_N100 = dict(E=1.8676e6, y1k=1.295e-3, p=2.906, va=3.467, n=34.94, alpha=0.06706, cap="column")
#: the point rbjax shipped before the max-min search (the morning of 2026-11-29)
_SHIPPED = dict(E=1.8676e6, y1k=1.33e-3, p=2.906, va=3.43, n=34.94, alpha=0.064, cap="column")
SCAN = {
    "n ≤ 12: none": _N12,
    "n ≤ 12: y_ref = 1.45 mm": dict(_N12, y1k=1.45e-3),
    "n ≤ 12: y_ref = 1.4 mm, α = 0.068 s/m": dict(_N12, y1k=1.4e-3, alpha=0.068),
    "n ≤ 100: none": _N100,
    "n ≤ 100: α = 0.064 s/m": dict(_N100, alpha=0.064),
    "n ≤ 100: shipped before": _SHIPPED,
    "before, E = 1.835 MPa, y_ref = 1.2 mm, p = 3.3": dict(_SHIPPED, E=1.835e6, y1k=1.2e-3, p=3.3),
    "before, E = 1.84 MPa, y_ref = 1.25 mm, p = 2.6": dict(_SHIPPED, E=1.84e6, y1k=1.25e-3, p=2.6),
}


# ------------------------------------------------------------------------------------------------
# the scipy vector fields


def _events(*fns):
    for f in fns:
        f.terminal, f.direction = True, -1
    return list(fns)


def _finish(sol, floor, v0, cor=None):
    """Contact time (end event), peak and L_FE of the floor force sampled at FS, restitution."""
    tc = sol.t[-1]
    t = np.arange(0.0, tc, 1 / FS)
    F = np.maximum([floor(y) for y in sol.sol(t).T], 0.0)
    L = np.asarray(lfe_octave_dB(F, FS, n_record=int(FS)))
    return dict(tc=tc, peak=F.max(), cor=cor if cor is not None else -sol.y[1][-1] / v0, L=L)


def _series_elastic(fe, y1k, p):
    """F(δ) of a layer K y^p (compression y1k at 1 kN) in series with u ↦ fe(u): brentq on u."""

    def F(d):
        if d <= 0:
            return 0.0
        u = brentq(
            lambda u: u + y1k * (max(fe(u), 0.0) / 1000.0) ** (1 / p) - d,
            0.0,
            d,
            xtol=1e-15,
            rtol=1e-13,
        )
        return fe(u)

    return F


def impact_flux_share(h, q):
    """Shell + gas + KV, the floor receiving w(δ̇) (M/2R) δ̇² during compression (fam.py; the
    paper with w = 0, momentum with w = 1)."""
    k, ckv, v0 = kshell(q["E"]), q.get("ckv", 0.0), np.sqrt(2 * 9.81 * h)
    wmax, ca, m = q["wmax"], q.get("ca", 1.0), q.get("m", 0.0)

    def w(v):  # s^m/(1+s^m): underflows to 0 at small speed, no overflow
        s = (abs(v) / ca) ** m
        return wmax * (1.0 if m == 0 else s / (1.0 + s))

    def fs(d, v):
        return k * d + gas(d) + ckv * v

    def rhs(t, y):
        d, v = y
        return [v, ((MU_PAPER * v * v if v < 0 else 0.0) - fs(d, v)) / (M * (1 - d / (2 * R)))]

    def floor(y):
        return fs(*y) + (w(y[1]) * MU_PAPER * y[1] ** 2 if y[1] > 0 else 0.0)

    ends = _events(
        lambda t, y: y[0] if t > 1e-6 else 1.0,
        lambda t, y: floor(y) if (t > 1e-6 and y[1] < 0) else 1.0,
    )
    sol = solve_ivp(rhs, (0, 0.06), [0.0, v0], method="DOP853", rtol=1e-9, atol=1e-12,
                    events=ends, dense_output=True, max_step=2e-5)  # fmt: skip
    return _finish(sol, floor, v0)


def impact_local_mach(h, q):
    """The paper's model with the water-hammer arrest ρcδ̇πa² M_e^q/(1+M_e^q), M_e = Rδ̇/(ac),
    a² = δ(2R−δ), acting on the ball and the floor (proto3.py)."""
    k, c, qq, wf, v0 = kshell(q["E"]), q["c"], q["q"], q["wf"], np.sqrt(2 * 9.81 * h)

    def fw(d, v):
        if v <= 0 or d <= 0:
            return 0.0
        a2 = d * (2 * R - d)
        me = R * v / (np.sqrt(a2) * c)
        return RHO_RUBBER * c * v * np.pi * a2 / (1.0 + me**-qq)

    def rhs(t, y):
        d, v = y
        thrust = MU_PAPER * v * v if v < 0 else 0.0
        return [v, (thrust - k * d - gas(d) - fw(d, v)) / (M * (1 - d / (2 * R)))]

    def floor(y):
        d, v = y
        return k * d + gas(d) + fw(d, v) + (wf * MU_PAPER * v * v if v > 0 else 0.0)

    ends = _events(
        lambda t, y: y[0] if t > 1e-6 else 1.0,
        lambda t, y: floor(y) if (t > 1e-6 and y[1] < 0) else 1.0,
    )
    sol = solve_ivp(rhs, (0, 0.06), [0.0, v0], method="DOP853", rtol=1e-9, atol=1e-12,
                    events=ends, dense_output=True, max_step=2e-5)  # fmt: skip
    return _finish(sol, floor, v0)


def impact_layer_alone(h, q):
    """A Hertz layer K y^p with a damper c_l in parallel, in series with the shell (layer.py):
    states X (approach), V, y (layer compression)."""
    E, p, cl, v0 = q["E"], q["p"], q["cl"], np.sqrt(2 * 9.81 * h)
    k, K = kshell(E), (4 / 3) * E / (1 - NU**2) * np.sqrt(R)

    def parts(s):
        X, V, yl = s
        d = X - yl
        f = k * d + gas(d)  # the shell's force = the layer's: K y^p + c_l ẏ
        yd = (f - K * max(yl, 0.0) ** p) / cl
        return d, V - yd, f, yd

    def rhs(t, s):
        d, dd, f, yd = parts(s)
        thrust = MU_PAPER * dd * dd if dd < 0 else 0.0
        return [s[1], (thrust - f) / (M * (1 - d / (2 * R))), yd]

    def floor(s):
        return parts(s)[2]

    ends = _events(lambda t, s: floor(s) if (t > 1e-5 and s[1] < 0) else 1.0)
    sol = solve_ivp(rhs, (0, 0.06), [0.0, v0, 0.0], method="LSODA", rtol=1e-8, atol=1e-12,
                    events=ends, dense_output=True, max_step=5e-5)  # fmt: skip
    return _finish(sol, floor, v0)


def impact_layer_share(h, q):
    """A layer K y^p in series with the shell (+ softening cubic −s_b (δ/h)²), the elastic force
    scaled by (1 + λδ̇), KV c δ̇, the share w(δ̇) of (M/2R)δ̇² on the floor during compression
    (comp.py); with f_w, that share passed through the wall's thickness resonance (comp2.py)."""
    k, v0 = kshell(q["E"]), np.sqrt(2 * 9.81 * h)
    ckv, lam, beta = q.get("ckv", 0.0), q.get("lam", 0.0), -q.get("sb", 0.0)
    wmax, ca, m = q["wmax"], q["ca"], q["m"]
    F = _series_elastic(lambda u: k * u, q["y1k"], q["p"])
    resonant = "fw" in q
    om, z = 2 * np.pi * q.get("fw", 1.0), q.get("zeta", 0.0)

    def fc(d, dd):
        return F(d) * (1 + beta * (d / H) ** 2) * (1 + lam * dd) + gas(d) + ckv * dd

    def flux(dd):
        s = (abs(dd) / ca) ** m
        return wmax * s / (1.0 + s) * MU_PAPER * dd * dd if dd > 0 else 0.0

    def rhs(t, y):
        d, dd = y[:2]
        thrust = MU_PAPER * dd * dd if dd < 0 else 0.0
        out = [dd, (thrust - fc(d, dd)) / (M * (1 - d / (2 * R)))]
        if resonant:
            out += [y[3], om * om * (flux(dd) - y[2]) - 2 * z * om * y[3]]
        return out

    def floor(y):
        return fc(y[0], y[1]) + (y[2] if resonant else flux(y[1]))

    ends = _events(
        lambda t, y: y[0] if t > 1e-5 else 1.0,
        lambda t, y: floor(y) if (t > 1e-4 and y[1] < 0) else 1.0,
    )
    y0 = [0.0, v0] + ([0.0, 0.0] if resonant else [])
    atol, max_step = (1e-10, 2e-5) if resonant else (1e-12, 5e-5)
    sol = solve_ivp(rhs, (0, 0.06), y0, method="DOP853", rtol=1e-8, atol=atol,
                    events=ends, dense_output=True, max_step=max_step)  # fmt: skip
    return _finish(sol, floor, v0)


def impact_cap(h, q):
    """A cap of mass M/μ on a layer K y^p (1 + λẏ), in series with the shell (+ KV) and the
    body M − M/μ with the paper's dynamic mass and thrust (cap.py): states X, V, Y, W."""
    k, p, v0 = kshell(q["E"]), q["p"], np.sqrt(2 * 9.81 * h)
    K, mc, lam, ckv = 1000.0 / q["y1k"] ** p, M / q["mu"], q["lam"], q["ckv"]

    def layer(Y, W):
        return K * Y**p * (1 + lam * W) if Y > 0 else 0.0

    def rhs(t, s):
        X, V, Y, W = s
        d, dd = X - Y, V - W
        fs = k * d + gas(d) + ckv * dd
        thrust = MU_PAPER * dd * dd if dd < 0 else 0.0
        return [V, (thrust - fs) / ((M - mc) * (1 - d / (2 * R))), W, (fs - layer(Y, W)) / mc]

    def floor(s):
        return layer(s[2], s[3])

    ends = _events(
        lambda t, s: floor(s) if (t > 1e-5 and s[3] < 0) else 1.0,
        lambda t, s: s[2] if t > 1e-5 else 1.0,
    )
    sol = solve_ivp(rhs, (0, 0.06), [0.0, v0, 0.0, v0], method="DOP853", rtol=1e-8, atol=1e-13,
                    events=ends, dense_output=True, max_step=2e-5)  # fmt: skip
    return _finish(sol, floor, v0)


def impact_composite_scipy(h, q):
    """The composite (HC α k δ δ̇ + layer in series + column arrest share) with the shell's
    stiffness falling smoothly to r·k beyond δ_c (exact2.py; dc = 0: the composite itself), the
    cap's mass per unit deflection the paper's M/2R (cap="paper", as before 2026-11-29 noon) or
    the arrest's column μ (cap="column", as rbjax has it since)."""
    k, v0, alpha, va, n = kshell(q["E"]), np.sqrt(2 * 9.81 * h), q["alpha"], q["va"], q["n"]
    dc, r, sw = q.get("dc", 0.0), q.get("r", 1.0), 0.1
    cap = MU_COLUMN if q.get("cap", "paper") == "column" else MU_PAPER

    def buckled(u):
        if dc <= 0:
            return u
        z = (u / dc - 1) / sw
        return dc * (u / dc - (1 - r) * sw * (np.log1p(np.exp(-abs(z))) + max(z, 0.0)))

    F = _series_elastic(lambda u: k * buckled(u) + gas(u), q["y1k"], q["p"])

    def fc(d, dd):
        return F(d) + alpha * k * d * dd

    def rhs(t, y):
        d, dd = y
        thrust = cap * dd * dd if dd < 0 else 0.0
        return [dd, (thrust - fc(d, dd)) / (M - cap * d)]

    def floor(y):
        dd = y[1]
        s = (max(dd, 0.0) / va) ** n
        return fc(*y) + (MU_COLUMN * dd * dd * s / (1 + s) if dd > 0 else 0.0)

    # the contact ends where F_c falls through 0, or δ does (Hunt–Crossley's F_c only touches 0
    # there: without the second event a solve can run past the end)
    ends = _events(
        lambda t, y: fc(*y) if (t > 1e-5 and y[1] < 0) else 1.0,
        lambda t, y: y[0] if t > 1e-5 else 1.0,
    )
    sol = solve_ivp(rhs, (0, 0.06), [0.0, v0], method="DOP853", rtol=1e-8, atol=1e-12,
                    events=ends, dense_output=True, max_step=5e-5)  # fmt: skip
    d_end = sol.y[0][-1]
    out = _finish(sol, floor, v0, cor=-(M - cap * d_end) * sol.y[1][-1] / (M * v0))
    # the floor's impulse against the ball's change of momentum M v0 (1 + e) (gravity aside):
    # 0 where the floor receives what the ball loses
    t = np.linspace(0.0, sol.t[-1], 8001)
    impulse = np.trapezoid([floor(y) for y in sol.sol(t).T], t)
    out["impulse_excess"] = impulse / (M * v0 * (1.0 + out["cor"])) - 1.0
    return out


SCIPY = {
    "flux_share": impact_flux_share,
    "local_mach": impact_local_mach,
    "layer_alone": impact_layer_alone,
    "layer_share": impact_layer_share,
    "cap": impact_cap,
    "composite_scipy": impact_composite_scipy,
}


# ------------------------------------------------------------------------------------------------
# the composite through rbjax


def composite_rbjax(q, heights):
    """HuntCrossley + ContactLayer + WaveLimitedArrest on the ball of Young's modulus E, through
    ``rbjax.simulate(..., path="ode")`` with the default Solver; a height it flags is NaN (its
    status recorded)."""
    ball = ball_of(q["E"])
    model = rbjax.Model(
        damping=rbjax.HuntCrossley(alpha_s_per_m=q["alpha"]),
        layer=rbjax.ContactLayer(layer_deflection_m=q["y1k"], layer_exponent=q["p"]),
        arrest=rbjax.WaveLimitedArrest(arrest_speed_m_per_s=q["va"], arrest_exponent=q["n"]),
    )
    result = rbjax.simulate(np.asarray(heights), ball, model, path="ode")
    L = np.asarray(result.lfe_octave_dB())
    rows = []
    for j, status in enumerate(np.atleast_1d(result.status_name)):
        ok = str(status) == "ok"
        rows.append(
            dict(
                tc=float(result.contact_time_s[j]) if ok else np.nan,
                peak=float(result.peak_force_N[j]) if ok else np.nan,
                cor=float(result.restitution[j]) if ok else np.nan,
                L=L[j] if ok else np.full(6, np.nan),
                default_status=str(status),
            )
        )
    return rows


# ------------------------------------------------------------------------------------------------
# figures and bars


def evaluate(name, cand, heights):
    q = cand["params"]
    if cand["kind"] == "rbjax":
        rows = composite_rbjax(q, heights)
    else:
        rows = [SCIPY[cand["kind"]](h, q) for h in heights]
        for row in rows:
            row["tc"] = float(row["tc"])
    L = np.array([r["L"] for r in rows])
    out = dict(
        source=cand["source"],
        kind=cand["kind"],
        params=q,
        heights_m=heights,
        contact_time_ms=np.array([r["tc"] for r in rows]) * 1e3,
        peak_N=np.array([r["peak"] for r in rows]),
        restitution=np.array([r["cor"] for r in rows]),
        lfe_dB=L,
    )
    ok = np.all(np.isfinite(L), axis=1)
    if ok.sum() >= 2:
        out["growth_dB_per_doubling"] = np.polyfit(np.log2(heights[ok]), L[ok], 1)[0]
    else:
        out["growth_dB_per_doubling"] = np.full(6, np.nan)
    if cand["kind"] == "rbjax":  # its scipy twin: the impulse, and how far the two agree
        twin = [impact_composite_scipy(h, dict(q, cap="column")) for h in heights]
        out["impulse_excess"] = np.array([r["impulse_excess"] for r in twin])
        tc_twin = np.array([float(r["tc"]) for r in twin]) * 1e3
        out["scipy_twin_contact_time_rel_diff"] = float(
            np.nanmax(np.abs(tc_twin / out["contact_time_ms"] - 1.0))
        )
    elif "impulse_excess" in rows[0]:
        out["impulse_excess"] = np.array([r["impulse_excess"] for r in rows])
    if "default_status" in rows[0]:
        out["default_status"] = [r["default_status"] for r in rows]
    out["bars"] = bars(out)
    return out


def _at(out, key, h):
    hs = list(np.round(out["heights_m"], 3))
    return out[key][hs.index(h)] if h in hs else np.nan


def bars(out):
    """Each bar of issue 43 that these heights can judge: True (met), False, or None (n/a)."""
    L1 = _at(out, "lfe_dB", 1.0)
    s = np.asarray(out["growth_dB_per_doubling"])
    tc1, cor1 = _at(out, "contact_time_ms", 1.0), _at(out, "restitution", 1.0)

    def judge(values):
        values = np.asarray(values, float)
        return None if not np.all(np.isfinite(values)) else True

    b = {}
    if judge(L1[:5]):
        b["table at 1 m"] = bool(np.all(np.abs(L1[:5] - TABLE_dB) <= TABLE_TOL_dB))
    if judge([tc1, cor1]):
        b["tc 18–22, e 0.7–0.9 at 1 m"] = bool(18 <= tc1 <= 22 and 0.7 <= cor1 <= 0.9)
    tcs = [_at(out, "contact_time_ms", h) for h in PAPER_TC_ms]
    if judge(tcs):
        b["tc ±0.3 ms"] = bool(np.all(np.abs(np.array(tcs) - list(PAPER_TC_ms.values())) <= 0.3))
    pks = [_at(out, "peak_N", h) for h in PAPER_PEAK_N]
    if judge(pks):
        b["peak ±5 %"] = bool(
            np.all(np.abs(np.array(pks) / list(PAPER_PEAK_N.values()) - 1) <= 0.05)
        )
    if judge(s):
        b["≤ 4 dB at 31.5, 63"] = bool(s[0] <= 4 and s[1] <= 4)
        b["rising 125 Hz–1 kHz"] = bool(np.all(np.diff(s[2:]) > 0))
        b["≥ 10 dB at 1 kHz"] = bool(s[5] >= 10)
    return b


BAR_NAMES = (
    "table at 1 m",
    "tc 18–22, e 0.7–0.9 at 1 m",
    "tc ±0.3 ms",
    "peak ±5 %",
    "≤ 4 dB at 31.5, 63",
    "rising 125 Hz–1 kHz",
    "≥ 10 dB at 1 kHz",
)


def _f(x, spec=".1f"):
    return "—" if not np.isfinite(x) else format(x, spec)


def print_table(results):
    heads = ["candidate", "tc 0.1/1/1.6 ms", "peak 0.1/1.6 N", "e at 1 m", "L_FE@1m 31.5–500"]
    heads += ["growth 31.5–1k dB", "bars met"]
    rows = []
    for name, o in results.items():
        tcs = "/".join(_f(_at(o, "contact_time_ms", h), ".2f") for h in PAPER_TC_ms)
        pks = "/".join(_f(_at(o, "peak_N", h), ".0f") for h in PAPER_PEAK_N)
        L1 = _at(o, "lfe_dB", 1.0)
        L1 = "/".join(_f(x) for x in L1[:5]) if np.ndim(L1) else "—"
        g = "/".join(_f(x) for x in o["growth_dB_per_doubling"])
        met = " ".join(
            "·" if o["bars"].get(b) is None else ("✓" if o["bars"][b] else "✗") for b in BAR_NAMES
        )
        rows.append([name, tcs, pks, _f(_at(o, "restitution", 1.0), ".3f"), L1, g, met])
    print(table(heads, rows))
    print("bars (✓ met, ✗ not, · n/a):", "; ".join(f"{i + 1} {b}" for i, b in enumerate(BAR_NAMES)))


# ------------------------------------------------------------------------------------------------
# the chart


def chart(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(15, 5.2))
    gs = fig.add_gridspec(2, 3, wspace=0.3, hspace=0.08)
    ax_l, ax_t = fig.add_subplot(gs[:, 0]), fig.add_subplot(gs[0, 1])
    ax_p, ax_g = fig.add_subplot(gs[1, 1], sharex=ax_t), fig.add_subplot(gs[:, 2])
    x = np.arange(6)
    ax_l.bar(x[:5], 2 * TABLE_TOL_dB, bottom=TABLE_dB - TABLE_TOL_dB, color="0.85", width=0.6,
             label="table (ISO 16283-2 A.1)")  # fmt: skip
    ax_g.fill_between([-0.3, 1.3], -2, 4, color="0.85", label="bar: ≤ 4 dB")
    ax_g.fill_between([4.7, 5.3], 10, 20, color="0.85", label="bar: ≥ 10 dB")
    ax_g.plot([0, 5], [PAPER_GROWTH_dB["31.5"], PAPER_GROWTH_dB["1000"]], "k*", ms=12,
              label="paper §4 (~3, almost 15)", zorder=5)  # fmt: skip
    for h, v in PAPER_TC_ms.items():
        ax_t.plot(h, v, "k*", ms=12, zorder=5)
    for h, v in PAPER_PEAK_N.items():
        ax_p.plot(h, v, "k*", ms=12, zorder=5)
    cmap = plt.get_cmap("tab10")
    for i, (name, o) in enumerate(results.items()):
        style = dict(color=cmap(i % 10), marker="o", ms=3.5, lw=1.3, label=name)
        L1 = _at(o, "lfe_dB", 1.0)
        if np.ndim(L1):
            ax_l.plot(x[:5], L1[:5], **style)
        ax_t.plot(o["heights_m"], o["contact_time_ms"], **style)
        ax_p.plot(o["heights_m"], o["peak_N"], **style)
        ax_g.plot(x, o["growth_dB_per_doubling"], **style)
    ax_l.set(xticks=x[:5], xticklabels=BANDS[:5], xlabel="octave band (Hz)",
             ylabel="L_FE at 1 m (dB re 1 N)", title="L_FE at 1 m against the table")  # fmt: skip
    ax_t.set(ylabel="contact time (ms)", title="contact time and peak (★ paper §4)")
    ax_t.tick_params(labelbottom=False)
    ax_p.set(xscale="log", xlabel="drop height (m)", ylabel="peak (N)")
    ax_p.set_xticks(HEIGHTS, [f"{h:g}" for h in HEIGHTS])
    ax_g.set(xticks=x, xticklabels=BANDS, xlabel="octave band (Hz)", ylim=(0, 17),
             ylabel="L_FE growth per doubling (dB)",
             title="growth per doubling, 0.1–1.6 m")  # fmt: skip
    ax_l.legend(fontsize=7, loc="lower left")
    shown = [
        (h, lab)
        for h, lab in zip(*ax_g.get_legend_handles_labels())
        if lab.startswith(("bar", "paper §"))
    ]
    ax_g.legend(*zip(*shown), fontsize=7, loc="upper left")
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def main(quick: bool = False) -> None:
    _check_gas()
    info = machine_info()
    heights = QUICK_HEIGHTS if quick else HEIGHTS
    names = QUICK if quick else tuple(CANDIDATES)
    results, seconds = {}, {}
    for name in names:
        t0 = time.perf_counter()
        results[name] = evaluate(name, CANDIDATES[name], heights)
        seconds[name] = time.perf_counter() - t0
        print(f"  {name}: {seconds[name]:.1f} s", flush=True)
    print_table(results)
    scan = {}
    if not quick:
        for label, q in SCAN.items():
            o = evaluate(label, dict(kind="composite_scipy", params=q, source="scan"), heights)
            scan[label] = dict(
                peak_1_6m_N=float(_at(o, "peak_N", 1.6)),
                restitution_1m=float(_at(o, "restitution", 1.0)),
                lfe_1m_dB=[float(x) for x in _at(o, "lfe_dB", 1.0)[:5]],
                growth_1kHz_dB=float(o["growth_dB_per_doubling"][5]),
                params=q,
            )
            L = "/".join(f"{x:.3f}" for x in scan[label]["lfe_1m_dB"])
            print(f"  scan {label}: peak 1.6 m {scan[label]['peak_1_6m_N']:.1f} N, "
                  f"e {scan[label]['restitution_1m']:.3f}, L_FE at 1 m {L} dB, "
                  f"growth 1 kHz {scan[label]['growth_1kHz_dB']:.2f} dB")  # fmt: skip
    suffix = "_quick" if quick else ""
    png = RESULTS_DIR / f"ball_across_heights{suffix}.png"
    RESULTS_DIR.mkdir(parents=True, exist_ok=True)
    chart(results, png)
    if not quick:
        (REPO / "docs" / "images").mkdir(exist_ok=True)
        shutil.copyfile(png, REPO / "docs" / "images" / "ball_across_heights.png")
    record = dict(
        machine=finish_machine_info(info),
        quick=quick,
        bands_Hz=BANDS,
        table_dB=TABLE_dB,
        table_tolerance_dB=TABLE_TOL_dB,
        paper=dict(contact_time_ms=PAPER_TC_ms, peak_N=PAPER_PEAK_N, growth_dB=PAPER_GROWTH_dB),
        bar_names=BAR_NAMES,
        seconds=seconds,
        candidates=results,
        column_cap_scan=scan,
    )
    print("wrote", write_json(f"ball_across_heights{suffix}", record), "and", png)


if __name__ == "__main__":
    main(quick=parse_args(__doc__.split("\n\n")[0]).quick)

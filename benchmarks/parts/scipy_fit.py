"""What a scipy user would write to fit the bundled recordings: the side-by-side anchor of
``fit_time.py``.

``scipy.optimize.least_squares`` (trust-region reflective, finite-difference Jacobian) on the
same conditioned records as ``rbjax fit`` (``rbjax.fit.prepare_data``: per-height averages,
30 ms windows), the same measuring chain (the 4th-order causal Butterworth at the records'
low-pass, ``scipy.signal.sosfilt``), the same sampling rule (the sample holding the contact
start takes the in-contact fraction of its interval) and the same weights (1/noise rms per
record). The force histories come from ``solve_ivp`` (DOP853, rtol 1e-10) of the independent
references in ``tests/`` (paper Eq. 7; the two-degree-of-freedom ball-mode impact): nothing of
rbjax's solver is used. Start values and onsets as a user would pick them: E from the lowest
height's contact time, onsets where the measured force first crosses 5 % of its peak.

``fit(model)`` returns the optimum, its cost ½Σr², the rms (N) and the wall time.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
import scipy.optimize
import scipy.signal

from rbjax import JIS_RUBBER_BALL, HuntCrossley, KelvinVoigt

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from scipy_ball_mode_reference import reference_ball_mode_impact  # noqa: E402
from scipy_reference import reference_impact  # noqa: E402

RTOL = 1e-10
#: (parameter names, start values, the reference impact of one height for parameters p)
MODELS = {
    "kelvin-voigt": (
        ("youngs_Pa", "damping_Ns_per_m"),
        (1.6e6, 50.0),
        lambda h, p: reference_impact(
            h,
            JIS_RUBBER_BALL.replace(youngs_Pa=p[0]),
            damping=KelvinVoigt(p[1]),
            blocked_force="momentum",
            rtol=RTOL,
        ),
    ),
    "hunt-crossley+ball-mode": (
        ("youngs_Pa", "alpha_s_per_m", "mode_mass_ratio", "mode_frequency_Hz", "mode_loss_factor"),
        (1.6e6, 0.05, 20.0, 600.0, 0.2),
        lambda h, p: reference_ball_mode_impact(
            h,
            JIS_RUBBER_BALL.replace(youngs_Pa=p[0]),
            p[2],
            p[3],
            p[4],
            damping=HuntCrossley(p[1]),
            blocked_force="momentum",
            rtol=RTOL,
        ),
    ),
}


def sampled(ref, tau, rate):
    """The box rule of the first sample, point values after it (as the fit's records)."""
    half = 0.5 / rate
    inside = np.clip((tau + half) * rate, 0.0, 1.0)
    mid = 0.5 * (np.maximum(tau - half, 0.0) + tau + half)
    return inside * ref.force_N(np.maximum(mid, 0.0))


def fit(model: str, data) -> dict:
    names, start, impact = MODELS[model]
    t0 = time.perf_counter()
    sos = scipy.signal.butter(4, data.lowpass_Hz, fs=data.rate_Hz, output="sos")
    t = data.time_s
    measured = data.force_N
    weights = 1.0 / data.noise_rms_N
    k = len(data.height_m)
    # onsets: where the measured force first crosses 5 % of its peak, less the filter's delay
    onsets = np.array([t[np.argmax(f > 0.05 * f.max())] for f in measured]) - 2.613 / (
        2 * math.pi * data.lowpass_Hz
    )
    scale = np.array([*start, *([1e-3] * k)])  # shifts in ms

    def residuals(x):
        p = x[: len(names)] * scale[: len(names)]
        shifts = x[len(names) :] * 1e-3
        rows = []
        for i, h in enumerate(data.height_m):
            ref = impact(float(h), p)
            rows.append(
                weights[i]
                * (
                    scipy.signal.sosfilt(sos, sampled(ref, t - shifts[i], data.rate_Hz))
                    - measured[i]
                )
            )
        return np.concatenate(rows)

    x0 = np.concatenate([np.ones(len(names)), onsets / 1e-3])
    sol = scipy.optimize.least_squares(residuals, x0, x_scale="jac", method="trf")
    elapsed = time.perf_counter() - t0
    p = sol.x[: len(names)] * scale[: len(names)]
    r = sol.fun / np.repeat(weights, t.size)
    return {
        "model": model,
        "parameters": dict(zip(names, map(float, p))),
        "onset_shift_s": (sol.x[len(names) :] * 1e-3).tolist(),
        "cost": float(sol.cost),
        "rms_N": float(np.sqrt(np.mean(r**2))),
        "evaluations": int(sol.nfev),
        "status": int(sol.status),
        "time_s": elapsed,
        "residuals": residuals,
    }


def cost_at(residuals, names, params: dict, shifts) -> float:
    """½Σr² of the scipy residuals at another optimum (rbjax's), for a like-for-like cost."""
    _, start, _ = MODELS_BY_NAMES[tuple(names)]
    x = np.concatenate([[params[n] / s for n, s in zip(names, start)], np.asarray(shifts) / 1e-3])
    r = residuals(x)
    return 0.5 * float(r @ r)


MODELS_BY_NAMES = {m[0]: m for m in MODELS.values()}

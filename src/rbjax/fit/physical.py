"""The fitted values read in physical terms, for the result's notes: the ball mode as the mass,
spring and damper it stands for, the series element as its spring and damper, and the
parameters that ended on a bound of their fit range (:data:`rbjax.fit.layout.FIT_RANGES`)."""

from __future__ import annotations

import math

from .layout import FIT_RANGES

#: How close (relative to the range: 1 %) a value must be to a bound to be reported as on it.
BOUND_TOLERANCE = 1e-2


def ball_mode_structure(ball, model) -> str:
    """The fitted ball mode as a mass at the contact on a spring and a damper (``""`` without
    one): m_b = M/μ, k_b = (2πf)² m_b, c_b = η (2πf) m_b."""
    mode = model.ball_mode
    if mode is None or float(mode.mode_mass_ratio) == 0.0:
        return ""
    mass = float(ball.mass_kg) / float(mode.mode_mass_ratio)
    omega = 2.0 * math.pi * float(mode.mode_frequency_Hz)
    eta = float(mode.mode_loss_factor)
    kind = (
        "a ringing mode"
        if eta < 1.0
        else (
            "an overdamped degree of freedom, not a ringing mode"
            if eta > 2.0
            else "a heavily damped mode"
        )
    )
    return (
        f"The ball mode as fitted: a {1e3 * mass:.3g} g mass at the contact (M/μ) on a spring of "
        f"{omega**2 * mass:.3g} N/m and a damper of {eta * omega * mass:.3g} N s/m "
        f"(f = {float(mode.mode_frequency_Hz):.4g} Hz, η = {eta:.3g}): {kind}."
    )


def series_structure(model) -> str:
    """The fitted series element as a spring and a damper (``""`` without one or when off):
    k_b = 1/C, c_b = τ/C."""
    element = model.series
    if element is None or float(element.series_compliance_m_per_N) == 0.0:
        return ""
    compliance, tau = (
        float(element.series_compliance_m_per_N),
        float(element.series_time_constant_s),
    )
    return (
        f"The series element as fitted: a spring of {1.0 / compliance:.3g} N/m and a damper of "
        f"{tau / compliance:.3g} N s/m in series with the shell (τ = {1e3 * tau:.3g} ms): the ball "
        "mode's massless limit."
    )


def at_bounds(values: dict) -> str:
    """A sentence naming the fitted parameters that ended on a bound of their fit range."""
    hits = []
    for name, value in values.items():
        if name not in FIT_RANGES:
            continue
        lower, upper = FIT_RANGES[name]
        for bound, side in ((lower, "lower"), (upper, "upper")):
            if abs(value - bound) <= BOUND_TOLERANCE * (upper - lower):
                hits.append(
                    f"{name} = {value:.4g} (the {side} bound of its fit range ({lower:g}, "
                    f"{upper:g}))"
                )
    if not hits:
        return ""
    return (
        "On a bound: " + "; ".join(hits) + ": the data ask for more than the term describes there."
    )

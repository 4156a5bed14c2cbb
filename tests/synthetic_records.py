"""Measured-like force records made without rbjax's solver (shared by the fit tests and the
parameter-layer tests): the scipy solution of paper Eq. 7 (tests/scipy_reference.py) sampled at
44.1 kHz (the sample holding the first contact takes the in-contact fraction of its interval),
white noise added, then scipy.signal's 4th-order Butterworth at 1250 Hz (the measuring chain);
the records then pass through rbjax.data like measured files."""

from __future__ import annotations

import numpy as np
import scipy.signal

from rbjax.data import Recording
from rbjax.fit import prepare_data

from scipy_reference import reference_impact

RATE_HZ = 44_100.0
CUTOFF_HZ = 1250.0
HEIGHTS_M = (0.1, 0.2, 0.4, 0.8, 1.0, 1.6)
SOS = scipy.signal.butter(4, CUTOFF_HZ, fs=RATE_HZ, output="sos")
NOISE_N = 0.8  # white, before the low-pass (as the brief's measuring chain)
RECORD_S = 0.06
CONTACT_START_S = 0.010


def sampled_force(ref, tau_s):
    """Point samples of the reference floor force; the sample whose interval holds the first
    contact takes the in-contact fraction times the force at the in-contact midpoint."""
    half = 0.5 / RATE_HZ
    inside = np.clip((tau_s + half) * RATE_HZ, 0.0, 1.0)
    mid = 0.5 * (np.maximum(tau_s - half, 0.0) + tau_s + half)
    return inside * ref.force_N(np.maximum(mid, 0.0))


def reference_records(ball, damping, blocked_force, starts_s, noise_N=0.0, seed=0):
    """Measured-like records (no chain applied yet is not an option: always filtered)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(RECORD_S * RATE_HZ))) / RATE_HZ
    out = []
    for h, t0 in zip(HEIGHTS_M, starts_s):
        ref = reference_impact(h, ball, damping=damping, blocked_force=blocked_force, rtol=1e-11)
        force = sampled_force(ref, t - t0) + rng.normal(0.0, noise_N, t.size)
        out.append(scipy.signal.sosfilt(SOS, force))
    return t, out


def synthetic_data(ball, damping, blocked_force, seed):
    rng = np.random.default_rng(seed + 100)
    starts = CONTACT_START_S + rng.uniform(0, 1 / RATE_HZ, len(HEIGHTS_M))
    _, forces = reference_records(ball, damping, blocked_force, starts, NOISE_N, seed)
    recs = [
        Recording(source=f"synthetic_h{int(round(h * 100)):03d}.csv", height_m=h, rate_Hz=RATE_HZ, force_N=f, lowpass_Hz=CUTOFF_HZ)
        for h, f in zip(HEIGHTS_M, forces)
    ]
    return prepare_data(recs)


def central_difference(reference, params: dict, shifts, name: str):
    """d reference(params, shifts)/d name by central differences: a parameter by a relative
    step of 1e-4, an onset ``shift[k]`` by 1e-7 s."""
    if name.startswith("shift["):
        k, step = int(name[6:-1]), 1e-7
        up, down = np.array(shifts, dtype=float), np.array(shifts, dtype=float)
        up[k] += step
        down[k] -= step
        return (reference(params, up) - reference(params, down)) / (2 * step)
    step = 1e-4 * params[name]
    return (reference({**params, name: params[name] + step}, shifts) - reference({**params, name: params[name] - step}, shifts)) / (2 * step)

"""Measured-like force records made without rbjax's solver (shared by the fit tests and the
parameter-layer tests): the scipy solution of paper Eq. 7 (tests/scipy_reference.py) sampled at
44.1 kHz (the sample holding the first contact takes the in-contact fraction of its interval),
white noise added, then scipy.signal's 4th-order Butterworth at 1250 Hz (the measuring chain);
the records then pass through rbjax.data like measured files."""

from __future__ import annotations

import wave

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


def sampled_force(ref, tau_s, rate_Hz=RATE_HZ):
    """Point samples of the reference floor force; the sample whose interval holds the first
    contact takes the in-contact fraction times the force at the in-contact midpoint."""
    half = 0.5 / rate_Hz
    inside = np.clip((tau_s + half) * rate_Hz, 0.0, 1.0)
    mid = 0.5 * (np.maximum(tau_s - half, 0.0) + tau_s + half)
    return inside * ref.force_N(np.maximum(mid, 0.0))


def reference_records(
    ball,
    damping,
    blocked_force,
    starts_s,
    noise_N=0.0,
    seed=0,
    *,
    rate_Hz=RATE_HZ,
    record_s=RECORD_S,
):
    """Measured-like records (no chain applied yet is not an option: always filtered), sampled
    at ``rate_Hz`` (the chain's Butterworth designed at that rate), ``record_s`` long."""
    rng = np.random.default_rng(seed)
    sos = SOS if rate_Hz == RATE_HZ else scipy.signal.butter(4, CUTOFF_HZ, fs=rate_Hz, output="sos")
    t = np.arange(int(round(record_s * rate_Hz))) / rate_Hz
    out = []
    for h, t0 in zip(HEIGHTS_M, starts_s):
        ref = reference_impact(h, ball, damping=damping, blocked_force=blocked_force, rtol=1e-11)
        force = sampled_force(ref, t - t0, rate_Hz) + rng.normal(0.0, noise_N, t.size)
        out.append(scipy.signal.sosfilt(sos, force))
    return t, out


def synthetic_data(ball, damping, blocked_force, seed):
    rng = np.random.default_rng(seed + 100)
    starts = CONTACT_START_S + rng.uniform(0, 1 / RATE_HZ, len(HEIGHTS_M))
    _, forces = reference_records(ball, damping, blocked_force, starts, NOISE_N, seed)
    recs = [
        Recording(
            source=f"synthetic_h{int(round(h * 100)):03d}.csv",
            height_m=h,
            rate_Hz=RATE_HZ,
            force_N=f,
            lowpass_Hz=CUTOFF_HZ,
        )
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
    return (
        reference({**params, name: params[name] + step}, shifts)
        - reference({**params, name: params[name] - step}, shifts)
    ) / (2 * step)


#: The drops behind the fault tests (tests/data/test_faults.py, tests/fit/test_fit_faults.py):
#: Kelvin–Voigt damping, the momentum blocked force, 1 s records as a laboratory keeps them.
FAULT_BALL_E_PA = 1.9e6
FAULT_DAMPING_NS_PER_M = 40.0
FAULT_START_S = 0.1
FAULT_RECORD_S = 1.0


def long_records(rate_Hz=RATE_HZ, seed=3):
    """(t, forces) of the six drops, 1 s long, contact at 0.1 s (+ a fraction of a sample),
    noise of the same density at every rate (0.8 N per sample at 44.1 kHz)."""
    from rbjax import JIS_RUBBER_BALL, KelvinVoigt

    ball = JIS_RUBBER_BALL.replace(youngs_Pa=FAULT_BALL_E_PA)
    starts = FAULT_START_S + np.random.default_rng(seed + 100).uniform(
        0, 1 / rate_Hz, len(HEIGHTS_M)
    )
    noise = NOISE_N * np.sqrt(rate_Hz / RATE_HZ)
    return reference_records(
        ball,
        KelvinVoigt(FAULT_DAMPING_NS_PER_M),
        "momentum",
        starts,
        noise,
        seed,
        rate_Hz=rate_Hz,
        record_s=FAULT_RECORD_S,
    )


def with_faults(
    t, force, *, offset_N=0.0, drift_N_per_s=0.0, hum=None, inverted=False, rebound_after_s=None
):
    """A clean record with the faults of a real one added after the measuring chain.

    hum: (frequency_Hz, amplitude_N): the fundamental, plus a third harmonic of a quarter of
    its amplitude; rebound_after_s: a second impact, half the first, that much later."""
    x = np.array(force, dtype=float)
    if rebound_after_s is not None:
        k = int(round(rebound_after_s / (t[1] - t[0])))
        x[k:] += 0.5 * force[: x.size - k]
    x += offset_N + drift_N_per_s * t
    if hum is not None:
        f, a = hum
        x += a * np.sin(2 * np.pi * f * t + 0.4) + 0.25 * a * np.sin(2 * np.pi * 3 * f * t + 1.1)
    return -x if inverted else x


# ----------------------------------------------------------------------------------------------
# the records written as the files laboratories export, each by its own library


def write_int_wav(path, force_N, bits, full_scale_N, rate=RATE_HZ):
    """A PCM WAV of ``bits`` written by the standard library's wave module."""
    full = 2 ** (bits - 1)
    codes = np.clip(np.round(force_N / full_scale_N * full), -full, full - 1).astype(np.int64)
    raw = codes.astype("<i4").view(np.uint8).reshape(-1, 4)[:, : bits // 8].tobytes()
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(bits // 8)
        w.setframerate(int(rate))
        w.writeframes(raw)


def write_mat_v73(path, variables):
    """An HDF5 file laid out as MATLAB's v7.3 (512-byte user block with the MAT header;
    arrays stored transposed, MATLAB being column-major)."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as f:
        for name, value in variables.items():
            f[name] = np.asarray(value).T
            f[name].attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as fh:
        fh.write(b"MATLAB 7.3 MAT-file, written by the rbjax tests".ljust(116, b" "))


def write_uff(path, channels):
    """Dataset 58 time responses, one per (id1, samples, unit), written by pyuff (ASCII)."""
    import pyuff

    t = np.arange(len(channels[0][1])) / RATE_HZ
    sets = [
        dict(
            type=58,
            binary=0,
            func_type=1,
            id1=name,
            rsp_node=1,
            rsp_dir=3,
            ref_node=1,
            ref_dir=3,
            orddenom_spec_data_type=0,
            abscissa_spacing=1,
            ordinate_axis_units_lab=unit,
            data=x,
            x=t,
        )
        for name, x, unit in channels
    ]
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")


def write_tdms(path, channels, group="plate"):
    """One group of channels (name, samples, properties), written by npTDMS."""
    from nptdms import ChannelObject, GroupObject, TdmsWriter

    objs = [GroupObject(group)] + [ChannelObject(group, n, x, properties=p) for n, x, p in channels]
    with TdmsWriter(str(path)) as w:
        w.write_segment(objs)

"""Causal Butterworth low-pass filters: the measuring chain of a force plate.

A force plate's conditioning amplifier and anti-alias filter act on the force *before*
it is sampled; they are causal (analogue) filters, so they delay and smooth the rising
edge of an impact. The JIS A 1418-2 rubber-ball paper uses a 4th-order low-pass at
1250 Hz. This module gives the digital equivalent:

* :func:`butter_lowpass_sos` designs a Butterworth low-pass of any order as cascaded
  second-order sections (SOS) with the bilinear transform, the cutoff pre-warped so the
  digital filter has its -3 dB point exactly at ``cutoff_Hz``. The layout of the
  sections is the one of ``scipy.signal.butter(order, cutoff_Hz, fs=rate_Hz,
  output="sos")``: rows ``[b0, b1, b2, 1, a1, a2]``, overall gain in the first row,
  sections ordered from the pole farthest from the unit circle to the closest one (a
  first-order section ``[b0, b1, 0, 1, a1, 0]`` comes first for an odd order).
* :func:`sosfilt_np` (NumPy) and :func:`sosfilt_jax` (JAX, ``jax.lax.scan``; works
  under ``jit``/``vmap``/``grad``, float64) run the sections causally from rest
  (zero initial state), along the last axis, in transposed direct form II, like
  ``scipy.signal.sosfilt``.
* :func:`sos_frequency_response` evaluates H(e^{i 2 pi f / rate}).

Only NumPy and JAX are used (no SciPy); the tests compare with SciPy to ~1e-10.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from . import _x64  # noqa: F401  (float64 on)

__all__ = [
    "butter_lowpass_sos",
    "sosfilt_np",
    "sosfilt_jax",
    "sos_frequency_response",
    "lowpass_np",
]


def butter_lowpass_sos(order: int = 4, cutoff_Hz: float = 1250.0, rate_Hz: float = 44100.0) -> np.ndarray:
    """Digital Butterworth low-pass as second-order sections, shape ``(ceil(order/2), 6)``.

    Analogue prototype poles ``w_a * exp(i pi (2k + order + 1) / (2 order))`` with the
    pre-warped cutoff ``w_a = 2 rate_Hz tan(pi cutoff_Hz / rate_Hz)`` (rad/s), mapped by
    the bilinear transform ``z = (1 + s/(2 rate)) / (1 - s/(2 rate))``; all zeros at
    z = -1; unit gain at DC.

    Args:
      order: filter order (>= 1).
      cutoff_Hz: -3 dB frequency in Hz, 0 < cutoff_Hz < rate_Hz / 2.
      rate_Hz: sampling rate in Hz.
    """
    order = int(order)
    if order < 1:
        raise ValueError(f"order={order!r} must be a positive integer")
    rate_Hz = float(rate_Hz)
    cutoff_Hz = float(cutoff_Hz)
    if not (math.isfinite(rate_Hz) and rate_Hz > 0):
        raise ValueError(f"rate_Hz={rate_Hz!r} must be positive and finite")
    if not (math.isfinite(cutoff_Hz) and 0 < cutoff_Hz < rate_Hz / 2):
        raise ValueError(
            f"cutoff_Hz={cutoff_Hz!r} must lie in (0, rate_Hz/2) = (0, {rate_Hz / 2:g}) Hz"
        )
    fs2 = 2.0 * rate_Hz
    w_a = fs2 * math.tan(math.pi * cutoff_Hz / rate_Hz)  # pre-warped analogue cutoff, rad/s
    k = np.arange(order)
    p_analog = w_a * np.exp(1j * np.pi * (2 * k + order + 1) / (2 * order))
    p_digital = (1 + p_analog / fs2) / (1 - p_analog / fs2)

    # one representative of each conjugate pair (upper half plane) plus the real pole
    upper = [p for p in p_digital if p.imag > 1e-14 * abs(p)]
    real = [p.real for p in p_digital if abs(p.imag) <= 1e-14 * abs(p)]
    # farthest from the unit circle first (as scipy's zpk2sos orders them)
    upper.sort(key=lambda p: 1 - abs(p), reverse=True)

    sections = []
    for r in real:  # at most one, for odd orders
        sections.append([1.0, 1.0, 0.0, 1.0, -r, 0.0])
    for p in upper:
        sections.append([1.0, 2.0, 1.0, 1.0, -2.0 * p.real, abs(p) ** 2])
    sos = np.array(sections, dtype=np.float64)
    # unit DC gain: H(z=1) = prod (b0+b1+b2)/(1+a1+a2)
    dc = np.prod(sos[:, :3].sum(axis=1) / sos[:, 3:].sum(axis=1))
    sos[0, :3] /= dc
    return sos


def _check_sos(sos) -> np.ndarray:
    sos = np.asarray(sos, dtype=np.float64)
    if sos.ndim != 2 or sos.shape[1] != 6 or sos.shape[0] < 1:
        raise ValueError(f"sos must have shape (n_sections, 6); got {sos.shape}")
    if np.any(sos[:, 3] == 0):
        raise ValueError("sos: a0 (column 3) must be non-zero in every section")
    return sos


def sosfilt_np(sos, x) -> np.ndarray:
    """Filter ``x`` causally with the sections ``sos`` along its last axis (NumPy).

    Zero initial state, transposed direct form II; same result as
    ``scipy.signal.sosfilt(sos, x)``. Returns a new float64 array of ``x``'s shape.
    """
    sos = _check_sos(sos)
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 0:
        raise ValueError("x must have at least one axis (time along the last axis)")
    sos = sos / sos[:, 3:4]
    if x.ndim == 1:
        y = x.tolist()  # plain Python floats: the sample loop is ~10x faster than on numpy scalars
        for b0, b1, b2, _, a1, a2 in sos.tolist():
            z1 = z2 = 0.0
            for n, xn in enumerate(y):
                yn = b0 * xn + z1
                z1 = b1 * xn - a1 * yn + z2
                z2 = b2 * xn - a2 * yn
                y[n] = yn
        return np.asarray(y, dtype=np.float64)
    lead = x.shape[:-1]
    y = np.array(x.reshape(-1, x.shape[-1]).T, dtype=np.float64, order="C")  # (n, batch)
    for b0, b1, b2, _, a1, a2 in sos.tolist():
        z1 = np.zeros(y.shape[1])
        z2 = np.zeros(y.shape[1])
        for n in range(y.shape[0]):
            xn = y[n].copy()
            yn = b0 * xn + z1
            z1 = b1 * xn - a1 * yn + z2
            z2 = b2 * xn - a2 * yn
            y[n] = yn
    return y.T.reshape(lead + (x.shape[-1],))


def sosfilt_jax(sos, x) -> jax.Array:
    """Filter ``x`` causally with the sections ``sos`` along its last axis (JAX).

    ``jax.lax.scan`` over time with zero initial state (transposed direct form II), in
    float64. Differentiable with respect to ``x`` (and ``sos``); works under ``jit``
    and ``vmap``. ``sos`` must have a concrete number of sections (its shape).
    """
    sos = jnp.asarray(sos, dtype=jnp.float64)
    if sos.ndim != 2 or sos.shape[1] != 6:
        raise ValueError(f"sos must have shape (n_sections, 6); got {sos.shape}")
    x = jnp.asarray(x, dtype=jnp.float64)
    if x.ndim == 0:
        raise ValueError("x must have at least one axis (time along the last axis)")
    sos = sos / sos[:, 3:4]
    n_sec = sos.shape[0]
    xt = jnp.moveaxis(x, -1, 0)  # (n, ...)
    z0 = jnp.zeros((n_sec, 2) + xt.shape[1:], dtype=jnp.float64)

    def step(z, xn):
        y = xn
        new = []
        for s in range(n_sec):
            b0, b1, b2, _, a1, a2 = (sos[s, j] for j in range(6))
            yn = b0 * y + z[s, 0]
            z1 = b1 * y - a1 * yn + z[s, 1]
            z2 = b2 * y - a2 * yn
            new.append(jnp.stack([z1, z2]))
            y = yn
        return jnp.stack(new), y

    _, yt = jax.lax.scan(step, z0, xt, unroll=4)
    return jnp.moveaxis(yt, 0, -1)


def sos_frequency_response(sos, f_Hz, rate_Hz: float) -> np.ndarray:
    """Complex frequency response H(exp(i 2 pi f_Hz / rate_Hz)) of the sections (NumPy)."""
    sos = _check_sos(sos)
    z = np.exp(1j * 2 * np.pi * np.asarray(f_Hz, dtype=np.float64) / float(rate_Hz))
    zi = 1.0 / z
    h = np.ones_like(z)
    for b0, b1, b2, a0, a1, a2 in sos:
        h = h * (b0 + b1 * zi + b2 * zi**2) / (a0 + a1 * zi + a2 * zi**2)
    return h


def lowpass_np(x, cutoff_Hz: float, rate_Hz: float, order: int = 4) -> np.ndarray:
    """Causal Butterworth low-pass of ``x`` along its last axis (NumPy convenience)."""
    return sosfilt_np(butter_lowpass_sos(order, cutoff_Hz, rate_Hz), x)

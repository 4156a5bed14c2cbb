"""Causal Butterworth low-pass filters: the measuring chain of a force plate.

A force plate's conditioning amplifier and anti-alias filter act on the force *before*
it is sampled; they are causal (analogue) filters, so they delay and smooth the rising
edge of an impact. The JIS A 1418-2 rubber-ball paper uses a 4th-order low-pass at
1250 Hz. This module gives the digital equivalent:

* :func:`butter_lowpass_sos`: the sections of ``scipy.signal.butter(order, cutoff_Hz,
  fs=rate_Hz, output="sos")`` (bilinear transform, cutoff pre-warped: -3 dB exactly at
  ``cutoff_Hz``), bit for bit, with the arguments checked, without importing
  ``scipy.signal``.
* :func:`lowpass_np`: the NumPy-side filter, ``scipy.signal.sosfilt`` (causal, from
  rest) with those sections.
* :func:`sosfilt_jax`: the same causal filter in JAX (``jax.lax.scan``; works under
  ``jit``/``vmap``/``grad``, float64), for the fit, which differentiates its residuals
  through the measuring chain. Tested against ``scipy.signal.sosfilt``.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "butter_lowpass_sos",
    "sosfilt_jax",
    "lowpass_np",
]


def butter_lowpass_sos(
    order: int = 4, cutoff_Hz: float = 1250.0, rate_Hz: float = 44100.0
) -> np.ndarray:
    """Digital Butterworth low-pass as second-order sections, shape ``(ceil(order/2), 6)``.

    The array ``scipy.signal.butter(order, cutoff_Hz, fs=rate_Hz, output="sos")`` gives, bit
    for bit (rows ``[b0, b1, b2, 1, a1, a2]``, unit gain at DC): the same arithmetic, its
    bilinear transform with the pre-warped cutoff and the pole–zero pairing of its
    ``zpk2sos`` (the pole nearest the unit circle last, each with the zeros nearest it, the
    gain in the first section), without importing ``scipy.signal``, which took 0.4–0.8 s of
    every fit's process (a model selection's workers among them) for this one design.

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
    # scipy's iirfilter: the prototype's poles on the unit circle, scaled to the pre-warped
    # cutoff (sampling rate normalised to 2), mapped by the bilinear transform; the zeros at
    # infinity go to z = -1 (and one to z = 0 for an odd order: zpk2sos's padding)
    warped = float(2 * 2.0 * np.tan(np.pi * (np.float64(cutoff_Hz) / (rate_Hz / 2)) / 2.0))
    m = np.arange(-order + 1, order, 2, dtype=np.float64)
    analog = warped * -np.exp(1j * np.pi * m / (2 * order))
    poles = (4.0 + analog) / (4.0 - analog)
    gain = warped**order * np.real(1.0 / np.prod(4.0 - analog))
    # zpk2sos: one pole a section (the upper of a conjugate pair; the real pole of an odd
    # order, with the pole at 0), the one nearest the unit circle first, each with the two
    # zeros nearest it; sections built from the last taken to the first
    firsts = [q for q in poles if q.imag > 0] + ([poles[order // 2].real] if order % 2 else [])
    zeros = [-1.0] * order + ([0.0] if order % 2 else [])
    sections = []
    while firsts:
        p1 = firsts.pop(int(np.argmin([abs(1 - abs(q)) for q in firsts])))
        pair = [p1, 0.0] if np.isreal(p1) else [p1, np.conj(p1)]
        near = [zeros.pop(int(np.argmin([abs(z - p1) for z in zeros]))) for _ in range(2)]
        sections.append(np.concatenate([np.poly(near), np.poly(pair).real]))
    sos = np.array(sections[::-1])
    sos[0, :3] *= gain
    return sos


def sosfilt_jax(sos, x) -> jax.Array:
    """Filter ``x`` causally with the sections ``sos`` along its last axis (JAX).

    ``jax.lax.scan`` over time with zero initial state (transposed direct form II), in
    float64: the result of ``scipy.signal.sosfilt(sos, x)``. Differentiable with respect
    to ``x`` (and ``sos``); works under ``jit`` and ``vmap``. ``sos`` must have a
    concrete number of sections (its shape).
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


def lowpass_np(x, cutoff_Hz: float, rate_Hz: float, order: int = 4) -> np.ndarray:
    """Causal Butterworth low-pass of ``x`` along its last axis (``scipy.signal.sosfilt``)."""
    import scipy.signal  # lazy: scipy.signal costs 0.6–1.7 s at import (benchmarks/RESULTS.md)

    return scipy.signal.sosfilt(
        butter_lowpass_sos(order, cutoff_Hz, rate_Hz), np.asarray(x, dtype=np.float64)
    )

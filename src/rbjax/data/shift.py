"""Sub-sample time shifts of a record (band-limited or interpolated)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["fractional_shift"]


def lagrange4(y4, u):
    """Cubic through y(-1), y(0), y(1), y(2) evaluated at u (scalars or arrays)."""
    ym1, y0, y1, y2 = y4
    return (
        -u * (u - 1) * (u - 2) / 6 * ym1
        + (u + 1) * (u - 1) * (u - 2) / 2 * y0
        - (u + 1) * u * (u - 2) / 2 * y1
        + (u + 1) * u * (u - 1) / 6 * y2
    )


def fractional_shift(x, shift_samples: float, *, interpolation: str = "fourier") -> np.ndarray:
    """Delay ``x`` by ``shift_samples`` (may be fractional or negative): ``y[i] = x(i - shift)``.

    Samples brought in from outside ``x`` are 0. Interpolations:

    * ``"fourier"``: band-limited shift, multiply the spectrum of the zero-padded
      record by ``exp(-2 pi i f shift / rate)`` (exact for band-limited signals; a
      record that does not start and end near zero rings near its ends);
    * ``"cubic"``: 4-point Lagrange interpolation;
    * ``"linear"``: linear interpolation (attenuates high frequencies by up to
      ``cos(pi f / rate)`` for half-sample shifts: 0.4 % at 1250 Hz, 44.1 kHz).

    Args:
        x: the samples, 1-D.
        shift_samples: the delay in samples (negative: an advance).
        interpolation: ``"fourier"``, ``"cubic"`` or ``"linear"``.

    Returns:
        The shifted samples, a float64 array as long as ``x``.

    Raises:
        ValueError: ``x`` is not 1-D, ``shift_samples`` is not finite, or an unknown
            ``interpolation``.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError(f"x must be 1-D, got shape {x.shape}")
    n = x.size
    d = float(shift_samples)
    if not math.isfinite(d):
        raise ValueError(f"shift_samples={shift_samples!r} must be finite")
    if interpolation not in ("fourier", "linear", "cubic"):
        raise ValueError(f"interpolation={interpolation!r}: use 'fourier', 'cubic' or 'linear'")
    if d == 0:
        return x.copy()
    if interpolation == "fourier":
        from scipy.fft import next_fast_len  # lazy: scipy.fft costs 0.3 s at import (RESULTS.md)

        N = next_fast_len(
            n + int(math.ceil(abs(d))) + 64, real=True
        )  # zero padding: no wrap-around
        k = np.arange(N // 2 + 1)
        ph = np.exp(-2j * np.pi * k * d / N)
        if N % 2 == 0:  # the Nyquist bin must stay real: keep its cosine part
            ph[-1] = math.cos(math.pi * d)
        return np.fft.irfft(np.fft.rfft(x, N) * ph, N)[:n]
    # "linear" or "cubic"
    pos = np.arange(n) - d
    ip = np.floor(pos).astype(np.int64)
    u = pos - ip
    xp = np.concatenate([[0.0, 0.0], x, [0.0, 0.0, 0.0]])  # index k -> xp[k + 2]

    def at(j):
        j = np.clip(j, -2, n + 2)
        return xp[j + 2]

    if interpolation == "linear":
        return (1 - u) * at(ip) + u * at(ip + 1)
    return lagrange4((at(ip - 1), at(ip), at(ip + 1), at(ip + 2)), u)

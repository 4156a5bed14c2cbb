"""The Fast detector (exponential time weighting, IEC 61672-1:2013, 3.7 and 5.8: τ = 0.125 s)
on sampled signals and, in closed form, on the decays of the room chain; and the maximum
over time with its exact gradient.

**Sampled.** ``time_weighting`` runs ẏ = (p² − y)/τ over a record of p² samples held over each
sample interval (the exact discretisation y_n = α y_{n−1} + (1 − α) p²_n, α = e^{−Δt/τ}: the
recursion of a digital sound level meter; ``scipy.signal.lfilter([1 − α], [1, −α], p²)`` is
the same filter).

**Closed form.** The room chain is a cascade of first-order stages driven by an impulse: the
floor's band energy decays at a (= ω η_floor), feeds the room, whose energy decays at
b = 6 ln 10 / T, and p² drives the detector, rate g = 1/τ. The response of a cascade of
first-order stages with rates r₀ … r_n to a unit impulse is the convolution of e^{−r_i t},
which is the divided difference of E(x) = e^{−xt} at the rates, up to the sign (−1)^n:

    e^{−at}                                  (one stage)
    (e^{−at} − e^{−bt})/(b − a) = t e^{−at} ψ((b − a)t),  ψ(z) = (1 − e^{−z})/z
    ((b,g) − (a,b))/(a − g) of the two-stage responses   (three stages)

(Opitz 1964: the divided differences of E are the last row of exp of the bidiagonal matrix;
de Boor, "Divided differences", Surveys in Approximation Theory 1, 2005, §4). ψ is evaluated
with ``expm1`` and the three-stage difference is taken across the two rates farthest apart,
so nothing cancels unless all three rates nearly coincide, where the Taylor value t²e^{−mt}/2
(m: their mean) is used (|r_i − m|·t < 1e-3: error ≲ 1e-7 relative).

**The maximum and its gradient.** L_Fmax = max_t y(t, θ). At a maximum inside the record
∂y/∂t = 0, so by the envelope theorem dy_max/dθ = ∂y/∂θ (t*, θ): the exact derivative of the
maximum is the partial derivative at the maximising time held fixed. ``maximum_over_time``
finds t* on a log-spaced grid, refines it by Newton steps on ∂y/∂t (under
``jax.lax.stop_gradient``) and evaluates y(t*, θ) with θ live: the gradient is exact, not
smoothed, wherever the maximum is unique (where two local maxima trade places the maximum has
a kink and its gradient jumps, as the level itself does).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from .._validate import check_range
from .standards import FAST_TIME_CONSTANT_s


def time_weighting(p2, rate_Hz: float, time_constant_s: float = FAST_TIME_CONSTANT_s):
    """Exponentially time-weighted mean square y_n of the samples p²_n (last axis), zero
    before the record: y_n = α y_{n−1} + (1 − α) p²_n, α = e^{−1/(rate τ)} (module docstring)."""
    check_range("rate_Hz", rate_Hz, lower=0.0)
    check_range("time_constant_s", time_constant_s, lower=0.0)
    alpha = np.exp(-1.0 / (float(rate_Hz) * float(time_constant_s)))
    x = jnp.moveaxis(jnp.asarray(p2, dtype=jnp.float64), -1, 0)

    def step(y, xn):
        y = alpha * y + (1.0 - alpha) * xn
        return y, y

    _, ys = jax.lax.scan(step, jnp.zeros(x.shape[1:]), x)
    return jnp.moveaxis(ys, 0, -1)


def _psi(z):
    """(1 − e^{−z})/z, 1 at z = 0 (a Taylor value for |z| < 1e-8)."""
    small = jnp.abs(z) < 1e-8
    safe = jnp.where(small, 1.0, z)
    return jnp.where(small, 1.0 - 0.5 * z, -jnp.expm1(-safe) / safe)


def two_stage(a, b, t):
    """∫₀ᵗ e^{−a s} e^{−b(t−s)} ds = (e^{−at} − e^{−bt})/(b − a), stable for a ≈ b."""
    return t * jnp.exp(-a * t) * _psi((b - a) * t)


def three_stage(a, b, g, t):
    """The convolution of e^{−at}, e^{−bt}, e^{−gt} (module docstring), stable for close rates."""
    rates = jnp.stack(jnp.broadcast_arrays(a, b, g))
    lo, hi = jnp.min(rates, axis=0), jnp.max(rates, axis=0)
    mid = jnp.sum(rates, axis=0) - lo - hi
    spread = (hi - lo) * t
    close = spread < 1e-3
    mean = jnp.sum(rates, axis=0) / 3.0
    taylor = 0.5 * t**2 * jnp.exp(-mean * t)
    gap = jnp.where(close, 1.0, hi - lo)
    general = (two_stage(lo, mid, t) - two_stage(mid, hi, t)) / gap
    return jnp.where(close, taylor, general)


def cascade(rates, t):
    """Unit-impulse response at times ``t`` of a cascade of 1–3 first-order stages of the given
    decay rates (each stage ẋ_i = x_{i−1} − r_i x_i)."""
    if len(rates) == 1:
        return jnp.exp(-rates[0] * t)
    if len(rates) == 2:
        return two_stage(rates[0], rates[1], t)
    if len(rates) == 3:
        return three_stage(rates[0], rates[1], rates[2], t)
    raise ValueError(f"a cascade of {len(rates)} stages; valid: 1 to 3")


def maximum_over_time(
    response, t_min_s: float, t_max_s: float, *, num_grid: int = 256, newton_steps: int = 8
):
    """(max_t y(t), t*) of a scalar function ``response(t)`` of time (JAX), with the exact
    gradient of the maximum (module docstring).

    The grid is log-spaced over [t_min_s, t_max_s] with t = 0 added; a maximum at t = 0 (a
    decay without build-up) is returned as it is.
    """
    grid = jnp.concatenate([jnp.zeros(1), jnp.geomspace(t_min_s, t_max_s, num_grid)])

    values = jax.vmap(response)(grid)
    k = jnp.argmax(values)
    dy = jax.grad(response)
    d2y = jax.grad(dy)
    lo = grid[jnp.maximum(k - 1, 0)]
    hi = grid[jnp.minimum(k + 1, num_grid)]

    def newton(t, _):
        step = dy(t) / d2y(t)
        t_new = jnp.clip(t - jnp.where(jnp.isfinite(step), step, 0.0), lo, hi)
        return jnp.where(k == 0, 0.0, t_new), None

    t_star, _ = jax.lax.scan(newton, grid[k], None, length=newton_steps)
    t_star = jax.lax.stop_gradient(t_star)
    return response(t_star), t_star

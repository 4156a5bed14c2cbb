"""The Fast detector: the sampled recursion against scipy.signal.lfilter, the closed-form
cascades against scipy's ODE solver, and the maximum's gradient against finite differences."""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.signal import lfilter

from rbjax.room.detector import cascade, maximum_over_time, time_weighting


def test_time_weighting_is_the_lfilter_recursion():
    rng = np.random.default_rng(1)
    rate, tau = 8000.0, 0.125
    p2 = rng.random((2, 4000)) ** 2
    alpha = math.exp(-1 / (rate * tau))
    expected = lfilter([1 - alpha], [1, -alpha], p2, axis=-1)
    np.testing.assert_allclose(
        np.asarray(time_weighting(p2, rate, tau)), expected, rtol=1e-12, atol=1e-15
    )


def _ode_cascade(rates, t):
    def rhs(_, x):
        d = -np.asarray(rates) * x
        d[1:] += x[:-1]
        return d

    x0 = np.zeros(len(rates))
    x0[0] = 1.0
    return solve_ivp(rhs, (0, t[-1]), x0, t_eval=t, rtol=1e-12, atol=1e-15, method="DOP853").y[-1]


@pytest.mark.parametrize(
    "rates",
    [
        (40.0,),
        (40.0, 13.8),
        (13.8, 13.8),
        (40.0, 13.8, 8.0),
        (8.0, 8.0 + 1e-7, 8.0 - 1e-7),
        (8.0, 8.0005, 30.0),
        (300.0, 6.9, 8.0),
    ],
)
def test_cascade_closed_form_against_ode(rates):
    t = np.linspace(0.0, 1.5, 61)[1:]
    np.testing.assert_allclose(
        np.asarray(cascade(list(rates), jnp.asarray(t))),
        _ode_cascade(rates, t),
        rtol=1e-7,
        atol=1e-14,
    )


def test_maximum_and_its_exact_gradient():
    # one program: the maximum, its time and its gradient; the finite differences from its values
    @jax.jit
    @functools.partial(jax.value_and_grad, has_aux=True)
    def peak(theta):
        a, b = theta
        return maximum_over_time(lambda t: cascade([a, b, 8.0], t), 1e-4, 5.0)

    theta = jnp.array([40.0, 13.8])
    (value, t_star), grad = peak(theta)
    # the maximum against a dense grid
    grid = np.linspace(0.0, 1.0, 200001)
    dense = np.asarray(cascade([40.0, 13.8, 8.0], jnp.asarray(grid)))
    assert float(value) == pytest.approx(dense.max(), rel=1e-9)
    assert float(t_star) == pytest.approx(grid[dense.argmax()], abs=1e-5)
    for i in range(2):
        h = 1e-5 * float(theta[i])
        up, down = theta.at[i].add(h), theta.at[i].add(-h)
        fd = (float(peak(up)[0][0]) - float(peak(down)[0][0])) / (2 * h)
        assert float(grad[i]) == pytest.approx(fd, rel=1e-6)

"""The rules of the quadrature path: nodes, weights and the matrices of linear functionals.

Everything :mod:`rbjax.solve.quadrature` (the scalar outputs) and
:mod:`rbjax.solve.quadrature_history` (the histories) integrate with, built once per number of
nodes in NumPy (cached) and independent of the ball and the model:

* Gauss–Legendre rules on [0, 1] (:func:`gauss_legendre_01`) and the φ rule of the phase times
  (``time_nodes`` points, :func:`refine_rules`);
* interpolation on Chebyshev–Lobatto points of [0, 1] (:func:`lobatto_01`): the matrix from
  values to Chebyshev coefficients (:func:`values_to_coefficients`), and from values to every
  functional the scalar path needs (:func:`bracket_rules`: the coefficients of the interpolant and
  of its antiderivative; :func:`refine_rules`: its integral, the Taylor coefficients at the right
  end, the sub-interval averages of the φ points and the Chebyshev tail), with their round-off
  scale (:func:`row_norms`);
* the error of a rule: the discrete Legendre projection's highest coefficients
  (:func:`legendre_tail`) and the decay ρ^(−2n) of an n-point rule (:func:`bernstein_decay`).
"""

from __future__ import annotations

import functools
import math

import jax.numpy as jnp
import numpy as np
from numpy.polynomial import chebyshev

#: Terms of the Taylor series in ε = δ_max/d1 − 1: of the antiderivative (the root, the rebound
#: velocity, the peak force) and of the sub-interval averages (the phase times).
ROOT_TERMS = 4
SUB_TERMS = 3
#: Highest Chebyshev coefficients of the interpolant kept for its error estimate.
TAIL_COEFFICIENTS = 4


@functools.cache
def gauss_legendre_01(n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [0, 1] (numpy's ``leggauss``, mapped)."""
    x, w = np.polynomial.legendre.leggauss(n_nodes)
    return 0.5 * (x + 1.0), 0.5 * w


@functools.cache
def lobatto_01(n: int) -> np.ndarray:
    """n Chebyshev–Lobatto points on [0, 1], ascending, with both ends exact."""
    t = 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / (n - 1)))
    t[0], t[-1] = 0.0, 1.0
    return t


@functools.cache
def values_to_coefficients(n: int) -> np.ndarray:
    """The matrix from values at ``lobatto_01(n)`` to Chebyshev coefficients in x = 2t − 1."""
    return np.linalg.inv(chebyshev.chebvander(2.0 * lobatto_01(n) - 1.0, n - 1))


@functools.cache
def bracket_rules(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lobatto points t on [0, 1]; the matrices from values p(t_j) to the Chebyshev coefficients
    of p and of its antiderivative ∫₀^t p (both in x = 2t − 1)."""
    to_coef = values_to_coefficients(n)
    integrate = np.stack([chebyshev.chebint(e, lbnd=-1.0, scl=0.5) for e in np.eye(n)], axis=1)
    return lobatto_01(n), to_coef, integrate @ to_coef


def time_nodes(n_nodes: int) -> int:
    """Gauss–Legendre points of the φ rule for ``n_nodes`` interpolation points (as many: the
    integrands' left singularity, near δ = −δ_max, moves in with the gas force's asymmetry)."""
    return n_nodes


@functools.cache
def legendre_tail(m: int) -> np.ndarray:
    """Rows giving the two highest Legendre coefficients a_{m−2}, a_{m−1} and a_0 of the
    degree-(m − 1) interpolant of values at the m Gauss–Legendre points (the discrete
    projection)."""
    x, w = np.polynomial.legendre.leggauss(m)
    rows = [
        (2 * k + 1) / 2.0 * w * np.polynomial.legendre.legval(x, np.eye(m)[k])
        for k in (0, m - 2, m - 1)
    ]
    return np.stack(rows)


@functools.cache
def refine_rules(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Lobatto points t_1..t_{n−1} on (0, 1] (t_0 = 0 is left out: F(0) = 0), the φ rule (sin φ_i,
    weights; ``time_nodes(n)`` points) and one matrix whose rows are linear functionals of the
    values p(t_1..t_{n−1}) of a degree-(n − 1) polynomial p with p(0) = 0:

    * row 0: ∫₀¹ p dt; rows 1..ROOT_TERMS: p^(q)(1)/q! for q = 0..ROOT_TERMS − 1 (the Taylor
      series of ∫₀^λ p dt about λ = 1 has coefficients p^(q)(1)/(q + 1)!, and of p(λ) these);
    * rows (q, i), q = 0..SUB_TERMS − 1, i over the φ points:
      (1/q!)(1/μ_i) ∫_{1−μ_i}^1 t^q p^(q)(t) dt, μ_i = 1 − sin φ_i (the Taylor coefficients in
      λ − 1 of the average of p(λt) over [1 − μ_i, 1]);
    * the last TAIL_COEFFICIENTS rows: the highest Chebyshev coefficients (the interpolant's tail).
    """
    to_coef = values_to_coefficients(n)
    m = time_nodes(n)
    x, w = np.polynomial.legendre.leggauss(m)
    phi, w_phi = np.pi / 4.0 * (x + 1.0), np.pi / 4.0 * w
    mu = 1.0 - np.sin(phi)
    lower = 2.0 * (1.0 - mu) - 1.0  # 1 − μ_i in x = 2t − 1
    end = np.zeros((ROOT_TERMS + 1, n))
    sub = np.zeros((SUB_TERMS, m, n))
    t_power = [np.array([1.0])]
    for _ in range(SUB_TERMS):
        t_power.append(chebyshev.chebmul(t_power[-1], np.array([0.5, 0.5])))  # t = (x + 1)/2
    for j in range(n):
        coef = to_coef[:, j]
        end[0, j] = chebyshev.chebval(1.0, chebyshev.chebint(coef, lbnd=-1.0, scl=0.5))
        for q in range(ROOT_TERMS):
            deriv = chebyshev.chebder(coef, q, scl=2.0) if q else coef
            end[q + 1, j] = chebyshev.chebval(1.0, deriv) / math.factorial(q)
            if q < SUB_TERMS:
                anti = chebyshev.chebint(chebyshev.chebmul(t_power[q], deriv), lbnd=-1.0, scl=0.5)
                sub[q, :, j] = (
                    (chebyshev.chebval(1.0, anti) - chebyshev.chebval(lower, anti))
                    / mu
                    / math.factorial(q)
                )
    rows = np.concatenate(
        [end, sub.reshape(SUB_TERMS * m, n), to_coef[-TAIL_COEFFICIENTS:]], axis=0
    )
    return lobatto_01(n)[1:], np.sin(phi), w_phi, rows[:, 1:]


@functools.cache
def row_norms(n: int) -> np.ndarray:
    """Largest absolute row sum of ``refine_rules(n)`` per Taylor order (their round-off scale)."""
    rows, m = refine_rules(n)[3], time_nodes(n)
    sub = rows[ROOT_TERMS + 1 : ROOT_TERMS + 1 + SUB_TERMS * m].reshape(SUB_TERMS, m, -1)
    end = np.abs(rows[1 : ROOT_TERMS + 1]).sum(axis=1)
    return np.array(
        [
            max(end[q], np.abs(sub[q]).sum(axis=1).max() if q < SUB_TERMS else 0.0)
            for q in range(ROOT_TERMS)
        ]
    )


def bernstein_decay(a, n):
    """ρ^(−2n), ρ = a + √(a² − 1): the error decay of an n-point rule for a function analytic
    inside the Bernstein ellipse whose semi-major axis is a (in units of the half interval)."""
    rho = a + jnp.sqrt(jnp.maximum(a**2 - 1.0, 0.0))
    return jnp.exp(-2.0 * n * jnp.log(jnp.maximum(rho, 1.0 + 1e-16)))

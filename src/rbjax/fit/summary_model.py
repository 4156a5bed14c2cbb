"""The summary figures of a model at given drop heights, and their exact Jacobian, as one
compiled program: what :func:`rbjax.fit.summary.fit_summary` and :mod:`rbjax.studies.design`
evaluate.

The scalars (contact time, peak force, restitution) come from the fastest exact path the model
allows (``rbjax.solve.simulate``: the quadrature for elastic models, the phase-angle integration
for damped ones on the rigid floor; the diffrax ODE with forward-mode adjoint otherwise). The
band levels L_FE (Eq. 11) come from the force sampled at 44.1 kHz inside the solve
(``rbjax.solve.sampled``; the ODE for coupled models) over a window of ``num_samples`` samples
and are those of the 1 s record (the rest of it zeros, ``n_record``). The Jacobian is
``jax.jacfwd`` of the same function with respect to the unconstrained coordinates φ of the free
parameters (their declared transforms, ``rbjax.terms.declare``); value and Jacobian come from
one compiled program (one per model structure, figures, number of heights and window).
"""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..solve.angle import angle_unsupported
from ..solve.inputs import PAPER_DURATION_S, PAPER_RATE_Hz, as_arrays
from ..solve.sampled import sampled_history_unsupported, sampled_solve, substeps_for_contact
from ..solve.simulate import simulate, trajectory
from ..solve.solver import Solver
from ..spectrum.levels import lfe_octave_dB, lfe_third_octave_dB
from ..terms.model import Model
from ..terms.parameters import replace
from .summary_table import OCTAVE_FIGURES, SCALAR_FIGURES, THIRD_OCTAVE_FIGURES

#: Record length whose L_FE the band figures are (the paper's 1 s at 44.1 kHz, §2.4).
N_RECORD = int(round(PAPER_RATE_Hz * PAPER_DURATION_S))
#: The sampled window covers the longest contact at the start times this factor, + 2 samples,
#: rounded up to a multiple of ``WINDOW_QUANTUM`` (so that fits of similar balls share a program).
WINDOW_MARGIN = 1.5
WINDOW_QUANTUM = 512


def window_samples(contact_time_s) -> int:
    """Samples of the force window for contacts up to ``WINDOW_MARGIN`` × the longest given."""
    tc = np.asarray(contact_time_s, dtype=float)
    longest = float(np.nanmax(tc)) if np.any(np.isfinite(tc)) else 0.05
    n = int(math.ceil(WINDOW_MARGIN * longest * PAPER_RATE_Hz)) + 2
    return min(N_RECORD, WINDOW_QUANTUM * math.ceil(n / WINDOW_QUANTUM))


def figures_of(
    heights_m, ball, model: Model, figures: tuple[str, ...], num_samples: int, substeps: int = 1
):
    """(len(heights), len(figures)) array of the figures of ``(ball, model)`` (traceable)."""
    # the ODE (no fast path: coupled models, a contact layer, an arrest law) with the adjoint
    # that jax.jacfwd can differentiate
    on_ode = angle_unsupported(model) is not None
    solver = Solver(adjoint="forward") if on_ode else None
    columns: dict = {}
    if any(f in SCALAR_FIGURES for f in figures):
        res = simulate(heights_m, ball, model, solver=solver)
        columns.update(
            contact_time_s=res.contact_time_s,
            peak_force_N=res.peak_force_N,
            restitution=res.restitution,
        )
    octave = [f for f in figures if f in OCTAVE_FIGURES]
    third = [f for f in figures if f in THIRD_OCTAVE_FIGURES]
    if octave or third:
        if sampled_history_unsupported(model) is None:
            force = sampled_solve(
                heights_m, ball, model, PAPER_RATE_Hz, num_samples, substeps
            ).force_N
        else:
            force = trajectory(
                heights_m, jnp.arange(num_samples) / PAPER_RATE_Hz, ball, model, solver
            ).force_N
        if octave:
            columns.update(
                zip(
                    OCTAVE_FIGURES,
                    jnp.moveaxis(lfe_octave_dB(force, PAPER_RATE_Hz, n_record=N_RECORD), -1, 0),
                )
            )
        if third:
            columns.update(
                zip(
                    THIRD_OCTAVE_FIGURES,
                    jnp.moveaxis(
                        lfe_third_octave_dB(force, PAPER_RATE_Hz, n_record=N_RECORD), -1, 0
                    ),
                )
            )
    return jnp.stack([columns[f] for f in figures], axis=-1)


def _figures_at_phi(phi, heights_m, ball, model, names, specs, figures, num_samples, substeps):
    values = {n: s.from_unconstrained(p) for n, s, p in zip(names, specs, phi)}
    _, ball, model = replace(values, 1.0, ball, model)
    return figures_of(heights_m, ball, model, figures, num_samples, substeps)


@eqx.filter_jit
def _value_and_jacobian(phi, heights_m, ball, model, names, specs, figures, num_samples, substeps):
    def both(p):
        y = _figures_at_phi(p, heights_m, ball, model, names, specs, figures, num_samples, substeps)
        return y, y

    jac, value = jax.jacfwd(both, has_aux=True)(phi)
    return value, jac


class FigureProgram:
    """The figures at ``heights_m`` of ``(ball, model)`` with the parameters ``names`` (declared
    by ``specs``) set from φ: ``value(φ)`` and ``value_and_jacobian(φ)`` (one program for both)
    (NumPy arrays of shape (heights, figures) and (heights, figures, len(φ)))."""

    def __init__(self, heights_m, ball, model: Model, names, specs, figures, contact_time_s=None):
        self.heights_m = np.asarray(heights_m, dtype=float)
        self.names, self.specs, self.figures = tuple(names), tuple(specs), tuple(figures)
        self.ball, self.model = as_arrays((ball, model))
        self.num_samples, self.substeps = 0, 1  # no histories: one program for any contact time
        if any(f.startswith("lfe_") for f in self.figures):
            if contact_time_s is None:
                contact_time_s = np.asarray(simulate(self.heights_m, ball, model).contact_time_s)
            self.num_samples = window_samples(contact_time_s)
            self.substeps = substeps_for_contact(contact_time_s, PAPER_RATE_Hz)
        self._last: tuple | None = None

    def _args(self, phi):
        return (
            jnp.asarray(phi, dtype=jnp.float64),
            jnp.asarray(self.heights_m),
            self.ball,
            self.model,
            self.names,
            self.specs,
            self.figures,
            self.num_samples,
            self.substeps,
        )

    def value(self, phi) -> np.ndarray:
        return self.value_and_jacobian(phi)[0]

    def value_and_jacobian(self, phi) -> tuple[np.ndarray, np.ndarray]:
        """Both from one compiled program (the optimiser asks for the value and then the
        Jacobian at the same φ: the last pair is kept)."""
        phi = np.asarray(phi, dtype=float)
        if self._last is None or not np.array_equal(self._last[0], phi):
            value, jac = _value_and_jacobian(*self._args(phi))
            self._last = (phi.copy(), np.asarray(value), np.asarray(jac))
        return self._last[1], self._last[2]

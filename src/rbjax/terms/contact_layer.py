"""A nonlinear contact layer in series with the shell: the ball's skin where it meets the floor.

The paper's shell (Reissner, Eqs. 1–3) is pressed by a point force from the first instant of
contact, so its force starts with a kink, F = kδ, at every drop height. The real contact starts
on a curved rubber surface whose local stiffness grows with the load, as Hertz's contact does
(F ∝ y^(3/2), Johnson 1985, §4.2) and as the felt of piano hammers does with larger exponents
(F ∝ y^p, p = 2–5: Boutillon 1988; Stulov 1995). Written as a massless layer of compression y in
series with the shell (and the gas, Eq. 4) pressed by u:

    δ = u + y,        F_B(u) + F_G(u) = K y^p,       K = F_ref / y_ref^p,

with y_ref the layer's compression under F_ref = 1 kN (the parameter ``layer_deflection_m``)
and p ≥ 1 its exponent (``layer_exponent``; p = 1 a linear spring, 3/2 Hertz). Both springs
being massless and elastic, the pair is one elastic law F(δ) of the total deflection: the
contact force still depends on δ alone. Near first contact the layer is the softer part and
F ≈ K δ^p rises smoothly (no kink); the smoothing lasts for a deflection of order y_ref, a time
of order y_ref/v that shortens as the drop height grows. This makes the force's content at high
frequency grow faster with the impact speed than the force itself (the note on the
mechanisms above 125 Hz, candidate 2).

The force is found by a safeguarded Newton iteration for u on [0, δ] on the compressions,
u + y_ref (F_e(u)/F_ref)^(1/p) = δ, increasing and concave in u (``NEWTON_STEPS`` steps,
bisection where a Newton step would leave the bracket), unrolled so that ``jax.grad`` and
``jax.jacfwd`` differentiate it; at convergence its derivative is the implicit
function's, du/dδ = K p y^(p−1) / (F′(u) + K p y^(p−1)).
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import ArrayLike

from .declare import Parameter, check_declared

#: The reference force F_ref at which the layer's compression y_ref is given (N).
REFERENCE_FORCE_N = 1000.0
#: Newton steps of the series solve (each bracketed).
NEWTON_STEPS = 10


class ContactLayer(eqx.Module):
    """A massless layer F = K y^p in series with the shell (see the module docstring).

    Attributes:
        layer_deflection_m: y_ref, 0 < y_ref ≤ 50 mm, the layer's compression under 1 kN (m).
        layer_exponent: p, 1 ≤ p ≤ 6 (1: a linear spring; 3/2: Hertz; felt hammers 2–5).

    Raises:
        ValueError: a field outside its range or not finite, named in the message (concrete
            values only).
    """

    layer_deflection_m: ArrayLike
    layer_exponent: ArrayLike
    name: ClassVar[str] = "contact-layer"
    PARAMETERS: ClassVar = {
        "layer_deflection_m": Parameter(
            "m",
            lower=0.0,
            upper=0.05,
            lower_open=True,
            upper_open=False,
            transform="log",
            description=(
                "y_ref, compression of the contact layer under 1 kN (F = K y^p in series with "
                "the shell, K = 1 kN / y_ref^p)"
            ),
        ),
        "layer_exponent": Parameter(
            "1",
            lower=1.0,
            upper=6.0,
            lower_open=False,
            upper_open=False,
            transform="interval",
            description=(
                "p of the contact layer F = K y^p (Hertz 3/2, Johnson 1985; felt 2–5, "
                "Boutillon 1988)"
            ),
        ),
    }

    def __check_init__(self):
        check_declared(self)

    def series_force_N(self, deflection_m, elastic_force_N):
        """F(δ) of the layer in series with ``elastic_force_N`` (u ↦ F_B(u) + F_G(u), increasing,
        0 at 0): the root of F_e(u) = K (δ − u)^p on 0 ≤ u ≤ δ, F = F_e(u); for δ ≤ 0 (no
        contact) F_e(δ), the shell's law continued."""
        raw = jnp.asarray(deflection_m)
        # the solve runs on δ > 0 only (elsewhere on y_ref, its result unused), so that no
        # infinite derivative at δ = 0 turns into NaN in reverse mode
        d = jnp.where(raw > 0.0, raw, self.layer_deflection_m)
        p = jnp.asarray(self.layer_exponent)
        scale = jnp.asarray(self.layer_deflection_m)

        def compression(u):
            # y(u) = y_ref (F_e(u)/F_ref)^(1/p): the layer's compression under the shell's force
            force = jnp.maximum(elastic_force_N(u), 1e-300)
            return scale * (force / REFERENCE_FORCE_N) ** (1.0 / p)

        def residual(u):
            # increasing and concave in u: Newton from the left of the root stays left of it
            y, dy = jax.jvp(compression, (u,), (jnp.ones_like(u),))
            return u + y - d, 1.0 + dy

        # start from the softer spring's share at the shell's secant stiffness k_s = F_e(δ)/δ
        k_s = elastic_force_N(d) / d
        layer_alone = REFERENCE_FORCE_N * (d / scale) ** p
        u = jnp.where(
            layer_alone < k_s * d,
            layer_alone / k_s,
            d - scale * (k_s * d / REFERENCE_FORCE_N) ** (1.0 / p),
        )

        def newton(_, state):
            u, lo, hi = state
            r, slope = residual(u)
            lo = jnp.where(r < 0.0, u, lo)
            hi = jnp.where(r >= 0.0, u, hi)
            step = u - r / slope
            return jnp.where((step >= lo) & (step <= hi), step, 0.5 * (lo + hi)), lo, hi

        u, _, _ = jax.lax.fori_loop(0, NEWTON_STEPS, newton, (u, jnp.zeros_like(d), d))
        # past the end of contact (δ ≤ 0) the shell's own law goes on (negative for δ < 0)
        return jnp.where(raw > 0.0, elastic_force_N(u), elastic_force_N(jnp.minimum(raw, 0.0)))

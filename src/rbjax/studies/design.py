"""A ball designed to the standard: the rubber that sits deepest inside the tolerances.

For a model (elastic, or a damping law's) and a geometry, find the parameters (E with ν held
at 0.5, the terms' parameters; optionally the wall thickness, the mass following it at the
ball's density) that maximise the smallest margin to the limits of the rubber-ball table at
the standard drop height of 1 m (ISO 16283-2:2020 Table A.1 = ISO 10140-5:2010 Table F.1 =
JIS A 1418-2:2019 Table A.2; ``rbjax.spectrum.standards``): L_FE in the octave bands
31.5–500 Hz, contact time 20 ± 2 ms, restitution 0.8 ± 0.1, mass 2.5 ± 0.1 kg.

The margins are compared in units of each item's tolerance (m_i = distance to the nearer limit
/ half-width: 1 at the nominal value, 0 on a limit, < 0 outside), so that 0.1 dB of a ±2 dB
band weighs as 5 ms·10⁻³ of the ±2 ms contact time. The objective is the smooth minimum
−T log Σ exp(−m_i/T) (T = :data:`SOFTMIN_TEMPERATURE`), maximised by Adam (optax) on the
unconstrained coordinates of the parameters (interval transforms over :data:`DESIGN_RANGES`),
the gradient exact (``jax.jacfwd`` through the fast exact paths, :mod:`rbjax.fit.summary_model`),
several starts in one vmapped program; the start with the largest true (hard) smallest margin
wins. The reported margins are then recomputed by ``rbjax.simulate`` and
``rbjax.spectrum.standards.check_conformance`` at the designed parameters.

Geometries: ``jis`` (the paper's JIS ball, R = 89 mm, h = 32 mm, M = 2.5 kg, §4) and ``iso``
(ISO 10140-5 Annex F's informative ball: 180 mm outer diameter, 30 mm wall; 2.5 kg).
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._progress import progress as say
from .._validate import as_float, check_choice, check_range, settings_or_default
from ..fit.layout import FIT_RANGES, fitted_parameter_names, model_from_name, parse_model_terms
from ..fit.summary_model import figures_of, window_samples
from ..solve.angle import local_terms_unsupported
from ..solve.inputs import as_arrays
from ..solve.path import quadrature_unsupported, resolve_path
from ..solve.simulate import simulate
from ..solve.solver import Solver
from ..spectrum.standards import (
    CLAUSE,
    RUBBER_BALL_TOLERANCES,
    TOLERANCED_OCTAVE_BANDS,
    Conformance,
    check_conformance,
)
from ..terms.ball import JIS_RUBBER_BALL, Ball
from ..terms.declare import Parameter
from ..terms.forces import reissner_stiffness_N_per_m
from ..terms.model import Model
from ..terms.parameters import declaration, parameter_table, replace
from ..terms.serialize import ball_to_dict, model_to_dict

GEOMETRIES = {
    "jis": JIS_RUBBER_BALL,
    "iso": Ball(radius_m=0.090, wall_m=0.030, mass_kg=2.5, youngs_Pa=1.6e6, poisson=0.5),
}
#: The search ranges of a design (interval transforms): wide enough for any conforming ball;
#: the ball mode's and the series element's are a fit's (``rbjax.fit.layout.FIT_RANGES``). The
#: contact layer's compression under 1 kN runs to 20 mm (as soft as the JIS ball's shell,
#: ~50 kN/m); a parameter not named here (the layer's exponent, the arrest law's) is searched
#: over its term's declared range (``rbjax.terms.declare``), which must then be finite.
DESIGN_RANGES = {
    "youngs_Pa": (0.5e6, 8.0e6),
    "damping_Ns_per_m": (0.0, 400.0),
    "alpha_s_per_m": (0.0, 1.0),
    "stiffness_ratio": (0.0, 3.0),
    "relaxation_time_s": (1e-4, 0.05),
    "beta": (0.0, 2.0),
    "layer_deflection_m": (1e-4, 0.02),
    **FIT_RANGES,
}
#: The wall's range with ``vary_wall``: the mass follows it at the ball's density and is checked.
WALL_RANGE_M = (0.020, 0.045)
STANDARD_HEIGHT_M = RUBBER_BALL_TOLERANCES.drop_height.nominal
ITEMS = tuple(f"lfe_{b}_dB" for b in TOLERANCED_OCTAVE_BANDS) + (
    "contact_time_s",
    "restitution",
    "mass_kg",
)
_TOLERANCES = tuple(RUBBER_BALL_TOLERANCES.lfe_octave_dB[b] for b in TOLERANCED_OCTAVE_BANDS) + (
    RUBBER_BALL_TOLERANCES.contact_time,
    RUBBER_BALL_TOLERANCES.restitution,
    RUBBER_BALL_TOLERANCES.mass,
)
#: Smooth minimum's temperature, in tolerance half-widths.
SOFTMIN_TEMPERATURE = 0.01


def _range(name, ball, model) -> tuple[float, float]:
    if name == "wall_m":
        return WALL_RANGE_M
    if name in DESIGN_RANGES:
        return DESIGN_RANGES[name]
    spec = declaration(name, ball, model)
    if not (math.isfinite(spec.lower) and math.isfinite(spec.upper)):
        raise ValueError(
            f"parameter {name!r} has no finite range to design in ({spec.lower}, {spec.upper}): "
            "name one in rbjax.studies.design.DESIGN_RANGES"
        )
    return float(spec.lower), float(spec.upper)


def _specs(names, ball, model) -> tuple[Parameter, ...]:
    out = []
    for n in names:
        lo, hi = _range(n, ball, model)
        out.append(Parameter("", lower=lo, upper=hi, transform="interval"))
    return tuple(out)


def _density(ball: Ball) -> float:
    r, h, m = (as_float(x) for x in (ball.radius_m, ball.wall_m, ball.mass_kg))
    return m / (4.0 / 3.0 * math.pi * (r**3 - (r - h) ** 3))


def _ball_model(phi, ball, model, names, specs, density):
    values = {n: s.from_unconstrained(p) for n, s, p in zip(names, specs, phi)}
    if "wall_m" in values:
        r, h = ball.radius_m, values["wall_m"]
        values["mass_kg"] = density * 4.0 / 3.0 * jnp.pi * (r**3 - (r - h) ** 3)
    _, ball, model = replace(values, 1.0, ball, model)
    return ball, model


def normalised_margins(values) -> jnp.ndarray:
    """m_i = min(v − lower, upper − v)/half-width of each item of ``ITEMS`` (last axis)."""
    lower = jnp.array([t.lower for t in _TOLERANCES])
    upper = jnp.array([t.upper for t in _TOLERANCES])
    half = jnp.array([t.plus for t in _TOLERANCES])
    return jnp.minimum(values - lower, upper - values) / half


def _figures(ball, model, num_samples):
    """The items but the mass at 1 m: ``figures_of``; with a contact layer or an arrest law (on
    the ODE, not coupled) the scalars from the ODE with forward-mode sensitivities (``jacfwd``
    cannot run through the default adjoint) and the bands from the sampled path."""
    height = jnp.asarray(STANDARD_HEIGHT_M)
    if local_terms_unsupported(model) is None:
        return figures_of(height, ball, model, tuple(ITEMS[:-1]), num_samples)
    bands = figures_of(height, ball, model, tuple(ITEMS[:-3]), num_samples)
    res = simulate(height, ball, model, solver=Solver(adjoint="forward"))
    return jnp.concatenate([bands, jnp.stack([res.contact_time_s, res.restitution])])


def _item_values(phi, ball, model, names, specs, density, num_samples):
    b, m = _ball_model(phi, ball, model, names, specs, density)
    values = _figures(b, m, num_samples)
    return jnp.concatenate([values, jnp.reshape(b.mass_kg, (1,))])


def _softmin(m):
    return -SOFTMIN_TEMPERATURE * jax.nn.logsumexp(-m / SOFTMIN_TEMPERATURE)


@eqx.filter_jit
def _step_program(phis, ball, model, names, specs, density, num_samples):
    """Per start: (soft-min, its gradient in φ, the items' values), vmapped over the starts."""

    def one(phi):
        def f(p):
            v = _item_values(p, ball, model, names, specs, density, num_samples)
            return _softmin(normalised_margins(v)), v

        return jax.jacfwd(f, has_aux=True)(phi)

    grad, values = jax.vmap(one)(phis)
    return _softmin(normalised_margins(values)), grad, values


@dataclasses.dataclass(frozen=True, eq=False)
class DesignResult:
    """The outcome of :func:`design` (frozen; ``to_dict()``, ``table()``, ``plot()``).

    Attributes:
        model_name, geometry: what was designed.
        ball, model: the designed ball and model (``rbjax.simulate`` them).
        parameters: name → designed value (the free ones; ν held at 0.5).
        conformance: ``check_conformance`` of ``rbjax.simulate`` at 1 m with the design.
        margins: item → margin in its unit (the check's), and ``normalised_margins`` in
            tolerance half-widths.
        smallest_margin: the smallest normalised margin; ``blocking``: the item where it is.
        conforms: every item within its limits.
        start_margins: the smallest normalised margin each start reached.
        optimiser_margins: the margins as the optimiser computed them (for the check against
            ``conformance``).
    """

    model_name: str
    geometry: str
    ball: Ball
    model: Model
    parameters: dict
    conformance: Conformance
    margins: dict
    normalised_margins: dict
    smallest_margin: float
    blocking: str
    conforms: bool
    start_margins: tuple
    optimiser_margins: dict
    steps: int
    time_s: float

    def verdict(self) -> str:
        label = dict(zip(ITEMS, (t.name for t in _TOLERANCES)))[self.blocking]
        if self.conforms:
            return (
                f"{self.model_name} on the {self.geometry.upper()} geometry conforms: smallest "
                f"margin {self.smallest_margin:.3f} of the tolerance ({label}: "
                f"{self.margins[self.blocking]:+.3g} {self._unit(self.blocking)})."
            )
        return (
            f"No {self.model_name} ball on the {self.geometry.upper()} geometry conforms in every "
            f"item: the best smallest margin is {self.smallest_margin:.3f} of the tolerance, "
            f"blocked by {label} ({self.margins[self.blocking]:+.3g} {self._unit(self.blocking)})."
        )

    def _unit(self, item: str) -> str:
        return dict(zip(ITEMS, (t.unit for t in _TOLERANCES)))[item]

    def to_dict(self) -> dict:

        return {
            "kind": "design",
            "clause": CLAUSE,
            "model_name": self.model_name,
            "geometry": self.geometry,
            "ball": ball_to_dict(self.ball),
            "model": model_to_dict(self.model),
            "parameters": dict(self.parameters),
            "margins": dict(self.margins),
            "normalised_margins": dict(self.normalised_margins),
            "smallest_margin": self.smallest_margin,
            "blocking": self.blocking,
            "conforms": self.conforms,
            "verdict": self.verdict(),
            "conformance": self.conformance.to_dict(),
            "start_margins": list(self.start_margins),
            "optimiser_margins": dict(self.optimiser_margins),
            "steps": self.steps,
            "time_s": self.time_s,
        }

    def table(self) -> str:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in self.parameters.items())
        return (
            f"{self.model_name}, {self.geometry.upper()} geometry: {params}\n"
            f"{self.conformance.table()}\n{self.verdict()}"
        )

    def plot(self, out_dir, name: str | None = None) -> Path:
        """A bar chart of the normalised margin of every item
        (``design_<model>_<geometry>.png``)."""
        # lazy: matplotlib costs 0.1–0.2 s at import (pyplot ~1 s)
        import matplotlib

        matplotlib.use("Agg")
        # lazy: matplotlib.pyplot costs ~1 s at import
        import matplotlib.pyplot as plt

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(figsize=(7, 3.4))
        labels = [t.name.replace("coefficient of ", "") for t in _TOLERANCES]
        values = [self.normalised_margins[k] for k in ITEMS]
        ax.bar(labels, values, color=["C2" if v >= 0 else "C3" for v in values])
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_ylabel("margin / tolerance half-width")
        ax.set_title(self.verdict(), fontsize=8, wrap=True)
        ax.tick_params(axis="x", labelrotation=45, labelsize=8)
        fig.tight_layout()
        path = out / (name or f"design_{self.model_name}_{self.geometry}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return path


@dataclasses.dataclass(frozen=True)
class DesignSearch:
    """How :func:`design` searches.

    Args:
        n_starts: how many starts (an integer ≥ 1): the first at the ball's E and the terms'
            start rules, the others drawn uniformly in φ over :data:`DESIGN_RANGES`.
        steps: Adam steps per start (an integer ≥ 0).
        learning_rate: Adam's step size in φ (> 0).
        seed: the seed of the starts drawn.

    Raises:
        ValueError: a field outside its range (the message names it).
    """

    n_starts: int = 8
    steps: int = 150
    learning_rate: float = 0.08
    seed: int = 0

    def __post_init__(self):
        if not (isinstance(self.n_starts, int) and self.n_starts >= 1):
            raise ValueError(
                f"n_starts={self.n_starts!r} is outside the valid range: an integer ≥ 1"
            )
        if not (isinstance(self.steps, int) and self.steps >= 0):
            raise ValueError(f"steps={self.steps!r} is outside the valid range: an integer ≥ 0")
        check_range("learning_rate", self.learning_rate, lower=0.0)


#: The fields of ``DesignSearch`` (``design``'s keywords of the previous release).
SEARCH_FIELDS = tuple(f.name for f in dataclasses.fields(DesignSearch))


def design(
    model: str = "paper",
    geometry: str = "jis",
    *,
    search: DesignSearch | None = None,
    vary_wall: bool = False,
    gas: str = "adiabatic",
    blocked_force: str = "paper",
    progress: bool = False,
) -> DesignResult:
    """Maximise the smallest margin to the rubber-ball table at 1 m (see the module docstring).

    Args:
        model: any model name of the fit (:func:`rbjax.fit.layout.all_model_names`:
            ``paper`` or a damping law, then ``+stiffening``, ``+contact-layer``, ``+arrest``,
            ``+ball-mode``, ``+series-kelvin-voigt``). The contact layer and the arrest law (no
            fast path solves them) and the coupled elements run on the ODE, more slowly (the
            progress line says so).
        geometry: ``jis`` or ``iso`` (:data:`GEOMETRIES`).
        search: a :class:`DesignSearch` (default ``DesignSearch()``): starts, Adam's steps and
            step size, seed.
        vary_wall: also vary the wall thickness (``WALL_RANGE_M``), the mass following it.
        gas: the model name's gas law (as :func:`rbjax.fit.fit`).
        blocked_force: the model name's blocked force (as :func:`rbjax.fit.fit`).
        progress: one line on stderr per start and when done.

    Returns:
        A :class:`DesignResult`: the designed parameters, each item's margin (the tolerance
        check's and the optimiser's), the verdict, and ``save_params`` for a parameter file
        that ``rbjax simulate --params`` takes.

    Raises:
        ValueError: an unknown model name, geometry or option, or a ``search`` of the wrong
            kind (the message names it).
    """
    # lazy: optax costs 0.2 s at import
    import optax  # type: ignore[import-untyped]

    search = settings_or_default("search", DesignSearch, search)
    n_starts, steps, learning_rate, seed = (getattr(search, k) for k in SEARCH_FIELDS)
    check_choice("geometry", geometry, tuple(GEOMETRIES))
    t0 = time.perf_counter()
    parse_model_terms(model)
    ball = GEOMETRIES[geometry]
    base = model_from_name(model, gas=gas, blocked_force=blocked_force)
    names = tuple(n for n in fitted_parameter_names(base) if n != "poisson") + (
        ("wall_m",) if vary_wall else ()
    )
    specs = _specs(names, ball, base)
    start_model = model_from_name(
        model, gas=gas, blocked_force=blocked_force, values=_start_values(base, ball)
    )
    density = _density(ball)
    if resolve_path("auto", base) == "ode":
        say(
            f"design {model}/{geometry}: {quadrature_unsupported(base)}: the search runs on the "
            "ODE, slower than on the fast paths",
            enabled=progress,
        )
    rng = np.random.default_rng(seed)
    first = [
        float(s.to_unconstrained(_value_of(n, ball, start_model))) for n, s in zip(names, specs)
    ]
    phis = np.vstack([first] + [rng.uniform(-3.0, 3.0, len(names)) for _ in range(n_starts - 1)])
    num_samples = window_samples(0.045)  # contacts to ~67 ms: E ≥ 0.5 MPa keeps them shorter
    args = as_arrays((ball, start_model))
    opt = optax.adam(learning_rate)
    state = opt.init(jnp.asarray(phis))
    history = []
    best_phi, best = phis.copy(), np.full(n_starts, -np.inf)
    for k in range(steps + 1):
        soft, grad, values = _step_program(
            jnp.asarray(phis), args[0], args[1], names, specs, density, num_samples
        )
        hard = np.min(np.asarray(normalised_margins(values)), axis=-1)
        hard = np.where(np.isfinite(hard), hard, -np.inf)
        better = hard > best
        best_phi[better], best[better] = phis[better], hard[better]
        history.append(float(np.max(hard)))
        if k == steps:
            break
        g = -np.nan_to_num(np.asarray(grad))  # maximise
        updates, state = opt.update(jnp.asarray(g), state)
        phis = np.asarray(optax.apply_updates(jnp.asarray(phis), updates))
    win = int(np.argmax(best))
    say(
        f"design {model}/{geometry}: smallest margin {best[win]:.4f} after {steps} steps × "
        f"{n_starts} starts ({time.perf_counter() - t0:.1f} s)",
        enabled=progress,
    )
    return _result(
        model, geometry, best_phi[win], args, names, specs, density, num_samples, best, steps, t0
    )


def _start_values(model, ball) -> dict:

    k = float(reissner_stiffness_N_per_m(ball))
    return model.term_starts(k, float(ball.mass_kg), 0.8, 0.02, math.sqrt(2 * 9.80665))


def _value_of(name, ball, model) -> float:
    if name in ("youngs_Pa", "wall_m"):
        return float(getattr(ball, name))

    return next(r.value for r in parameter_table(1.0, ball, model) if r.name == name)


def _result(
    model_name, geometry, phi, args, names, specs, density, num_samples, start_best, steps, t0
) -> DesignResult:
    ball, model = args
    optimiser_values = np.asarray(
        _item_values(jnp.asarray(phi), ball, model, names, specs, density, num_samples)
    )
    b, m = _ball_model(jnp.asarray(phi), ball, model, names, specs, density)
    b = Ball(
        *(
            as_float(getattr(b, f))
            for f in ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")
        )
    )
    m = jax.tree_util.tree_map(lambda x: float(x) if eqx.is_array(x) else x, m)
    res = simulate(STANDARD_HEIGHT_M, b, m)
    lfe = np.asarray(res.lfe_octave_dB())
    check = check_conformance(
        lfe, contact_time_s=res.contact_time_s, restitution=res.restitution, mass_kg=b.mass_kg
    )
    by_name = {it.name: it for it in check.items}
    items = {k: by_name[t.name] for k, t in zip(ITEMS, _TOLERANCES)}
    margins = {k: float(items[k].margin) for k in ITEMS}
    normalised = {k: margins[k] / t.plus for k, t in zip(ITEMS, _TOLERANCES)}
    blocking = min(normalised, key=lambda k: normalised[k])
    values = {n: float(s.from_unconstrained(p)) for n, s, p in zip(names, specs, phi)}
    if "wall_m" in values:
        values["mass_kg"] = as_float(b.mass_kg)
    om = np.asarray(normalised_margins(optimiser_values))
    return DesignResult(
        model_name=model_name,
        geometry=geometry,
        ball=b,
        model=m,
        parameters=values,
        conformance=check,
        margins=margins,
        normalised_margins=normalised,
        smallest_margin=float(normalised[blocking]),
        blocking=blocking,
        conforms=check.passed,
        start_margins=tuple(float(x) for x in start_best),
        optimiser_margins={k: float(x) for k, x in zip(ITEMS, om)},
        steps=steps,
        time_s=time.perf_counter() - t0,
    )

"""What a fit varies: model names, the fitted parameter vector θ and its transforms.

θ holds, in this order, the physical parameters that a fit may free (those of the ball and
the model's terms, in the order of :func:`rbjax.terms.parameters.parameter_names`, except the
geometry R, h, M and the momentum-flux weight, which stay constants), then one onset shift
per record, then (with ``height_error``) one drop-height error per record. Every entry has a
:class:`rbjax.terms.declare.Parameter` declaration, so names, units, bounds and the transforms
φ ↔ θ come from the terms themselves; a new term's parameters are fitted without any change
here.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from ..terms.arrest import WaveLimitedArrest
from ..terms.ball import Ball
from ..terms.ball_mode import BallMode
from ..terms.contact_layer import ContactLayer
from ..terms.damping import DAMPING_MODELS, AbstractDamping
from ..terms.declare import HEIGHT_ERROR, ONSET_SHIFT
from ..terms.forces import CubicStiffening
from ..terms.model import Model
from ..terms.parameters import declaration, parameter_table, replace, to_vector
from ..terms.series_kelvin_voigt import SeriesKelvinVoigt

#: The fitted models that model selection compares by default: the paper's elastic model, one
#: damping law each, Hunt–Crossley with the ball's own mode (the model that meets the held-out
#: accuracy bars on the bundled recordings; selection, not this list, decides whether it is
#: worth its parameters) and with the mode's massless limit (one parameter fewer). Any registered
#: damping law's name is a model name too. Append ``+stiffening`` for the cubic stiffening of the
#: shell, F_B = kδ(1 + β(δ/h)²), and then
#: ``+ball-mode`` for one mode of the ball in series with the shell (``rbjax.BallMode``:
#: μ, f, η fitted), e.g. ``hunt-crossley+stiffening+ball-mode``, and then
#: ``+series-kelvin-voigt`` for its overdamped, massless limit, a spring and a damper in series
#: with the shell (``rbjax.SeriesKelvinVoigt``: C, τ fitted).
MODEL_NAMES = (
    "paper",
    "kelvin-voigt",
    "hunt-crossley",
    "zener",
    "hunt-crossley+ball-mode",
    "hunt-crossley+series-kelvin-voigt",
)
STIFFENING_SUFFIX = "+stiffening"
LAYER_SUFFIX = "+contact-layer"
ARREST_SUFFIX = "+arrest"
BALL_MODE_SUFFIX = "+ball-mode"
SERIES_SUFFIX = "+series-kelvin-voigt"
#: Parameters that are never fitted: constants of the program (``fix`` may still set them).
CONSTANT_PARAMETERS = ("radius_m", "wall_m", "mass_kg", "momentum_flux_weight")
#: Ranges a fit keeps some parameters in (an ``interval`` transform in place of the term's own
#: declaration, which stays what ``simulate`` accepts), where a term's fit could otherwise run
#: to a limit at which its parameters stop meaning anything. The ball mode, fitted free, ran to
#: f = 4e-7 Hz, η = 1.6e11 (a 16 g mass behind a 6.9 kN s/m dashpot, with f and η singular
#: there, correlation +1). A fit keeps it inside: its mass at the contact at least M/100
#: (25 g of the JIS ball), its frequency from a slow degree of freedom (20 Hz, below the
#: contact's own ~25 Hz) to the top of the standard's 1 kHz octave band, its loss factor up to
#: twice critical damping (η = 4). At a bound the fit says so, and the result states the
#: structure in physical terms (mass, stiffness, damping: ``ball_mode_structure``).
#: The series element (the ball mode's massless limit) keeps its spring stiffer than 50 kN/m
#: (C < 2e-5 m/N; about the JIS ball's shell stiffness) and its relaxation time from 0.5 ms
#: (faster, the element is a bare spring and the equations stiff) to 0.1 s (slower, a rigid
#: damper); the fit on the bundled recordings lands at C = 3.0e-6 m/N, τ = 4.6 ms. Wider
#: ranges would raise the sampled path's most sub-steps (``fit_substeps``, set by the fastest
#: corner; each evaluation takes those its own values need).
FIT_RANGES = {
    "mode_mass_ratio": (0.0, 100.0),
    "mode_frequency_Hz": (20.0, 2500.0),
    "mode_loss_factor": (0.0, 4.0),
    "series_compliance_m_per_N": (0.0, 2e-5),
    "series_time_constant_s": (5e-4, 0.1),
}
#: The ``FIT_RANGES`` parameters whose lower bound (not the upper) is the model's fastest rate.
FASTEST_AT_LOWER = ("series_time_constant_s",)


def fit_declaration(name: str, ball, model):
    """The declaration a fit uses for ``name``: the term's own, or its ``FIT_RANGES`` interval."""
    spec = declaration(name, ball, model)
    if name not in FIT_RANGES:
        return spec
    lower, upper = FIT_RANGES[name]
    return dataclasses.replace(
        spec,
        lower=lower,
        upper=upper,
        lower_open=True,
        upper_open=True,
        transform="interval",
        description=f"{spec.description} (fitted in ({lower:g}, {upper:g}))",
    )


def all_model_names() -> tuple[str, ...]:
    """Every model name that :func:`parse_model_terms` accepts and :func:`model_from_name`
    builds: a base, then at most one suffix of each kind, in ``Model.name``'s order.

    Returns:
        The names, a tuple of str: ``paper`` and each registered damping law, then each of
        these with ``+stiffening``, then all of those with ``+contact-layer``, ``+arrest`` and
        ``+contact-layer+arrest``, then all of those with ``+ball-mode``, then all of them
        with ``+series-kelvin-voigt``, then all of them with ``+ball-mode+series-kelvin-voigt``
        (both elements in series with the shell).
    """
    base = ("paper",) + tuple(n for n in DAMPING_MODELS if n != "paper")
    with_stiffening = base + tuple(m + STIFFENING_SUFFIX for m in base)
    local = (LAYER_SUFFIX, ARREST_SUFFIX, LAYER_SUFFIX + ARREST_SUFFIX)
    with_local = with_stiffening + tuple(m + s for s in local for m in with_stiffening)
    elements = (BALL_MODE_SUFFIX, SERIES_SUFFIX, BALL_MODE_SUFFIX + SERIES_SUFFIX)
    return with_local + tuple(m + suffix for suffix in elements for m in with_local)


class ModelTerms(NamedTuple):
    """The terms a model name stands for."""

    laws: tuple[type[AbstractDamping], ...]
    stiffening: bool
    ball_mode: bool
    series: bool
    layer: bool = False
    arrest: bool = False


def parse_model_terms(name: str) -> ModelTerms:
    """(damping law classes, stiffening?, ball mode?, series element?) of a model name such as
    ``zener+stiffening+ball-mode`` (the suffixes in this order, as ``Model.name`` writes them).

    Args:
        name: a model name: ``paper`` or a registered damping law, then optionally
            ``+stiffening``, ``+contact-layer``, ``+arrest``, ``+ball-mode`` and
            ``+series-kelvin-voigt``, in this order.

    Returns:
        A ``ModelTerms`` ``(laws, stiffening, ball_mode, series)``: the damping law classes
        (empty for ``paper``) and whether the name has each of the three suffixes.

    Raises:
        TypeError: ``name`` is not a str (the message names the type received).
        ValueError: what is left of ``name`` without the suffixes is neither ``paper`` nor a
            registered damping law.
    """
    if not isinstance(name, str):
        raise TypeError(
            f"model={name!r} (of type {type(name).__name__}) is not a model name: expected a "
            f"str; valid: {', '.join(all_model_names())}"
        )

    def strip(rest, suffix):
        return (rest[: -len(suffix)], True) if rest.endswith(suffix) else (rest, False)

    rest, series = strip(name, SERIES_SUFFIX)
    rest, mode = strip(rest, BALL_MODE_SUFFIX)
    rest, arrest = strip(rest, ARREST_SUFFIX)
    rest, layer = strip(rest, LAYER_SUFFIX)
    base, stiff = strip(rest, STIFFENING_SUFFIX)
    if base != "paper" and base not in DAMPING_MODELS:
        raise ValueError(
            f"model={name!r} is not a known model; valid: {', '.join(all_model_names())}"
        )
    laws = () if base == "paper" else (DAMPING_MODELS[base],)
    return ModelTerms(laws, stiff, mode, series, layer, arrest)


def parse_model_name(name: str) -> tuple[tuple[type[AbstractDamping], ...], bool]:
    """(damping law classes, stiffening?) of a model name such as ``zener+stiffening``
    (a ``+ball-mode`` suffix is accepted; :func:`parse_model_terms` also says whether it is
    there).

    Args:
        name: a model name (see :func:`parse_model_terms`).

    Returns:
        A tuple ``(laws, stiffening)``: the damping law classes (empty for ``paper``) and
        whether the name has the ``+stiffening`` suffix.

    Raises:
        TypeError: ``name`` is not a str.
        ValueError: ``name`` is not a model name (see :func:`parse_model_terms`).
    """
    terms = parse_model_terms(name)
    return terms.laws, terms.stiffening


def model_from_name(
    name: str, *, gas: str = "adiabatic", blocked_force: str = "paper", values=None
) -> Model:
    """The ``Model`` a model name stands for, its parameters from ``values`` (name → value;
    the ball mode's and the series element's defaults are their ``start``'s for a 50 kN/m shell).

    Args:
        name: a model name (see :func:`all_model_names`).
        gas: the gas term, ``adiabatic`` or ``none``.
        blocked_force: ``paper`` or ``momentum``.
        values: name → value of the terms' parameters (SI units, as named); a damping law's
            parameter not given is 1.0, the stiffening's ``beta`` 0.05. None: every default.

    Returns:
        The ``rbjax.Model`` with the terms the name stands for.

    Raises:
        TypeError: ``name`` is not a str.
        ValueError: ``name`` is not a model name, ``gas`` or ``blocked_force`` is not an
            option, or a value is outside its parameter's range.
    """
    terms = parse_model_terms(name)
    values = dict(values or {})
    damping = tuple(law(**{k: values.get(k, 1.0) for k in law.PARAMETERS}) for law in terms.laws)
    stiffening = CubicStiffening(values.get("beta", 0.05)) if terms.stiffening else None

    def term(cls, present):
        if not present:
            return None
        default = cls.start(5e4, 2.5, 0.8, 0.02, 1.0)
        return cls(**{k: values.get(k, default[k]) for k in cls.PARAMETERS})

    layer = None
    if terms.layer:
        layer = ContactLayer(
            values.get("layer_deflection_m", 1e-3), values.get("layer_exponent", 2.0)
        )
    arrest = None
    if terms.arrest:
        if blocked_force != "paper":
            raise ValueError(
                f"model={name!r} with blocked_force={blocked_force!r}: the arrest law says what "
                "the floor receives of the momentum flux; valid: blocked_force='paper'"
            )
        default = WaveLimitedArrest.start(4.4)
        arrest = WaveLimitedArrest(
            **{k: values.get(k, default[k]) for k in WaveLimitedArrest.PARAMETERS}
        )
    return Model(
        gas=gas,
        blocked_force=blocked_force,
        damping=damping,
        stiffening=stiffening,
        ball_mode=term(BallMode, terms.ball_mode),
        series=term(SeriesKelvinVoigt, terms.series),
        layer=layer,
        arrest=arrest,
    )


def fitted_parameter_names(model: str | Model) -> tuple[str, ...]:
    """The physical parameters a fit of ``model`` frees by default, e.g. ``("youngs_Pa",
    "poisson", "stiffness_ratio", "relaxation_time_s")`` for ``zener``.

    Args:
        model: a model name (see :func:`parse_model_terms`) or an ``rbjax.Model``.

    Returns:
        The names (tuple of str), in the fit's order: E and ν, then the parameters of the
        damping laws, stiffening, ball mode and series element (not R, h, M).

    Raises:
        TypeError: ``model`` is neither a str nor a ``Model``.
        ValueError: ``model`` is not a model name.
    """
    if not isinstance(model, Model):
        model = model_from_name(model)
    names = [row.name for row in parameter_table(1.0, Ball(1.0, 0.5, 1.0, 1.0, 0.0), model)]
    return tuple(n for n in names if n not in CONSTANT_PARAMETERS and n != "height_m")


class FitLayout:
    """Names, declarations and positions of θ for one model structure and data shape."""

    def __init__(self, ball: Ball, model: Model, n_records: int, height_error: bool):
        table = parameter_table(1.0, ball, model)
        self.all_names = tuple(r.name for r in table)  # height first, as in to_vector
        self.physical = tuple(
            n for n in self.all_names if n != "height_m" and n not in CONSTANT_PARAMETERS
        )
        self.constants = tuple(n for n in self.all_names if n in CONSTANT_PARAMETERS)
        self.n_records = n_records
        self.height_error = height_error
        self.names = list(self.physical) + [f"shift[{k}]" for k in range(n_records)]
        if height_error:
            self.names += [f"dh[{k}]" for k in range(n_records)]
        self.specs = tuple(fit_declaration(n, ball, model) for n in self.physical)
        self.specs += (ONSET_SHIFT,) * n_records + (
            (HEIGHT_ERROR,) * n_records if height_error else ()
        )
        self.units = {n: s.unit for n, s in zip(self.physical, self.specs)}
        p = len(self.physical)
        self.shift_slice = slice(p, p + n_records)
        self.dh_slice = slice(p + n_records, p + 2 * n_records) if height_error else None
        self.physical_positions = tuple(self.all_names.index(n) for n in self.physical)
        self.constant_positions = tuple(self.all_names.index(n) for n in self.constants)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(
                f"parameter {name!r} is not in this fit; valid: {', '.join(self.physical)}"
            ) from None

    def theta(self, ball: Ball, model: Model, shifts) -> np.ndarray:
        """θ from a ball, a model (of this layout's structure) and the onset shifts (dh = 0)."""
        values = np.asarray(to_vector(1.0, ball, model))
        theta = np.zeros(len(self.names))
        theta[: len(self.physical)] = values[list(self.physical_positions)]
        theta[self.shift_slice] = shifts
        return theta

    def constant_values(self, ball: Ball, model: Model) -> np.ndarray:
        values = np.asarray(to_vector(1.0, ball, model))
        return values[list(self.constant_positions)]

    def ball_and_model(self, theta, ball: Ball, model: Model) -> tuple[Ball, Model]:
        """The ball and model (of this layout's structure) with the physical values of θ."""
        values = {n: float(theta[i]) for i, n in enumerate(self.physical)}
        _, ball, model = replace(values, 1.0, ball, model)
        return ball, model

    def to_phi(self, theta) -> np.ndarray:
        return np.array([float(s.to_unconstrained(t)) for s, t in zip(self.specs, theta)])

    def from_phi(self, phi) -> tuple[np.ndarray, np.ndarray]:
        """(θ, dθ/dφ) of φ."""
        theta = np.array([float(s.from_unconstrained(x)) for s, x in zip(self.specs, phi)])
        slope = np.array([float(s.slope(x)) for s, x in zip(self.specs, phi)])
        return theta, slope

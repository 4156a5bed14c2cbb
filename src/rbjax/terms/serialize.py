"""Ball and model parameters to and from JSON-ready dicts (the format of ``--params FILE.json``).

    {"ball": {"radius_m": .., "wall_m": .., "mass_kg": .., "youngs_Pa": .., "poisson": ..},
     "model": {"gas": "adiabatic", "blocked_force": "paper", "max_deflection_ratio": 2.0,
               "damping": null | {"name": "zener", "stiffness_ratio": .., "relaxation_time_s": ..},
               "stiffening": null | {"beta": ..},
               "ball_mode": null | {"mode_mass_ratio": .., "mode_frequency_Hz": .., "mode_loss_factor": ..},
               "series": {"series_compliance_m_per_N": .., "series_time_constant_s": ..},
               "layer": {"layer_deflection_m": .., "layer_exponent": ..},
               "arrest": {"name": "arrest", "arrest_speed_m_per_s": .., "arrest_exponent": ..},
               "floor": {"name": "rigid"} | {"name": "infinite-plate", "plate_thickness_m": .., ...}}}

Each element in series with the shell is one table under its class's ``key()`` (``ball_mode``,
``series``, or a new element's ``name``), absent without it (``ball_mode`` is written null, as
files have always had it); the tables present are read back in the file's order. ``layer`` (a ``ContactLayer``) and
``arrest`` (an arrest law, by name) are absent without them.

A fit's JSON output carries these two keys, so ``rbjax simulate --params FIT.json`` predicts
with the fitted model.
"""  # noqa: E501

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import as_float
from .arrest import ARREST_LAWS
from .ball import Ball
from .contact_layer import ContactLayer
from .damping import DAMPING_MODELS
from .floors.kinds import FLOOR_MODELS
from .forces import CubicStiffening
from .model import Model
from .series_element import SERIES_ELEMENTS

#: The keys of a model's table besides its elements' (``SERIES_ELEMENTS``' ``key()``).
MODEL_KEYS = (
    "gas",
    "blocked_force",
    "momentum_flux_weight",
    "max_deflection_ratio",
    "damping",
    "stiffening",
    "layer",
    "arrest",
    "floor",
)


def _fields(module) -> dict:
    return {f.name: _plain(getattr(module, f.name)) for f in dataclasses.fields(module)}


def _plain(x):
    if isinstance(x, str) or x is None:
        return x
    arr = np.asarray(x)
    return float(arr) if arr.ndim == 0 else arr.tolist()


def ball_to_dict(ball: Ball) -> dict:
    return _fields(ball)


def _table(what: str, d) -> dict:
    if not isinstance(d, dict):
        raise ValueError(f"{what}: expected a table/object of parameters, got {d!r}")
    return d


def ball_from_dict(d: dict) -> Ball:
    d = _table("ball", d)
    names = [f.name for f in dataclasses.fields(Ball)]
    missing = [n for n in names if n not in d]
    if missing:
        raise ValueError(f"ball parameters missing {missing}; expected keys {names}")
    try:
        return Ball(**{n: float(d[n]) for n in names})
    except (TypeError, ValueError) as err:
        raise ValueError(f"ball: bad parameter value ({err})") from err


def _construct(what: str, cls, fields: dict):
    valid = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(fields) - set(valid))
    if unknown:
        raise ValueError(f"{what}: unknown keys {unknown}; valid: {valid}")
    try:
        return cls(**fields)
    except TypeError as err:
        raise ValueError(f"{what}: bad parameters ({err}); valid keys: {valid}") from err


def model_to_dict(model: Model) -> dict:
    """``damping`` is one table (one law), a list of tables (laws in parallel) or null."""
    laws = [{"name": d.name, **_fields(d)} for d in model.damping]
    damping = None if not laws else laws[0] if len(laws) == 1 else laws
    stiffening = None if model.stiffening is None else _fields(model.stiffening)
    w = as_float(model.momentum_flux_weight)
    out: dict[str, Any] = {"gas": model.gas}
    out.update(
        {"blocked_force": model.blocked_force} if w in (0.0, 1.0) else {"momentum_flux_weight": w}
    )
    out.update(
        {
            "max_deflection_ratio": as_float(model.max_deflection_ratio),
            "damping": damping,
            "stiffening": stiffening,
        }
    )
    if model.layer is not None:
        out["layer"] = _fields(model.layer)
    if model.arrest is not None:
        out["arrest"] = {"name": model.arrest.name, **_fields(model.arrest)}
    out["ball_mode"] = None  # null without a ball mode, as files have always had it
    for element in model.series_elements:  # the others absent without them
        out[element.key()] = _fields(element)
    out["floor"] = {"name": model.floor.name, **_fields(model.floor)}
    return out


def model_from_dict(d: dict) -> Model:
    d = _table("model", d)
    damping = d.get("damping")
    laws = [] if damping is None else damping if isinstance(damping, list) else [damping]
    terms = []
    for law in laws:
        law = dict(_table("damping", law))
        name = law.pop("name", None)
        if name not in DAMPING_MODELS:
            raise ValueError(f"damping name={name!r} is not known; valid: {sorted(DAMPING_MODELS)}")
        terms.append(_construct(f"damping {name!r}", DAMPING_MODELS[name], law))
    stiffening = d.get("stiffening")
    if stiffening is not None:
        stiffening = _construct("stiffening", CubicStiffening, _table("stiffening", stiffening))
    classes = {cls.key(): cls for cls in SERIES_ELEMENTS.values()}
    unknown = sorted(set(d) - set(MODEL_KEYS) - set(classes))
    if unknown:
        raise ValueError(
            f"model: unknown keys {unknown}; valid: {', '.join(MODEL_KEYS + tuple(classes))} (an "
            "element in series with the shell is known once its class is defined)"
        )
    elements = tuple(
        _construct(key, classes[key], _table(key, value))
        for key, value in d.items()
        if key in classes and value is not None
    )
    floor = dict(_table("floor", d.get("floor", {"name": "rigid"})))
    floor_name = floor.pop("name", None)
    if floor_name not in FLOOR_MODELS:
        raise ValueError(f"floor name={floor_name!r} is not known; valid: {sorted(FLOOR_MODELS)}")
    layer = d.get("layer")
    if layer is not None:
        layer = _construct("layer", ContactLayer, _table("layer", layer))
    arrest = d.get("arrest")
    if arrest is not None:
        arrest = dict(_table("arrest", arrest))
        arrest_name = arrest.pop("name", None)
        if arrest_name not in ARREST_LAWS:
            raise ValueError(
                f"arrest name={arrest_name!r} is not known; valid: {sorted(ARREST_LAWS)}"
            )
        arrest = _construct(f"arrest {arrest_name!r}", ARREST_LAWS[arrest_name], arrest)
    weight = d.get("momentum_flux_weight")
    return Model(
        gas=d.get("gas", "adiabatic"),
        blocked_force=None if weight is not None else d.get("blocked_force", "paper"),
        damping=tuple(terms),
        stiffening=stiffening,
        max_deflection_ratio=float(d.get("max_deflection_ratio", 2.0)),
        momentum_flux_weight=None if weight is None else float(weight),
        series_elements=elements,
        floor=_construct(f"floor {floor_name!r}", FLOOR_MODELS[floor_name], floor),
        layer=layer,
        arrest=arrest,
    )


def jsonable(x):
    """Plain Python for ``json``: arrays to lists, NaN/inf to ``None`` (JSON ``null``)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (str, bool)) or x is None:
        return x
    if hasattr(x, "to_dict"):
        return jsonable(x.to_dict())
    arr = np.asarray(x)
    if arr.dtype == object:
        return [jsonable(v) for v in arr.tolist()] if arr.ndim else jsonable(arr.item())
    if arr.ndim:
        return [jsonable(v) for v in arr.tolist()]
    value = arr.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def to_json(obj) -> str:
    """Strict JSON text of ``obj`` (through :func:`jsonable`: no NaN tokens)."""
    return json.dumps(jsonable(obj), indent=2, allow_nan=False)


def save_params(path, ball: Ball, model: Model, **extra) -> None:
    """Write ``{"ball": .., "model": .., **extra}`` as JSON."""
    Path(path).write_text(
        json.dumps({"ball": ball_to_dict(ball), "model": model_to_dict(model), **extra}, indent=2)
    )


def load_params(path) -> tuple[Ball, Model]:
    """Read a ball and model from a JSON file with ``ball`` and ``model`` keys (e.g. a fit's
    output)."""
    try:
        d = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as err:
        raise ValueError(f"params file {path}: cannot read JSON ({err})") from err
    if not isinstance(d, dict) or "ball" not in d or "model" not in d:
        raise ValueError(f"params file {path}: expected an object with 'ball' and 'model' keys")
    return ball_from_dict(d["ball"]), model_from_dict(d["model"])

"""Ball and model parameters to and from JSON-ready dicts (the format of ``--params FILE.json``).

    {"ball": {"radius_m": .., "wall_m": .., "mass_kg": .., "youngs_Pa": .., "poisson": ..},
     "model": {"gas": "adiabatic", "blocked_force": "paper", "max_deflection_ratio": 2.0,
               "damping": null | {"name": "zener", "stiffness_ratio": .., "relaxation_time_s": ..},
               "stiffening": null | {"beta": ..}}}

A fit's JSON output carries these two keys, so ``rbjax simulate --params FIT.json`` predicts
with the fitted model.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from .ball import Ball
from .forces import DAMPING_MODELS, CubicStiffening
from .model import Model


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
    damping = None
    if model.damping is not None:
        damping = {"name": model.damping.name, **_fields(model.damping)}
    stiffening = None if model.stiffening is None else _fields(model.stiffening)
    return {
        "gas": model.gas,
        "blocked_force": model.blocked_force,
        "max_deflection_ratio": float(model.max_deflection_ratio),
        "damping": damping,
        "stiffening": stiffening,
    }


def model_from_dict(d: dict) -> Model:
    d = _table("model", d)
    damping = d.get("damping")
    if damping is not None:
        damping = dict(_table("damping", damping))
        name = damping.pop("name", None)
        if name not in DAMPING_MODELS:
            raise ValueError(f"damping name={name!r} is not known; valid: {sorted(DAMPING_MODELS)}")
        damping = _construct(f"damping {name!r}", DAMPING_MODELS[name], damping)
    stiffening = d.get("stiffening")
    if stiffening is not None:
        stiffening = _construct("stiffening", CubicStiffening, _table("stiffening", stiffening))
    return Model(
        gas=d.get("gas", "adiabatic"),
        blocked_force=d.get("blocked_force", "paper"),
        damping=damping,
        stiffening=stiffening,
        max_deflection_ratio=float(d.get("max_deflection_ratio", 2.0)),
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
    Path(path).write_text(json.dumps({"ball": ball_to_dict(ball), "model": model_to_dict(model), **extra}, indent=2))


def load_params(path) -> tuple[Ball, Model]:
    """Read a ball and model from a JSON file with ``ball`` and ``model`` keys (e.g. a fit's output)."""
    try:
        d = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as err:
        raise ValueError(f"params file {path}: cannot read JSON ({err})") from err
    if not isinstance(d, dict) or "ball" not in d or "model" not in d:
        raise ValueError(f"params file {path}: expected an object with 'ball' and 'model' keys")
    return ball_from_dict(d["ball"]), model_from_dict(d["model"])

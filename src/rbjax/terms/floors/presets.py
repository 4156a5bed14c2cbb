"""Floors by name, and floors described in a TOML or JSON file.

``floor_preset(name)`` gives one of ``FLOOR_PRESETS``: the rigid floor of the paper, or an
infinite thin plate of a material of :mod:`rbjax.terms.floors.materials` and a thickness
(Z = 8√(B′m″), ``rbjax.terms.floors.kinds.plate_impedance_Ns_per_m``).
``load_floor(name_or_path)`` takes a preset name or a file describing a floor (``.toml`` or
``.json``), one table with a ``type``:

- ``type = "rigid"``: the immobile floor;
- ``type = "infinite-plate"``: ``thickness_m`` and either ``material`` (a name of
  ``rbjax.terms.floors.materials.MATERIALS``) or ``youngs_Pa``, ``density_kg_per_m3`` and
  ``poisson`` (explicit values override the material's);
- ``type = "dashpot"``: ``impedance_Ns_per_m`` (a real point impedance, u̇ = F/Z);
- ``type = "modal"``: ``mass_kg``, ``frequency_Hz``, ``loss_factor`` (one value per mode;
  one ``loss_factor`` for all modes is allowed): ``rbjax.terms.floors.kinds.ModalFloor``;
- ``type = "floating"``: a screed on a resilient layer over a base mode,
  ``rbjax.terms.floors.floating.FloatingFloor``, by its constructor's names: ``screed_thickness_m``,
  ``screed_density_kg_per_m3``, ``area_m2`` (the screed area moving with the ball),
  ``dynamic_stiffness_N_per_m3`` (s′ of the layer, EN 29052-1), ``base_mass_kg``,
  ``base_frequency_Hz`` (0: a free mass) and, optionally, ``layer_loss_factor`` (default 0.1)
  and ``base_loss_factor`` (default 0.02); each within the bounds the floor declares
  (``FloatingFloor.PARAMETERS``).

An optional ``name`` labels the floor (default: the file's stem); ``description`` is free text.
Any other key, a missing one or a value out of range raises ``ValueError`` naming the file,
the key, the value and the valid range. ``src/rbjax/examples/floors/`` has example files
(``floating-screed.toml``: modal; ``floating-screed-70mm.toml``: floating).
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .floating import FloatingFloor
from .kinds import AbstractFloor, Dashpot, InfinitePlate, ModalFloor, Rigid
from .materials import MATERIALS, material

#: preset name → (material name, plate thickness in m); ``rigid`` is the paper's floor.
PLATE_PRESETS: dict[str, tuple[str, float]] = {
    "concrete-140mm": ("concrete", 0.140),
    "concrete-150mm": ("concrete", 0.150),
    "concrete-200mm": ("concrete", 0.200),
    "clt-140mm": ("clt", 0.140),
    "steel-10mm": ("steel", 0.010),
    "chipboard-22mm": ("chipboard", 0.022),
    "osb-15mm": ("osb", 0.015),
    "osb-22mm": ("osb", 0.022),
}
FLOOR_PRESETS: tuple[str, ...] = ("rigid", *PLATE_PRESETS)

#: ``type`` → (required keys, optional keys) of a floor file, besides ``type``, ``name`` and
#: ``description``.
FLOOR_FILE_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "rigid": ((), ()),
    "infinite-plate": (("thickness_m",), ("material", "youngs_Pa", "density_kg_per_m3", "poisson")),
    "dashpot": (("impedance_Ns_per_m",), ()),
    "modal": (("mass_kg", "frequency_Hz", "loss_factor"), ()),
    "floating": (
        (
            "screed_thickness_m",
            "screed_density_kg_per_m3",
            "area_m2",
            "dynamic_stiffness_N_per_m3",
            "base_mass_kg",
            "base_frequency_Hz",
        ),
        ("layer_loss_factor", "base_loss_factor"),
    ),
}
_COMMON_KEYS = ("type", "name", "description")


def plate(material_name: str, thickness_m: float) -> InfinitePlate:
    """The infinite plate of the named material (``rbjax.terms.floors.materials``) and thickness
    (within the material's plausible range, ``Material.check_thickness``)."""
    m = material(material_name)
    m.check_thickness(thickness_m)
    return InfinitePlate(
        plate_thickness_m=thickness_m,
        plate_youngs_Pa=m.youngs_Pa,
        plate_density_kg_per_m3=m.density_kg_per_m3,
        plate_poisson=m.poisson,
    )


def floor_preset(name: str) -> AbstractFloor:
    """The floor preset called ``name`` (one of ``FLOOR_PRESETS``)."""
    if name == "rigid":
        return Rigid()
    if name not in PLATE_PRESETS:
        raise ValueError(
            f"floor={name!r} is not a floor preset; valid: {', '.join(FLOOR_PRESETS)} (or a "
            ".toml/.json floor file)"
        )
    return plate(*PLATE_PRESETS[name])


def load_floor(name_or_path: str | Path) -> AbstractFloor:
    """A floor preset by name, or the floor a ``.toml``/``.json`` file describes (module
    docstring)."""
    return load_named_floor(name_or_path)[1]


def load_named_floor(name_or_path: str | Path) -> tuple[str, AbstractFloor]:
    """(label, floor) of ``load_floor``: the preset name, or the file's ``name`` (default: its
    stem)."""
    text = str(name_or_path)
    if isinstance(name_or_path, str) and text in FLOOR_PRESETS:
        return text, floor_preset(text)
    path = Path(name_or_path)
    if not path.is_file():
        if path.suffix.lower() in (".toml", ".json"):
            raise ValueError(f"floor file {text!r} does not exist")
        raise ValueError(
            f"floor={text!r} is neither a floor preset nor a floor file; valid: "
            f"{', '.join(FLOOR_PRESETS)} or a .toml/.json file"
        )
    table = _read(path)
    try:
        return str(table.get("name", path.stem)), floor_from_mapping(table)
    except ValueError as err:
        raise ValueError(f"floor file {text}: {err}") from err


def _read(path: Path) -> dict:
    suffix = path.suffix.lower()
    try:
        if suffix == ".toml":
            with path.open("rb") as f:
                table = tomllib.load(f)
        elif suffix == ".json":
            table = json.loads(path.read_text())
        else:
            raise ValueError(
                f"floor file {str(path)!r} has the suffix {suffix!r}; valid: .toml, .json"
            )
    except (tomllib.TOMLDecodeError, json.JSONDecodeError, UnicodeDecodeError) as err:
        raise ValueError(f"floor file {str(path)!r} cannot be parsed: {err}") from err
    if not isinstance(table, dict):
        raise ValueError(
            f"floor file {str(path)!r} must hold one table (a JSON object), not "
            f"{type(table).__name__}"
        )
    return table


def _number(
    key: str,
    value,
    *,
    lower: float,
    lower_open: bool = True,
    upper: float = math.inf,
    upper_open: bool = True,
) -> float:
    lo, hi = "(" if lower_open else "[", ")" if upper_open else "]"
    valid = f"{lo}{lower:g}, {upper:g}{hi}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{key}={value!r} is not a number; valid range {valid}")
    x = float(value)
    below = x <= lower if lower_open else x < lower
    above = x >= upper if upper_open else x > upper
    if not math.isfinite(x) or below or above:
        raise ValueError(f"{key}={value!r} is outside the valid range {valid}")
    return x


def _numbers(key: str, value, **bounds) -> list[float]:
    values = value if isinstance(value, list) else [value]
    if not values:
        raise ValueError(f"{key}=[] is empty; give one value per mode")
    return [
        _number(f"{key}[{i}]" if isinstance(value, list) else key, v, **bounds)
        for i, v in enumerate(values)
    ]


def floor_from_mapping(table: Mapping) -> AbstractFloor:
    """The floor a parsed floor file describes (see the module docstring)."""
    kind = table.get("type")
    if kind not in FLOOR_FILE_KEYS:
        raise ValueError(
            f"type={kind!r} is not a floor type; valid: "
            f"{', '.join(repr(k) for k in FLOOR_FILE_KEYS)}"
        )
    required, optional = FLOOR_FILE_KEYS[kind]
    allowed = (*_COMMON_KEYS, *required, *optional)
    for key in table:
        if key not in allowed:
            raise ValueError(
                f"key {key!r} is not known for type={kind!r}; valid keys: {', '.join(allowed)}"
            )
    for key in required:
        if key not in table:
            raise ValueError(f"type={kind!r} needs the key {key!r}")
    if kind == "rigid":
        return Rigid()
    if kind == "dashpot":
        return Dashpot(
            floor_impedance_Ns_per_m=_number(
                "impedance_Ns_per_m", table["impedance_Ns_per_m"], lower=0.0
            )
        )
    if kind == "modal":
        return ModalFloor(
            mass_kg=_numbers("mass_kg", table["mass_kg"], lower=0.0),
            frequency_Hz=_numbers(
                "frequency_Hz", table["frequency_Hz"], lower=0.0, lower_open=False
            ),
            loss_factor=_numbers("loss_factor", table["loss_factor"], lower=0.0, lower_open=False),
        )
    if kind == "floating":
        bounds = FloatingFloor.PARAMETERS
        values = {
            key: _number(
                key,
                table[key],
                lower=bounds[key].lower,
                lower_open=bounds[key].lower_open,
                upper=bounds[key].upper,
                upper_open=bounds[key].upper_open,
            )
            for key in (*required, *optional)
            if key in table
        }
        return FloatingFloor(**values)
    return _plate_from_mapping(table)


def _plate_from_mapping(table: Mapping) -> InfinitePlate:
    values: dict[str, float] = {}
    if "material" in table:
        name = table["material"]
        if name not in MATERIALS:
            raise ValueError(
                f"material={name!r} is not a known material; valid: {', '.join(MATERIALS)}"
            )
        m = MATERIALS[name]
        values = {
            "youngs_Pa": m.youngs_Pa,
            "density_kg_per_m3": m.density_kg_per_m3,
            "poisson": m.poisson,
        }
    bounds: dict[str, dict[str, Any]] = {
        "youngs_Pa": dict(lower=0.0),
        "density_kg_per_m3": dict(lower=0.0),
        "poisson": dict(lower=-1.0, upper=0.5, upper_open=False),
    }
    for key, bound in bounds.items():
        if key in table:
            values[key] = _number(key, table[key], **bound)
    missing = [k for k in bounds if k not in values]
    if missing:
        raise ValueError(
            "type='infinite-plate' needs 'material' or the keys "
            f"{', '.join(repr(k) for k in missing)}"
        )
    thickness = _number("thickness_m", table["thickness_m"], lower=0.0)
    if "material" in table:
        MATERIALS[table["material"]].check_thickness(thickness)
    return InfinitePlate(
        plate_thickness_m=thickness,
        plate_youngs_Pa=values["youngs_Pa"],
        plate_density_kg_per_m3=values["density_kg_per_m3"],
        plate_poisson=values["poisson"],
    )

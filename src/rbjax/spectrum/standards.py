"""The rubber-ball heavy impact source as printed in the standards, and a conformance check.

The same requirements appear in three standards:

* ISO 16283-2:2020, Annex A, Table A.1;
* ISO 10140-5:2010 (+A1:2014), Annex F, Table F.1;
* JIS A 1418-2:2019, Annex A, Table A.2.

Octave-band force exposure level L_FE (dB re 1 N, T0 = 1 s; Schoenwald et al. 2011,
Eq. 11) for a free drop from the standard height onto a rigid (blocked) force plate, and the
ball's mechanical properties:

=====================  ===============
31.5 Hz                39.0 ± 1.0 dB
63 Hz                  31.0 ± 1.5 dB
125 Hz                 23.0 ± 1.5 dB
250 Hz                 17.0 ± 2.0 dB
500 Hz                 12.5 ± 2.0 dB
drop height            1.00 ± 0.01 m
contact time           20 ± 2 ms
mass                   2.5 ± 0.1 kg
restitution            0.8 ± 0.1
=====================  ===============

The 1000 Hz octave (reported by :func:`rbjax.spectrum.levels.lfe_octave_dB`) has no tolerance.
Plain Python/NumPy; no JAX needed (JAX and NumPy scalars are accepted as values).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from .bands import OCTAVE_BANDS

__all__ = [
    "Tolerance",
    "RubberBallTolerances",
    "RUBBER_BALL_TOLERANCES",
    "TOLERANCED_OCTAVE_BANDS",
    "CLAUSE",
    "CheckItem",
    "Conformance",
    "check_conformance",
]

#: Where the rubber-ball requirements are printed (identical in all three standards).
CLAUSE = (
    "ISO 16283-2:2020 Annex A Table A.1 = ISO 10140-5:2010 Annex F Table F.1 = "
    "JIS A 1418-2:2019 Annex A Table A.2"
)

#: The octave bands (nominal mid-band frequency labels, IEC 61260-1) that carry a tolerance.
TOLERANCED_OCTAVE_BANDS = ("31.5", "63", "125", "250", "500")

# the octave bands reported by rbjax.spectrum.levels.lfe_octave_dB
_ALL_OCTAVE_BANDS = OCTAVE_BANDS


def _printed(x: float) -> float:
    """A limit as the standard prints it: float round-off of nominal ± tolerance removed."""
    return float(f"{x:.12g}")


@dataclass(frozen=True)
class Tolerance:
    """A printed requirement ``nominal (−minus, +plus) unit`` and where it is printed.

    ``lower``/``upper`` are the limits; a value on a limit conforms.
    """

    name: str
    nominal: float
    minus: float
    plus: float
    unit: str
    clause: str = CLAUSE

    @property
    def lower(self) -> float:
        """nominal − minus, as printed (rounded to 12 significant digits: 0.8 − 0.1 is 0.7)."""
        return _printed(self.nominal - self.minus)

    @property
    def upper(self) -> float:
        """nominal + plus, as printed (rounded to 12 significant digits)."""
        return _printed(self.nominal + self.plus)

    def margin(self, value: float) -> float:
        """Signed distance to the nearer limit, in ``unit``: > 0 inside, 0 on a limit, < 0
        outside."""
        return min(value - self.lower, self.upper - value)

    def __str__(self) -> str:
        pm = f"± {self.plus:g}" if self.plus == self.minus else f"-{self.minus:g}/+{self.plus:g}"
        return f"{self.name}: {self.nominal:g} {pm} {self.unit}"


def _band(label: str, nominal_dB: float, tol_dB: float) -> Tolerance:
    return Tolerance(f"L_FE {label} Hz", nominal_dB, tol_dB, tol_dB, "dB re 1 N")


@dataclass(frozen=True)
class RubberBallTolerances:
    """The printed table: octave-band L_FE at the standard drop height and the mechanical
    properties of the ball (see the module docstring for the clauses)."""

    octave_bands: tuple[Tolerance, ...]
    drop_height: Tolerance
    contact_time: Tolerance
    mass: Tolerance
    restitution: Tolerance
    clause: str = CLAUSE

    @property
    def lfe_octave_dB(self) -> Mapping[str, Tolerance]:
        """Band tolerances keyed by the nominal labels "31.5" … "500" (read-only)."""
        return MappingProxyType(dict(zip(TOLERANCED_OCTAVE_BANDS, self.octave_bands)))


#: ISO 16283-2:2020 Table A.1 = ISO 10140-5:2010 Table F.1 = JIS A 1418-2:2019 Table A.2.
RUBBER_BALL_TOLERANCES = RubberBallTolerances(
    octave_bands=(
        _band("31.5", 39.0, 1.0),
        _band("63", 31.0, 1.5),
        _band("125", 23.0, 1.5),
        _band("250", 17.0, 2.0),
        _band("500", 12.5, 2.0),
    ),
    drop_height=Tolerance("drop height", 1.00, 0.01, 0.01, "m"),
    contact_time=Tolerance("contact time", 20.0e-3, 2.0e-3, 2.0e-3, "s"),
    mass=Tolerance("mass", 2.5, 0.1, 0.1, "kg"),
    restitution=Tolerance("coefficient of restitution", 0.8, 0.1, 0.1, "1"),
)


# --------------------------------------------------------------------------------------
# conformance
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CheckItem:
    """One checked requirement: the value, its limits, the signed margin (item's unit,
    positive inside), whether it passed, and the clause."""

    name: str
    value: float
    lower: float
    upper: float
    margin: float
    passed: bool
    unit: str
    clause: str

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "value": self.value,
            "lower": self.lower,
            "upper": self.upper,
            "margin": self.margin,
            "passed": self.passed,
            "unit": self.unit,
            "clause": self.clause,
        }


@dataclass(frozen=True)
class Conformance:
    """Result of :func:`check_conformance`: the items checked and the overall verdict
    (every item within its limits; vacuously True when nothing was given)."""

    items: tuple[CheckItem, ...]
    clause: str = field(default=CLAUSE)

    @property
    def passed(self) -> bool:
        return all(item.passed for item in self.items)

    @property
    def failed(self) -> tuple[CheckItem, ...]:
        return tuple(item for item in self.items if not item.passed)

    def __getitem__(self, name: str) -> CheckItem:
        for item in self.items:
            if item.name == name:
                return item
        raise KeyError(f"{name!r}; items: {', '.join(i.name for i in self.items)}")

    def __bool__(self) -> bool:
        return self.passed

    def table(self) -> str:
        """A readable plain-text table, one line per item, and the verdict."""
        header = (
            f"{'item':<28} {'value':>10} {'lower':>10} {'upper':>10} {'margin':>10}  {'unit':<10} "
            "result"
        )
        lines = [header, "-" * len(header)]
        for it in self.items:
            lines.append(
                f"{it.name:<28} {it.value:>10.4g} {it.lower:>10.4g} {it.upper:>10.4g} "
                f"{it.margin:>+10.3g}  {it.unit:<10} {'pass' if it.passed else 'FAIL'}"
            )
        lines.append("-" * len(header))
        lines.append(f"overall: {'PASS' if self.passed else 'FAIL'}   ({self.clause})")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()

    def to_dict(self) -> dict:
        """JSON-ready: plain floats, bools and strings."""
        return {
            "passed": self.passed,
            "clause": self.clause,
            "items": [item.to_dict() for item in self.items],
        }


def _scalar(name: str, value) -> float:
    """A finite real scalar from a Python/NumPy/JAX number, else ValueError naming it.

    A float32/float16 value is taken as the decimal number it prints as (np.float32(0.7)
    is 0.7, not 0.699999988), so a value given on a limit stays on it.
    """
    arr = np.asarray(value)
    if arr.dtype.kind not in "biuf":
        raise ValueError(f"{name}={value!r} is not valid: expected a finite real number")
    if arr.shape != ():
        raise ValueError(f"{name}={value!r} has shape {arr.shape}; expected a scalar")
    if arr.dtype.kind == "f" and arr.dtype != np.float64:
        # arr[()] of a 0-d array is a numpy scalar; numpy's stubs type it as an ndarray.
        x = float(np.format_float_positional(arr[()], unique=True))  # type: ignore[arg-type]
    else:
        x = float(arr)
    if not math.isfinite(x):
        raise ValueError(f"{name}={x!r} is not valid: expected a finite real number")
    return x


def _band_values(lfe_octave_dB) -> dict[str, float]:
    """Mapping label→dB, or an array in OCTAVE_BANDS order (5 or 6 values), to floats
    for the toleranced bands."""
    if isinstance(lfe_octave_dB, Mapping):
        unknown = set(map(str, lfe_octave_dB)) - set(_ALL_OCTAVE_BANDS)
        if unknown:
            raise ValueError(
                f"lfe_octave_dB has unknown band labels {sorted(unknown)}; "
                f"valid labels: {', '.join(_ALL_OCTAVE_BANDS)}"
            )
        given = {str(k): v for k, v in lfe_octave_dB.items()}
        return {
            label: _scalar(f"lfe_octave_dB[{label!r}]", given[label])
            for label in TOLERANCED_OCTAVE_BANDS
            if label in given
        }
    arr = np.asarray(lfe_octave_dB, dtype=float)
    if arr.ndim != 1 or arr.shape[0] not in (len(TOLERANCED_OCTAVE_BANDS), len(_ALL_OCTAVE_BANDS)):
        raise ValueError(
            f"lfe_octave_dB={arr.tolist()!r} has shape {arr.shape}; expected shape (5,) "
            f"({', '.join(TOLERANCED_OCTAVE_BANDS)} Hz) or (6,) ({', '.join(_ALL_OCTAVE_BANDS)} Hz)"
        )
    return {
        label: _scalar(f"lfe_octave_dB[{i}] ({label} Hz)", arr[i])
        for i, label in enumerate(TOLERANCED_OCTAVE_BANDS)
    }


def _item(tol: Tolerance, value: float) -> CheckItem:
    margin = tol.margin(value)
    return CheckItem(
        name=tol.name,
        value=value,
        lower=tol.lower,
        upper=tol.upper,
        margin=margin,
        passed=bool(tol.lower <= value <= tol.upper),
        unit=tol.unit,
        clause=tol.clause,
    )


def check_conformance(
    lfe_octave_dB=None,
    *,
    contact_time_s=None,
    restitution=None,
    mass_kg=None,
    height_m=None,
    tolerances: RubberBallTolerances = RUBBER_BALL_TOLERANCES,
) -> Conformance:
    """Check values against the rubber-ball table (ISO 16283-2:2020 Table A.1 = ISO
    10140-5:2010 Table F.1 = JIS A 1418-2:2019 Table A.2); only what is given is checked.

    Args:
      lfe_octave_dB: octave-band L_FE at the standard drop height, dB re 1 N: a mapping
        label→dB (any of "31.5" … "1000"), or an array in ``OCTAVE_BANDS`` order (6 values,
        31.5 Hz–1 kHz, or the first 5). Only 31.5–500 Hz are toleranced.
      contact_time_s: contact time, s (20 ± 2 ms).
      restitution: coefficient of restitution (0.8 ± 0.1).
      mass_kg: mass of the ball, kg (2.5 ± 0.1 kg).
      height_m: drop height, m (1.00 ± 0.01 m).

    A value on a limit conforms (margin 0). Values may be Python, NumPy or JAX scalars.

    Raises:
      ValueError: a NaN/inf value or an array of the wrong shape, naming the parameter,
        its value and the valid range/shape.
    """
    items = []
    if lfe_octave_dB is not None:
        bands = tolerances.lfe_octave_dB
        for label, value in _band_values(lfe_octave_dB).items():
            items.append(_item(bands[label], value))
    for name, value, tol in (
        ("contact_time_s", contact_time_s, tolerances.contact_time),
        ("restitution", restitution, tolerances.restitution),
        ("mass_kg", mass_kg, tolerances.mass),
        ("height_m", height_m, tolerances.drop_height),
    ):
        if value is not None:
            items.append(_item(tol, _scalar(name, value)))
    return Conformance(tuple(items), tolerances.clause)

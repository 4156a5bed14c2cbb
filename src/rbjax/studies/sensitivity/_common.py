"""Small helpers shared by the sensitivity modules: output names, uniform ranges as a SALib
problem, inputs and outputs as dicts, the dropping of failed evaluations, and the fields every
result shares."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from ...solve.options import EvaluationSpec, model_from_shortcuts, spec_or_default
from ...terms.model import Model


def study_settings(
    function: str, model: Model | None, evaluation: EvaluationSpec | None
) -> tuple[Model, EvaluationSpec]:
    """The ``Model`` (default ``Model()``) and ``EvaluationSpec`` (default ``EvaluationSpec()``)
    of a study, each checked to be one."""
    return model_from_shortcuts(function, model, {}), spec_or_default(evaluation)


def is_lfe(name: str) -> bool:
    """Whether an output name is an octave-band force exposure level ``lfe_<band>_dB``."""
    return name.startswith("lfe_")


def check_ranges(
    ranges: Mapping, canonical: Callable = lambda n: n
) -> dict[str, tuple[float, float]]:
    """``ranges`` (parameter → (low, high)) checked: finite, low < high; names made canonical."""
    if not isinstance(ranges, Mapping) or not ranges:
        raise ValueError(
            f"ranges={ranges!r} must be a non-empty mapping of parameter name to (low, high)"
        )
    out = {}
    for name, bounds in ranges.items():
        try:
            low, high = (float(b) for b in bounds)
        except (TypeError, ValueError):
            raise ValueError(
                f"ranges[{name!r}]={bounds!r} must be a pair (low, high) of numbers"
            ) from None
        if not (math.isfinite(low) and math.isfinite(high) and low < high):
            raise ValueError(f"ranges[{name!r}]=({low!r}, {high!r}) must be finite with low < high")
        out[canonical(name)] = (low, high)
    return out


def salib_problem(ranges: Mapping) -> dict:
    """The SALib problem of independent uniform inputs over ``ranges`` (checked)."""
    return {
        "num_vars": len(ranges),
        "names": list(ranges),
        "bounds": [list(b) for b in ranges.values()],
    }


def check_count(name: str, value, lowest: int, power_of_two: bool = False, why: str = "") -> int:
    """``value`` as an int ≥ ``lowest`` (and a power of two if asked), else a named error."""
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool) and value >= lowest
    if ok and power_of_two and value & (value - 1):
        below = 1 << (int(value).bit_length() - 1)
        raise ValueError(
            f"{name}={value!r} must be a power of two{why}: e.g. {below} or {2 * below}"
        )
    if not ok:
        raise ValueError(f"{name}={value!r} must be an integer ≥ {lowest}{why}")
    return int(value)


def inputs_dict(x: np.ndarray, names) -> dict[str, np.ndarray]:
    """The columns of a SALib design (rows: evaluations) by parameter name."""
    return {name: np.ascontiguousarray(x[:, j]) for j, name in enumerate(names)}


def outputs_dict(y, n_rows: int) -> dict[str, np.ndarray]:
    """``func``'s result as output name → (n_rows,) float array (a bare array is ``"y"``)."""
    out = (
        {k: np.asarray(v, dtype=float) for k, v in y.items()}
        if isinstance(y, Mapping)
        else {"y": np.asarray(y, dtype=float)}
    )
    for name, v in out.items():
        if v.shape != (n_rows,):
            raise ValueError(f"func returned {name!r} with shape {v.shape}; expected ({n_rows},)")
    return out


def finite_groups(y: np.ndarray, group_size: int) -> np.ndarray:
    """Which consecutive groups of ``group_size`` rows (a base point and its companions in a
    SALib design) have every output finite: the groups an estimator may use."""
    return np.all(np.isfinite(y.reshape(-1, group_size)), axis=1)


def salib_seed(seed: int) -> int:
    """A seed for SALib's analysers (they treat 0 as 'no seed' and draw from the global state)."""
    return int(seed) + 1


def interval(value, half_width) -> np.ndarray:
    """(..., 2) intervals value ± half_width (SALib's normal-approximation intervals)."""
    value, half_width = np.asarray(value, dtype=float), np.asarray(half_width, dtype=float)
    return np.stack([value - half_width, value + half_width], axis=-1)


def shared_fields(
    ranges: Mapping, outputs: Mapping, n_evaluations: int, res: Mapping
) -> dict[str, Any]:
    """The fields every result of :mod:`~rbjax.studies.sensitivity.results` has, from the
    checked ``ranges``, the outputs (by name) and the per-output ``n_valid`` and ``salib``."""
    return {
        "parameters": tuple(ranges),
        "outputs": tuple(outputs),
        "ranges": ranges,
        "n_evaluations": n_evaluations,
        "n_valid": res["n_valid"],
        "salib": res["salib"],
    }

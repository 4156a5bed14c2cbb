"""rbjax design: the margins against the printed table's check, and bad input. (The design
itself, its agreement with `rbjax simulate` + the check and the 32-start bar, is measured in
``benchmarks/fitting.py --only design_check``: one design compiles for ~40 s.)"""

import numpy as np
import pytest

from rbjax.spectrum.standards import RUBBER_BALL_TOLERANCES, check_conformance
from rbjax.studies.design import (
    GEOMETRIES,
    ITEMS,
    DesignSearch,
    _density,
    design,
    normalised_margins,
)

from cli_runner import run_cli

# A smoke test (tests/conftest.py: compiled with most optimisations off): margins and bad input;
# the design itself: benchmarks/fitting.py --only design_check.
pytestmark = pytest.mark.xla_smoke


def test_normalised_margins_are_the_checks_margins_over_the_half_widths():
    rng = np.random.default_rng(0)
    nominal = np.array([39.0, 31.0, 23.0, 17.0, 12.5, 0.020, 0.8, 2.5])
    half = np.array([1.0, 1.5, 1.5, 2.0, 2.0, 0.002, 0.1, 0.1])
    for _ in range(20):
        v = nominal + half * rng.uniform(-2, 2, 8)
        m = np.asarray(normalised_margins(v))
        check = check_conformance(v[:5], contact_time_s=v[5], restitution=v[6], mass_kg=v[7])
        expect = np.array([it.margin for it in check.items]) / half
        np.testing.assert_allclose(m, expect, rtol=0, atol=1e-12)
        assert (m.min() >= 0) == check.passed


def test_items_and_geometries():
    assert len(ITEMS) == 8 and ITEMS[0] == "lfe_31.5_dB"
    iso = GEOMETRIES["iso"]
    assert 2 * iso.radius_m == pytest.approx(0.180) and iso.wall_m == pytest.approx(0.030)
    # the JIS ball's rubber: M over the shell volume, 1148 kg/m³ (docs/guides/physics.md)
    assert _density(GEOMETRIES["jis"]) == pytest.approx(1148, abs=1)
    assert RUBBER_BALL_TOLERANCES.mass.nominal == 2.5


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"geometry": "din"}, "geometry='din'"),
        ({"search": {"n_starts": 0}}, "n_starts=0"),
        ({"model": "maxwell"}, "model='maxwell'"),
    ],
)
def test_bad_design_input_is_named(kwargs, needle):
    with pytest.raises(ValueError, match=needle):
        search = DesignSearch(**kwargs.pop("search", {}))
        design(search=search, **kwargs)


def test_every_model_name_of_the_fit_has_a_search_range():
    # issue 43, item 3: design takes every model the fit takes (each parameter gets a finite
    # interval: DESIGN_RANGES, else its term's declared range)
    from rbjax.fit.layout import all_model_names, fitted_parameter_names, model_from_name
    from rbjax.studies.design import _specs

    ball = GEOMETRIES["jis"]
    for name in all_model_names():
        base = model_from_name(name)
        names = tuple(n for n in fitted_parameter_names(base) if n != "poisson") + ("wall_m",)
        for n, spec in zip(names, _specs(names, ball, base), strict=True):
            assert np.isfinite(spec.lower) and np.isfinite(spec.upper) and spec.lower < spec.upper


def test_cli_help_of_the_new_commands():
    code, out, _ = run_cli(["design", "--help"])
    assert code == 0 and "--geometry" in out and "optax" in out
    code, out, _ = run_cli(["fit", "--help"])
    assert code == 0 and "--summary" in out

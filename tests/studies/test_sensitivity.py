"""Local sensitivities against finite differences of the scipy reference; conformance
probability against an analytic case; the CLI. (Global methods: test_global_sensitivity.py.)"""

from __future__ import annotations

import json
import math
import types

import numpy as np
import pytest
from scipy.optimize import brentq

import rbjax
from rbjax.cli import main
from rbjax.spectrum.levels import lfe_octave_dB
from rbjax.spectrum.standards import RUBBER_BALL_TOLERANCES, check_conformance
from rbjax.studies.sensitivity import (
    conformance_flags,
    conformance_probability,
    local_sensitivity,
)

import scipy_reference as ref

BALL = rbjax.JIS_RUBBER_BALL
FIELDS = ("radius_m", "wall_m", "mass_kg", "youngs_Pa", "poisson")
HEIGHTS = [0.5, 1.0, 10.0]  # 10 m exceeds δ_max = 2h: status deflection_limit, NaN outputs
RATE = 44_100.0


def reference_outputs(height_m, damping=None, lfe=True, **changes):
    """Contact time, peak force, restitution (and L_FE bands) from the scipy reference."""
    fields = {k: float(getattr(BALL, k)) for k in FIELDS} | changes
    r = ref.reference_impact(height_m, types.SimpleNamespace(**fields), damping=damping)
    out = [r.contact_time_s, r.peak_force_N, r.restitution]
    if lfe:  # the 44.1 kHz × 1 s record, zero after contact (§2.4)
        n = int(math.ceil(r.contact_time_s * RATE)) + 2
        force = np.zeros(int(RATE))
        force[:n] = r.force_N(np.arange(n) / RATE)
        out += list(np.asarray(lfe_octave_dB(force, RATE)))
    return np.array(out)


def central_difference(height_m, name, step=1e-6, **kw):
    """∂outputs/∂name by a central difference of relative step ``step`` on the reference."""
    if name == "height_m":
        dx = step * height_m
        return (reference_outputs(height_m + dx, **kw) - reference_outputs(height_m - dx, **kw)) / (
            2 * dx
        )
    x = float(getattr(BALL, name))
    dx = step * x
    up, down = (
        reference_outputs(height_m, **kw, **{name: x + dx}),
        reference_outputs(height_m, **kw, **{name: x - dx}),
    )
    return (up - down) / (2 * dx)


@pytest.fixture(scope="module")
def local():
    return local_sensitivity(HEIGHTS, wrt=("height_m",) + FIELDS)


def test_local_jacobian_matches_central_differences_of_scipy_reference(local):
    assert local.parameters == ("height_m",) + FIELDS
    assert len(local.outputs) == 3 + 6
    for i, h in enumerate(HEIGHTS[:2]):
        assert local.status[i] == 0
        for p in local.parameters:
            fd = central_difference(h, p)
            ad = np.array([local.jacobian[o][p][i] for o in local.outputs])
            np.testing.assert_allclose(ad, fd, rtol=1e-4, err_msg=f"height {h} m, d/d{p}")


def test_local_values_match_reference(local):
    for i, h in enumerate(HEIGHTS[:2]):
        got = np.array([local.values[o][i] for o in local.outputs])
        np.testing.assert_allclose(got, reference_outputs(h), rtol=1e-6)


def test_elasticities_obey_the_shell_stiffness_scaling(local):
    # The elastic model sees h and ν only through k = 4Eh²/(R√(3(1−ν²))) (Eqs. 1–3), so
    # ε_h = 2 ε_E and ε_ν = ν²/(1−ν²) ε_E for every output, L_FE included.
    el = local.elasticity
    nu = float(BALL.poisson)
    for o in local.outputs:
        e_young = el[o]["youngs_Pa"][:2]
        np.testing.assert_allclose(el[o]["wall_m"][:2], 2.0 * e_young, rtol=1e-6, err_msg=o)
        np.testing.assert_allclose(
            el[o]["poisson"][:2], nu**2 / (1 - nu**2) * e_young, rtol=1e-6, err_msg=o
        )
    # elasticity of a scalar output: ∂ln y/∂ln x, checked on the reference by a log-difference
    x, step = float(BALL.youngs_Pa), 1e-6
    up = reference_outputs(1.0, lfe=False, youngs_Pa=x * (1 + step))
    down = reference_outputs(1.0, lfe=False, youngs_Pa=x * (1 - step))
    fd = (np.log(up) - np.log(down)) / (np.log1p(step) - np.log1p(-step))
    got = [el[o]["youngs_Pa"][1] for o in ("contact_time_s", "peak_force_N", "restitution")]
    np.testing.assert_allclose(got, fd, rtol=1e-4)


def test_flagged_height_gives_nan_not_numbers(local):
    assert local.status_name[2] == "deflection_limit"
    for o in local.outputs:
        assert np.isnan(local.values[o][2])
        assert all(np.isnan(local.jacobian[o][p][2]) for p in local.parameters)
    rows = local.to_dict()
    assert [r["status"] for r in rows] == ["ok", "ok", "deflection_limit"]


def test_tornado_chart_is_written(local, tmp_path):
    fig = local.plot(1, outputs=["contact_time_s", "lfe_63_dB"])
    path = tmp_path / "tornado.png"
    fig.savefig(path)
    assert path.stat().st_size > 1000
    bars = fig.axes[0].patches
    widths = sorted(abs(b.get_width()) for b in bars)
    expected = sorted(abs(local.elasticity["contact_time_s"][p][1]) for p in local.parameters)
    np.testing.assert_allclose(widths, expected)


def test_damping_parameter_sensitivity_matches_reference():
    damping = rbjax.KelvinVoigt(damping_Ns_per_m=20.0)
    model = rbjax.Model(damping=damping)
    s = local_sensitivity(1.0, model=model, wrt=("DAMPING_NS_PER_M", "youngs_pa"), lfe=False)
    assert s.parameters == ("youngs_Pa", "damping_Ns_per_m")
    assert s.status[0] == 0
    c, dc = 20.0, 20.0 * 1e-6
    up = reference_outputs(1.0, damping=("kv", c + dc), lfe=False)
    down = reference_outputs(1.0, damping=("kv", c - dc), lfe=False)
    fd = (up - down) / (2 * dc)
    np.testing.assert_allclose(
        [s.jacobian[o]["damping_Ns_per_m"][0] for o in s.outputs], fd, rtol=1e-4
    )
    fd_e = central_difference(1.0, "youngs_Pa", damping=("kv", c), lfe=False)
    np.testing.assert_allclose([s.jacobian[o]["youngs_Pa"][0] for o in s.outputs], fd_e, rtol=1e-4)


def test_unknown_parameter_is_rejected():
    with pytest.raises(ValueError, match="stiffness_Pa.*valid"):
        local_sensitivity(1.0, wrt=("stiffness_Pa",))
    with pytest.raises(
        ValueError, match="damping_Ns_per_m"
    ):  # a damping field without a damping model
        local_sensitivity(1.0, wrt=("damping_Ns_per_m",))


# ----------------------------------------------------------------------------------------------
# Conformance probability.


def test_conformance_probability_of_a_uniform_drop_height_against_analytic_fraction():
    # Only the drop height varies, uniform on [0.6, 1.4] m. The 31.5 Hz level and the
    # restitution are monotone in h, so each conforms on an interval of heights whose ends
    # are roots found on the scipy reference: the exact probability is its length / 0.8 m.
    lo_h, hi_h = 0.6, 1.4
    tol = RUBBER_BALL_TOLERANCES

    def lfe31(h):
        return reference_outputs(h)[3]

    def restitution(h):
        return reference_outputs(h, lfe=False)[2]

    def fraction(f, lower, upper):
        a, b = lo_h, hi_h
        if f(a) < lower:
            a = brentq(lambda h: f(h) - lower, lo_h, hi_h, xtol=1e-6)
        if f(b) > upper:
            b = brentq(lambda h: f(h) - upper, lo_h, hi_h, xtol=1e-6)
        return (b - a) / (hi_h - lo_h)

    band = tol.lfe_octave_dB["31.5"]
    p_band = fraction(lfe31, band.lower, band.upper)
    p_rest = fraction(lambda h: -restitution(h), -tol.restitution.upper, -tol.restitution.lower)
    assert 0.1 < p_band < 0.9 and 0.1 < p_rest < 0.9  # a case that can fail either way

    res = conformance_probability(
        2000,
        {"height_m": ("uniform", lo_h, hi_h)},
        seed=5,
        confidence=0.999,
        parallel=rbjax.Parallel(chunk_size=64),
    )
    assert res.n_valid == 2000
    for key, p in (("lfe_31.5_dB", p_band), ("restitution", p_rest)):
        low, high = res.interval[key]
        assert low <= p <= high, (key, p, res.probability[key], res.interval[key])
    # height outside 1.00 ± 0.01 m is a failure of the drop-height item
    assert abs(res.probability["height_m"] - 0.02 / 0.8) < 0.02
    # the vectorised check follows rbjax.spectrum.standards.check_conformance sample by sample
    s = res.samples
    for i in range(0, 2000, 97):
        bands = [s[f"lfe_{b}_dB"][i] for b in ("31.5", "63", "125", "250", "500", "1000")]
        expected = check_conformance(
            bands,
            contact_time_s=s["contact_time_s"][i],
            restitution=s["restitution"][i],
            mass_kg=2.5,
            height_m=s["input_height_m"][i],
        )
        assert bool(s["pass_overall"][i]) == expected.passed
        assert bool(s["pass_lfe_31.5_dB"][i]) == expected["L_FE 31.5 Hz"].passed


def test_conformance_flags_on_the_limits():
    tol = RUBBER_BALL_TOLERANCES
    values = {
        f"lfe_{b}_dB": np.array([t.lower, t.upper, t.upper + 1e-9])
        for b, t in tol.lfe_octave_dB.items()
    }
    values |= {
        "contact_time_s": np.full(3, 0.02),
        "restitution": np.full(3, 0.8),
        "mass_kg": np.full(3, 2.5),
        "height_m": np.full(3, 1.0),
    }
    flags = conformance_flags(values)
    assert flags["lfe"].tolist() == [True, True, False]
    assert flags["overall"].tolist() == [True, True, False]


def test_bad_distribution_is_rejected():
    with pytest.raises(ValueError, match="sd > 0"):
        conformance_probability(10, {"mass_kg": ("normal", 2.5, -0.1)})
    with pytest.raises(ValueError, match="kind"):
        conformance_probability(10, {"mass_kg": {"kind": "beta", "a": 1, "b": 2}})
    with pytest.raises(ValueError, match="not known"):
        conformance_probability(10, {"colour": ("uniform", 0, 1)})


# ----------------------------------------------------------------------------------------------
# CLI.


def test_cli_sensitivity_json(local, capsys):
    # lower-case names, all of them: the same parameter set as the fixture (no recompile)
    argv = [
        "sensitivity",
        "--height-m",
        *map(str, HEIGHTS),
        "--wrt",
        "HEIGHT_M",
        "radius_m",
        "wall_m",
        "mass_kg",
        "youngs_pa",
        "poisson",
        "--json",
    ]
    assert main(argv) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["height_m"] for r in rows] == HEIGHTS
    row = rows[1]
    assert set(row) >= {"height_m", "status", "jacobian", "elasticity", "values"}
    assert set(row["jacobian"]) == set(local.outputs)
    assert set(row["jacobian"]["lfe_63_dB"]) == set(local.parameters)
    assert row["jacobian"]["contact_time_s"]["youngs_Pa"] == pytest.approx(
        local.jacobian["contact_time_s"]["youngs_Pa"][1], rel=1e-12
    )
    assert rows[2]["jacobian"]["peak_force_N"]["mass_kg"] is None  # NaN → null for a flagged height


def test_cli_sensitivity_unknown_wrt(capsys):
    assert main(["sensitivity", "--height-m", "1.0", "--wrt", "youngs_pa", "stiffness"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rbjax: error:") and "'stiffness'" in err and "youngs_Pa" in err
    assert "\n" not in err

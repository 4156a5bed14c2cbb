"""rbjax.spectrum.standards: the printed rubber-ball table and the conformance check.

Expected values are the ones printed in ISO 16283-2:2020 Table A.1 = ISO 10140-5:2010
Table F.1 = JIS A 1418-2:2019 Table A.2, typed in here from the standards.
"""

from __future__ import annotations

import json

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from rbjax.spectrum import standards as ST  # noqa: E402
from rbjax.spectrum.bands import OCTAVE_BANDS  # noqa: E402

# label: (nominal dB, ± dB), as printed
PRINTED_BANDS = {
    "31.5": (39.0, 1.0),
    "63": (31.0, 1.5),
    "125": (23.0, 1.5),
    "250": (17.0, 2.0),
    "500": (12.5, 2.0),
}
NOMINAL = [39.0, 31.0, 23.0, 17.0, 12.5]
LOWER = [38.0, 29.5, 21.5, 15.0, 10.5]
UPPER = [40.0, 32.5, 24.5, 19.0, 14.5]


def test_printed_band_table():
    bands = ST.RUBBER_BALL_TOLERANCES.lfe_octave_dB
    assert list(bands) == ["31.5", "63", "125", "250", "500"]
    for label, (nominal, tol) in PRINTED_BANDS.items():
        t = bands[label]
        assert (t.nominal, t.minus, t.plus) == (nominal, tol, tol)
        assert t.unit == "dB re 1 N"
        assert (t.lower, t.upper) == (nominal - tol, nominal + tol)
    assert "1000" not in bands  # no tolerance at 1 kHz
    assert tuple(bands) == OCTAVE_BANDS[:5]


def test_printed_mechanical_properties():
    tol = ST.RUBBER_BALL_TOLERANCES
    assert (tol.drop_height.nominal, tol.drop_height.minus, tol.drop_height.plus) == (
        1.00,
        0.01,
        0.01,
    )
    assert tol.drop_height.unit == "m"
    assert (tol.contact_time.nominal, tol.contact_time.minus, tol.contact_time.plus) == (
        0.020,
        0.002,
        0.002,
    )
    assert tol.contact_time.unit == "s"
    assert (tol.mass.nominal, tol.mass.minus, tol.mass.plus) == (2.5, 0.1, 0.1)
    assert tol.mass.unit == "kg"
    assert (tol.restitution.nominal, tol.restitution.minus, tol.restitution.plus) == (0.8, 0.1, 0.1)
    # the limits as printed, without float round-off (0.8 - 0.1 is 0.7)
    assert (tol.restitution.lower, tol.restitution.upper) == (0.7, 0.9)
    assert (tol.contact_time.lower, tol.contact_time.upper) == (0.018, 0.022)
    assert (tol.drop_height.lower, tol.drop_height.upper) == (0.99, 1.01)
    assert (tol.mass.lower, tol.mass.upper) == (2.4, 2.6)


def test_clauses_cite_all_three_standards():
    tol = ST.RUBBER_BALL_TOLERANCES
    for item in (*tol.octave_bands, tol.drop_height, tol.contact_time, tol.mass, tol.restitution):
        for ref in (
            "ISO 16283-2:2020",
            "Table A.1",
            "ISO 10140-5:2010",
            "Table F.1",
            "JIS A 1418-2:2019",
            "Table A.2",
        ):
            assert ref in item.clause


def test_table_is_immutable():
    tol = ST.RUBBER_BALL_TOLERANCES
    with pytest.raises(AttributeError):
        tol.mass = None
    with pytest.raises(AttributeError):
        tol.mass.nominal = 3.0
    with pytest.raises(TypeError):
        tol.lfe_octave_dB["63"] = None


def test_nominal_values_pass_with_full_margin():
    res = ST.check_conformance(
        NOMINAL, contact_time_s=0.020, restitution=0.8, mass_kg=2.5, height_m=1.0
    )
    assert res.passed and bool(res)
    assert [it.name for it in res.items] == [
        "L_FE 31.5 Hz", "L_FE 63 Hz", "L_FE 125 Hz", "L_FE 250 Hz", "L_FE 500 Hz",
        "contact time", "coefficient of restitution", "mass", "drop height",
    ]  # fmt: skip
    margins = [it.margin for it in res.items]
    np.testing.assert_allclose(margins, [1.0, 1.5, 1.5, 2.0, 2.0, 0.002, 0.1, 0.1, 0.01], rtol=1e-9)
    np.testing.assert_allclose([it.lower for it in res.items[:5]], LOWER)
    np.testing.assert_allclose([it.upper for it in res.items[:5]], UPPER)


@pytest.mark.parametrize("limits", [LOWER, UPPER])
def test_values_on_the_limits_pass_with_zero_margin(limits):
    res = ST.check_conformance(limits + [-99.0])  # 1000 Hz is not toleranced
    assert res.passed
    assert len(res.items) == 5
    assert all(it.margin == 0.0 for it in res.items)
    for name, lo, hi in (("contact_time_s", 0.018, 0.022), ("restitution", 0.7, 0.9),
                         ("mass_kg", 2.4, 2.6), ("height_m", 0.99, 1.01)):  # fmt: skip
        for value in (lo, hi):
            item = ST.check_conformance(**{name: value}).items[0]
            assert item.passed and item.margin == 0.0, (name, value, item)


def test_out_of_range_fails_with_negative_margin():
    values = [37.5, 33.0, 23.0, 14.0, 12.5]  # 0.5 below, 0.5 above, inside, 1.0 below, inside
    res = ST.check_conformance(
        values, contact_time_s=0.0235, restitution=0.65, mass_kg=2.45, height_m=1.02
    )
    assert not res.passed and not bool(res)
    by_name = {it.name: it for it in res.items}
    assert by_name["L_FE 31.5 Hz"].margin == pytest.approx(-0.5)
    assert by_name["L_FE 63 Hz"].margin == pytest.approx(-0.5)
    assert by_name["L_FE 125 Hz"].margin == pytest.approx(1.5) and by_name["L_FE 125 Hz"].passed
    assert by_name["L_FE 250 Hz"].margin == pytest.approx(-1.0)
    assert by_name["contact time"].margin == pytest.approx(-0.0015)
    assert by_name["coefficient of restitution"].margin == pytest.approx(-0.05)
    assert by_name["mass"].margin == pytest.approx(0.05) and by_name["mass"].passed
    assert by_name["drop height"].margin == pytest.approx(-0.01)
    assert {it.name for it in res.failed} == {
        "L_FE 31.5 Hz", "L_FE 63 Hz", "L_FE 250 Hz", "contact time",
        "coefficient of restitution", "drop height",
    }  # fmt: skip
    assert res["L_FE 63 Hz"].value == 33.0
    # margin is the distance to the *nearer* limit, positive inside
    inside = ST.check_conformance([38.2, 31, 23, 17, 12.5])["L_FE 31.5 Hz"]
    assert inside.margin == pytest.approx(0.2)


def test_accepts_mappings_arrays_and_numpy_jax_scalars():
    as_map = ST.check_conformance({"63": jnp.float64(31.2), "500": np.float32(10.5), "1000": 1.0})
    assert [it.name for it in as_map.items] == ["L_FE 63 Hz", "L_FE 500 Hz"]
    assert as_map.passed and as_map["L_FE 500 Hz"].margin == 0.0  # float32 10.5 is exact
    as_jax = ST.check_conformance(jnp.asarray(NOMINAL + [0.0]), contact_time_s=jnp.asarray(0.019),
                                  restitution=np.float32(0.7), mass_kg=np.int64(2))  # fmt: skip
    assert as_jax["coefficient of restitution"].passed  # np.float32(0.7) is taken as 0.7
    assert not as_jax["mass"].passed
    assert isinstance(as_jax["contact time"].value, float)
    assert ST.check_conformance().passed and ST.check_conformance().items == ()


def test_table_text_and_json():
    res = ST.check_conformance([37.0, 31, 23, 17, 12.5], mass_kg=2.5)
    text = res.table()
    assert "L_FE 31.5 Hz" in text and "FAIL" in text and "mass" in text and "pass" in text
    assert text.strip().splitlines()[-1].startswith("overall: FAIL")
    d = json.loads(json.dumps(res.to_dict()))
    assert d["passed"] is False
    assert d["items"][0] == {
        "name": "L_FE 31.5 Hz", "value": 37.0, "lower": 38.0, "upper": 40.0, "margin": -1.0,
        "passed": False, "unit": "dB re 1 N", "clause": ST.CLAUSE,
    }  # fmt: skip


@pytest.mark.parametrize(
    "kwargs,needle",
    [
        ({"lfe_octave_dB": [39.0, 31.0, 23.0]}, "lfe_octave_dB"),
        ({"lfe_octave_dB": np.zeros((2, 5))}, "lfe_octave_dB"),
        ({"lfe_octave_dB": [39.0, float("nan"), 23.0, 17.0, 12.5]}, "lfe_octave_dB[1]"),
        ({"lfe_octave_dB": {"63": float("nan")}}, "lfe_octave_dB['63']"),
        ({"lfe_octave_dB": {"2000": 10.0}}, "lfe_octave_dB"),
        ({"contact_time_s": float("nan")}, "contact_time_s"),
        ({"restitution": float("inf")}, "restitution"),
        ({"mass_kg": [2.5, 2.5]}, "mass_kg"),
        ({"height_m": "1 m"}, "height_m"),
    ],
)
def test_bad_input_raises_naming_the_parameter(kwargs, needle):
    with pytest.raises(ValueError) as info:
        ST.check_conformance(**kwargs)
    msg = str(info.value)
    assert needle in msg
    assert any(word in msg for word in ("finite", "shape", "valid"))


def test_wrong_length_message_gives_shape():
    with pytest.raises(ValueError, match=r"shape \(3,\).*\(5,\).*\(6,\)"):
        ST.check_conformance([1.0, 2.0, 3.0])

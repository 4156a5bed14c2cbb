"""The ball at several drop positions (``rbjax.room.positions``): the energy average and its
rating against the arithmetic written out here (numpy, with ISO 717-2:2020 Table D.3's
A-weighted reference values as printed), each position's levels against the independent
numpy/scipy chain (``scipy_room_reference``), bad input and the command line.

Compile budget: one program for the slab with a given drive point (the positions share it:
the drive point is a value, not a shape).
"""

import json

import numpy as np
import pytest
import scipy_room_reference as reference

from rbjax.room import ReceivingRoom, Slab, impact_sound, position_average, round_rating
from rbjax.terms import JIS_RUBBER_BALL
from tests.cli_runner import run_cli

SLAB = Slab.of_material("concrete", 0.15)  # 4 m × 5 m, clamped, the preset concrete-150mm
ROOM = ReceivingRoom(50.0, 0.5)
#: the five points of the thickness table (benchmarks/RESULTS.md, "Room"), m from a corner
POINTS = [(2.0, 2.5), (1.2, 2.0), (2.8, 1.75), (1.6, 3.5), (2.6, 3.25)]
#: ISO 717-2:2020 Table D.3, A-weighted reference values of the octaves 63-500 Hz, as printed
TABLE_D3 = np.array([-26.2, -16.2, -8.7, -3.2])


@pytest.fixture(scope="module")
def average():
    return position_average(SLAB, ROOM, POINTS)


@pytest.fixture(scope="module")
def independent():
    """Each position's band levels by the independent numpy/scipy chain (its own force, modes
    and room), dB."""
    force = reference.Force(JIS_RUBBER_BALL, 1.0, 0.15)
    return np.array([reference.levels(force, 0.15, drive=p) for p in POINTS])


def test_the_average_is_the_energy_mean_of_the_positions_and_its_rating_formula_d1(
    average, independent
):
    singles = [
        impact_sound(Slab.of_material("concrete", 0.15, drive_x_m=x, drive_y_m=y), ROOM)
        for x, y in POINTS
    ]
    levels = np.array([s.level_dB for s in singles])
    expected = 10 * np.log10(np.mean(10 ** (levels / 10), axis=0))
    np.testing.assert_allclose(average.level_dB, expected, rtol=1e-12)
    normalised = np.array([s.normalised_dB for s in singles])
    np.testing.assert_allclose(
        average.normalised_dB, 10 * np.log10(np.mean(10 ** (normalised / 10), axis=0)), rtol=1e-12
    )
    rating = 10 * np.log10(np.sum(10 ** ((expected[1:5] + TABLE_D3) / 10)))
    assert average.LiA_Fmax_unrounded_dB == pytest.approx(rating, abs=1e-9)
    assert average.LiA_Fmax_dB == round_rating(rating)
    assert [r.LiA_Fmax_unrounded_dB for r in average.results] == [
        s.LiA_Fmax_unrounded_dB for s in singles
    ]
    # the centre hears the first mode at its antinode: it rates above the others
    assert average.results[0].LiA_Fmax_unrounded_dB > max(
        r.LiA_Fmax_unrounded_dB for r in average.results[1:]
    )
    assert average.positions_m == tuple(POINTS)
    # each position's levels against the independent chain (measured ≤ 1.5e-4 dB apart), and
    # their energy mean's rating
    np.testing.assert_allclose(levels, independent, atol=1e-3)
    mean = 10 * np.log10(np.mean(10 ** (independent / 10), axis=0))
    assert average.LiA_Fmax_unrounded_dB == pytest.approx(reference.rating(mean), abs=1e-3)
    # docs/guides/room.md, "Several drop positions" (clamped, 150 mm): 59.8 dB at the centre,
    # 57.4 dB over the five points, to their printed 0.1 dB
    assert reference.rating(independent[0]) == pytest.approx(59.8, abs=0.05)
    assert reference.rating(mean) == pytest.approx(57.4, abs=0.05)
    assert average.to_dict()["LiA_Fmax_dB"] == average.LiA_Fmax_dB


def test_one_position_is_that_position(average):
    one = position_average(SLAB, ROOM, [POINTS[1]])
    assert one.level_dB == pytest.approx(average.results[1].level_dB, rel=1e-12)
    assert one.LiA_Fmax_unrounded_dB == pytest.approx(
        average.results[1].LiA_Fmax_unrounded_dB, abs=1e-9
    )


@pytest.mark.parametrize(
    ("positions", "match"),
    [
        ([], r"positions_m=\[\] holds no position"),
        ([(2.0, 2.5), (1.0,)], r"positions_m\[1\]=\(1.0,\) is not a pair"),
        ([(2.0, 2.5), (4.5, 1.0)], r"positions_m\[1\]=\(4.5, 1\): drive_x_m=4.5 is outside"),
    ],
)
def test_bad_positions(positions, match):
    with pytest.raises(ValueError, match=match):
        position_average(SLAB, ROOM, positions)


def test_cli_drive_points(average, independent, tmp_path):
    room = ["--room-volume-m3", "50", "--reverberation-s", "0.5"]
    points = [arg for x, y in POINTS for arg in ("--drive-point", f"{x},{y}")]
    plot = tmp_path / "positions.png"
    code, out, _ = run_cli(["room", "--floor", "concrete-150mm", *room, *points, "--json"])
    assert code == 0
    data = json.loads(out)
    assert data["LiA_Fmax_unrounded_dB"] == pytest.approx(average.LiA_Fmax_unrounded_dB, abs=1e-9)
    assert data["positions_m"] == [list(p) for p in POINTS] and len(data["positions"]) == 5
    # its figures against the independent chain: each position's bands and their energy mean
    # (measured ≤ 1.5e-4 dB apart), the mean's rating and its rounding; V = 50 m³ and
    # T = 0.5 s are the reference room, so normalised = measured
    assert data["bands_Hz"] == ["31.5", "63", "125", "250", "500", "1000"]
    got = np.array([p["Li_Fmax_dB"] for p in data["positions"]])
    np.testing.assert_allclose(got, independent, atol=1e-3)
    mean = 10 * np.log10(np.mean(10 ** (independent / 10), axis=0))
    np.testing.assert_allclose(data["Li_Fmax_dB"], mean, atol=1e-3)
    np.testing.assert_allclose(data["Li_Fmax_normalised_dB"], data["Li_Fmax_dB"], atol=1e-12)
    assert data["LiA_Fmax_unrounded_dB"] == pytest.approx(reference.rating(mean), abs=1e-3)
    assert data["LiA_Fmax_dB"] == data["LiA_Fmax_normalised_dB"] == 57  # 57.4 dB, rounded
    code, out, _ = run_cli(
        ["room", "--floor", "concrete-150mm", *room, *points, "--plot", str(plot)]
    )
    assert code == 0 and f"unrounded {average.LiA_Fmax_unrounded_dB:.2f} dB" in out
    assert plot.stat().st_size > 1000
    code, _, err = run_cli(["room", "--floor", "concrete-150mm", *room, "--drive-point", "2"])
    assert code == 2 and "'2' is not two comma-separated numbers" in err
    code, _, err = run_cli(
        ["room", "--floor", "concrete-150mm", *room, *points, "--drive-x-m", "1.0"]
    )
    assert code == 2 and "not both" in err

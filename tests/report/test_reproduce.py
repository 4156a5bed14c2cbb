"""``rbjax reproduce``: files, report, and the physics against the paper and an independent solver.

One run of ``rbjax reproduce --json`` (module fixture, in-process) feeds every test. Numbers
are checked against the paper's reported values (Schoenwald, Zeitler & Nightingale 2011,
§4.1-4.2) within 10 %, and against the scipy solution of Eq. 7 (tests/scipy_reference.py).
"""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest

import rbjax
from rbjax.cli import main
from rbjax.report.paper import DEFAULT_HEIGHTS_M, printed_eq4_limit_m
from rbjax.report.reproduce import reproduce

from scipy_reference import reference_impact

FIGURES = [
    "fig03_force_components_1m.png",
    "fig04_force_histories.png",
    "fig05_peak_force.png",
    "fig06_contact_time.png",
    "fig07_relative_difference.png",
    "fig08_lfe_1m.png",
    "fig09_lfe_normalised.png",
    "fig10_lfe_increase.png",
    "fig11_increase_per_doubling.png",
    "fig12_contact_resonance.png",
    "measured_ball.png",
]
GASES = ("adiabatic", "none")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out_dir = tmp_path_factory.mktemp("reproduce")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["reproduce", "--out", str(out_dir), "--json"])
    return {"code": code, "dir": out_dir, "stdout": out.getvalue(), "stderr": err.getvalue()}


@pytest.fixture(scope="module")
def results(run):
    assert run["code"] == 0, run["stderr"]
    return json.loads((run["dir"] / "results.json").read_text())


def at(results, gas, name, h):
    i = results["heights_m"].index(h)
    return results["gas"][gas][name][i]


def test_writes_figures_report_and_results(run, results):
    assert run["code"] == 0
    for name in FIGURES:
        data = (run["dir"] / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000, name
    assert results["figures"] == FIGURES
    assert (run["dir"] / "report.md").stat().st_size > 0


def test_json_stdout_matches_results_file(run, results):
    printed = json.loads(run["stdout"])
    assert printed["out_dir"] == str(run["dir"])
    assert printed["comparison"] == results["comparison"]
    assert sorted(printed["files"]) == sorted(
        str(run["dir"] / f) for f in [*FIGURES, "report.md", "results.json"]
    )


def test_progress_goes_to_stderr(run):
    lines = run["stderr"].splitlines()
    assert len(lines) >= 4 and all(line.startswith("rbjax: reproduce:") for line in lines)
    assert "[1/4]" in lines[0]


def test_all_heights_solved(results):
    assert results["heights_m"] == list(DEFAULT_HEIGHTS_M)
    for gas in GASES:
        assert results["gas"][gas]["status"] == ["ok"] * len(DEFAULT_HEIGHTS_M)


def test_matches_the_independent_solver(results):
    """Contact time, peak force and restitution agree with scipy's DOP853 at rtol 1e-12."""
    for gas in GASES:
        for h in (0.1, 1.0, 1.6):
            ref = reference_impact(h, rbjax.JIS_RUBBER_BALL, gas=gas)
            assert at(results, gas, "contact_time_s", h) == pytest.approx(
                ref.contact_time_s, rel=1e-7
            )
            assert at(results, gas, "peak_force_N", h) == pytest.approx(ref.peak_force_N, rel=1e-7)
            assert at(results, gas, "restitution", h) == pytest.approx(ref.restitution, rel=1e-7)


# The paper reports (§4.1): contact time 20.8 ms at 1 m (prediction); peak force roughly 500 N at
# 10 cm and about 1800 N at 160 cm. Its numbers agree with rbjax's shell-only model (gas off)
# within a few %; with the corrected gas force (Eq. 4) the peak at 160 cm is 12 % higher, which
# report.md explains, so the 160 cm peak is checked for gas off only.
PAPER_CHECKS = [
    ("none", "peak_force_N", 0.1, 500.0),
    ("none", "peak_force_N", 1.6, 1800.0),
    ("none", "contact_time_s", 1.0, 20.8e-3),
    ("adiabatic", "peak_force_N", 0.1, 500.0),
    ("adiabatic", "contact_time_s", 1.0, 20.8e-3),
]


@pytest.mark.parametrize("gas, name, h, paper", PAPER_CHECKS)
def test_within_10_percent_of_the_paper(results, gas, name, h, paper):
    assert at(results, gas, name, h) == pytest.approx(paper, rel=0.10)


def test_lfe_increase_per_doubling_is_about_3_dB(results):
    """Paper §4.2/Fig. 11: about 3 dB per doubling of drop height in the bands other than 63 Hz,
    the value 10·log10(2) of a source whose force scales with v0 ∝ √h (Eq. 10)."""
    for gas in GASES:
        slopes = results["gas"][gas]["increase_per_doubling_dB"]
        for band, slope in slopes.items():
            if band != "63":
                assert slope == pytest.approx(10 * math.log10(2), abs=0.5), (gas, band)
        assert slopes["63"] > max(v for b, v in slopes.items() if b != "63")  # the 63 Hz excess


def test_contact_resonance_near_the_half_sine_notch(results):
    """The first spectral minimum of a half-sine pulse of length t_c is at 1.5/t_c; the shell-only
    pulse is close to a half-sine (within 3 %), and the paper's 66 Hz → 73 Hz is within 10 %."""
    gas = "none"
    for h, paper in ((0.1, 66.0), (1.6, 73.0)):
        f = at(results, gas, "contact_resonance_Hz", h)
        assert f == pytest.approx(1.5 / at(results, gas, "contact_time_s", h), rel=0.03)
        assert f == pytest.approx(paper, rel=0.10)


def test_grid_contact_time_is_the_next_sample(results):
    """The paper's sign-change contact time (§2.4) is the first 44.1 kHz sample after contact."""
    for gas in GASES:
        tc = np.array(results["gas"][gas]["contact_time_s"])
        grid = np.array(results["gas"][gas]["grid_contact_time_s"])
        np.testing.assert_allclose(grid, np.floor(tc * 44_100 + 1) / 44_100, rtol=0, atol=1e-12)


# The rows of report.md's comparison table: (quantity, the paper's value as the report prints
# it, what rbjax computes, drop height in m or octave band in Hz). The paper's values are typed
# in here from the paper (§4.1, §4.2 and Fig. 12), not read from rbjax.reproduce.
REPORT_ROWS = [
    ("predicted contact time at 100 cm", "20.8 ms", "contact_time", 1.0),
    ("peak force at 10 cm", "≈ 500 N", "peak_force", 0.1),
    ("peak force at 160 cm", "≈ 1800 N", "peak_force", 1.6),
    ("measured contact time at 10 cm", "21.3 ms", "contact_time", 0.1),
    ("measured contact time at 100 cm", "19.6 ms", "contact_time", 1.0),
    ("measured contact time at 160 cm", "19.3 ms", "contact_time", 1.6),
    *[
        (
            f"L_FE increase per doubling, {band} Hz",
            "≈ 5.0 dB" if band == "63" else "≈ 3.0 dB",
            "increase_per_doubling",
            band,
        )
        for band in ("31.5", "63", "125", "250", "500", "1000")
    ],
    ("contact resonance at 10 cm", "66 Hz", "contact_resonance", 0.1),
    ("contact resonance at 160 cm", "73 Hz", "contact_resonance", 1.6),
]
UNITS = {
    "contact_time": "ms",
    "peak_force": "N",
    "increase_per_doubling": "dB",
    "contact_resonance": "Hz",
}
#: Half a unit in the last printed digit (ms and dB to 0.01, N to 1, Hz to 0.1).
PRINTED = {
    "contact_time": 0.005,
    "peak_force": 0.5,
    "increase_per_doubling": 0.005,
    "contact_resonance": 0.05,
}
GAS_COLUMNS = {"adiabatic": "rbjax, gas on", "none": "rbjax, gas off"}


def markdown_table(text, heading):
    """The first table after ``heading``: a list of {column header: cell} per row."""
    lines = text.splitlines()
    start = lines.index(heading)
    table = []
    for line in lines[start + 1 :]:
        if line.startswith("|"):
            table.append([cell.strip() for cell in line.strip().strip("|").split("|")])
        elif table:
            break
    header, rule, *rows = table
    assert all(set(cell) <= set("-:") for cell in rule), rule
    assert all(len(row) == len(header) for row in rows), rows
    return [dict(zip(header, row)) for row in rows]


def number_in(cell, unit):
    """The number of a cell such as '20.43 ms', '≈ 500 N' or '+1.9 %'."""
    value, _, printed_unit = cell.removeprefix("≈ ").partition(" ")
    assert printed_unit == unit, (cell, unit)
    return float(value)


def _octave_lfe(force, rate):
    """L_FE in the octave bands 31.5 Hz–1 kHz written out: rfft of the 1 s record, one-sided
    energy spectral density, base-ten band edges 1000·10^(0.3(x ± 1/2)) Hz, x = −5 … 0."""
    esd = 2.0 * np.abs(np.fft.rfft(force) / rate) ** 2
    esd[0] /= 2.0
    esd[-1] /= 2.0  # even record length: the Nyquist bin
    f = np.fft.rfftfreq(force.size, 1.0 / rate)
    edges = [
        (1000.0 * 10 ** (0.3 * (x - 0.5)), 1000.0 * 10 ** (0.3 * (x + 0.5))) for x in range(-5, 1)
    ]
    return np.array(
        [10 * math.log10(np.sum(esd[(f >= lo) & (f < hi)]) * rate / force.size) for lo, hi in edges]
    )


def _first_notch_Hz(force, rate, fmin=20.0, fmax=200.0, step=0.01):
    """The first local minimum of |F(f)| above fmin: the zero-padded FFT (a 0.01 Hz grid of the
    record's DTFT), refined by a parabola through the grid minimum and its neighbours."""
    n_fft = int(round(rate / step))
    level = np.abs(np.fft.rfft(force, n_fft)) ** 2
    k = np.arange(int(fmin / step), int(fmax / step))
    first = k[(level[k] < level[k - 1]) & (level[k] <= level[k + 1])][0]
    a, b, c = level[first - 1 : first + 2]
    return (first + 0.5 * (a - c) / (a - 2 * b + c)) * step


@pytest.fixture(scope="module")
def independent():
    """The compared quantities from the scipy solution of Eq. 7 (tests/scipy_reference.py), with
    L_FE, its slope and the notch computed here with NumPy: {(kind, where, gas): value} in the
    report's units."""
    rate = 44_100.0
    t = np.arange(int(rate)) / rate  # the paper's 44.1 kHz x 1 s record (§2.4)
    out = {}
    for gas in GASES:
        levels = []
        for h in DEFAULT_HEIGHTS_M:
            ref = reference_impact(h, rbjax.JIS_RUBBER_BALL, gas=gas)
            force = ref.force_N(t)
            levels.append(_octave_lfe(force, rate))
            out["contact_time", h, gas] = ref.contact_time_s * 1e3
            out["peak_force", h, gas] = ref.peak_force_N
            out["contact_resonance", h, gas] = _first_notch_Hz(force, rate)
        # least-squares slope of L_FE against log2(h / 1 m) (§4.2, Fig. 11)
        slopes = np.polyfit(np.log2(np.array(DEFAULT_HEIGHTS_M)), np.array(levels), 1)[0]
        for band, slope in zip(("31.5", "63", "125", "250", "500", "1000"), slopes):
            out["increase_per_doubling", band, gas] = slope
    return out


def test_report_sets_paper_values_beside_computed_ones(run, independent):
    """Each paper value stands in its own row of the comparison table, beside rbjax's numbers
    (gas on and off), which agree with the independent solution to the printed digits, and
    beside the differences between the two."""
    report = (run["dir"] / "report.md").read_text()
    rows = markdown_table(report, "## rbjax beside the paper")
    for quantity, paper, kind, where in REPORT_ROWS:
        (row,) = [r for r in rows if r["quantity"] == quantity]  # exactly one row per quantity
        assert row["paper"] == paper, (quantity, row)
        unit = UNITS[kind]
        paper_value = number_in(paper, unit)
        for gas, column in GAS_COLUMNS.items():
            expected = independent[kind, where, gas]
            value = number_in(row[column], unit)
            assert value == pytest.approx(expected, abs=PRINTED[kind] + 1e-6), (quantity, gas, row)
            difference = row[column.replace("rbjax", "difference")]
            if unit == "dB":  # levels: the difference in dB
                assert number_in(difference, "dB") == pytest.approx(
                    expected - paper_value, abs=0.005 + 1e-6
                ), (quantity, gas, row)
            else:  # the relative difference in %
                assert number_in(difference, "%") == pytest.approx(
                    100 * (expected / paper_value - 1), abs=0.05 + 1e-6
                ), (quantity, gas, row)


def test_report_explains_the_differences_and_lists_tolerances_and_figures(run, results):
    report = (run["dir"] / "report.md").read_text()
    rows = {r["key"]: r for r in results["comparison"]}
    assert rows["peak_force_1.6m"]["relative_difference"]["none"] == pytest.approx(
        at(results, "none", "peak_force_N", 1.6) / 1800 - 1
    )
    assert "## Why they differ" in report
    for key in (
        "contact_time_1.0m",
        "peak_force_0.1m",
        "peak_force_1.6m",
        "measured_contact_time",
        "increase_per_doubling",
        "contact_resonance",
    ):
        assert results["explanations"][key] in report
    assert "21.5–24.5" in report  # the 125 Hz tolerance (ISO 10140-5 Table F.1)
    for name in FIGURES:
        assert f"]({name})" in report


#: docs/guides/summary-and-design.md, "The paper's measured ball": the table, each model's
#: E (MPa), contact times at 10 / 100 / 160 cm (ms), held-out rms (σ), predicted 160 cm peak ± sd
#: (N) and its excess over 1800 N (%).
MEASURED_BALL_TABLE = {
    "paper": (1.719, (21.17, 19.83, 19.27), 1.98, 2079, 8, 15.5),
    "paper+stiffening": (1.700, (21.26, 19.79, 19.17), 2.69, 2111, 37, 17.3),
    "kelvin-voigt": (1.714, (21.15, 19.82, 19.26), 2.12, 2064, 38, 14.6),
}


def test_measured_ball_table_is_the_readme_table(results):
    """docs/guides/summary-and-design.md, "The paper's measured ball" (the table;
    recommended: the elastic ``paper``; no model within 5 % of 1800 N): every figure at its printed
    digits (within one unit of the last printed digit, two for the ± of a peak), from the reproduce
    run's results.json."""
    measured = results["measured_ball"]
    assert measured["recommended"] == "paper" and measured["bar_met"] is False
    assert set(measured["models"]) == set(MEASURED_BALL_TABLE)
    for name, (e_MPa, tc_ms, rms, peak, sd, excess) in MEASURED_BALL_TABLE.items():
        row = measured["models"][name]
        assert row["youngs_Pa"] / 1e6 == pytest.approx(e_MPa, abs=0.001), name
        got_tc = [1e3 * row["contact_time_s"][h] for h in ("0.1", "1", "1.6")]
        np.testing.assert_allclose(got_tc, tc_ms, atol=0.01, err_msg=name)
        assert row["held_out_rms_sigma"] == pytest.approx(rms, abs=0.01), name
        assert row["predicted_peak_1.6m_N"] == pytest.approx(peak, abs=1.0), name
        assert row["predicted_sd_N"] == pytest.approx(sd, abs=2.0), name
        assert 100 * row["relative_error"] == pytest.approx(excess, abs=0.1), name


#: The paper's measured ball (§4.1-4.2, Fig. 5, Fig. 11) and issue 43's bars on it: contact time
#: (s) within 0.3 ms at 10 / 100 / 160 cm, peak (N) within 5 % at 10 / 160 cm.
PAPER_CONTACT_TIME_S = {"0.1": 21.3e-3, "1": 19.6e-3, "1.6": 19.3e-3}
PAPER_PEAK_N = {"0.1": 500.0, "1.6": 1800.0}
#: ISO 16283-2 Table A.1, L_FE at 1 m, 31.5-500 Hz: (nominal, tolerance) in dB
TABLE_dB = {"31.5": (39.0, 1.0), "63": (31.0, 1.5), "125": (23.0, 1.5), "250": (17.0, 2.0),
            "500": (12.5, 2.0)}  # fmt: skip


def test_the_measured_ball_across_heights_meets_the_papers_figures(run, results):
    """docs/guides/ball-across-heights.md, "The measured ball users can take": the composite
    ``rbjax reproduce`` writes as measured_ball.json meets each bar of issue 43, judged here
    against the paper's figures and the standard's table (written above, not taken from rbjax),
    and the file holds the model rbjax ships."""
    across = results["measured_ball_across_heights"]
    f = across["figures"]
    assert set(f["status"]) == {"ok"}
    for h, tc in PAPER_CONTACT_TIME_S.items():
        assert abs(f["contact_time_s"][h] - tc) <= 0.3e-3, h
    for h, peak in PAPER_PEAK_N.items():
        assert abs(f["peak_force_N"][h] / peak - 1.0) <= 0.05, h
    for band, (nominal, tol) in TABLE_dB.items():
        assert abs(f["lfe_1m_dB"][band] - nominal) <= tol, band
    assert 0.7 <= f["restitution_1m"] <= 0.9 and 18e-3 <= f["contact_time_s"]["1"] <= 22e-3
    growth = [f["growth_per_doubling_dB"][b] for b in ("31.5", "63", "125", "250", "500", "1000")]
    assert max(growth[:2]) <= 4.0 and np.all(np.diff(growth[2:]) > 0) and growth[5] >= 10.0
    assert all(across["bars"].values()) and across["failed_at_1m"] == []
    ball, model = rbjax.terms.serialize.load_params(run["dir"] / "measured_ball.json")
    assert ball == rbjax.report.MEASURED_BALL and model == rbjax.report.MEASURED_BALL_MODEL


def test_measured_ball_elastic_row_against_the_independent_solver():
    """docs/guides/summary-and-design.md, "The paper's measured ball", the recommended row:
    the elastic model with the printed E = 1.719 MPa (gas on, paper blocked force) gives 21.17 /
    19.83 / 19.27 ms and 2079 N at 160 cm by the scipy solution of Eq. 7 (tests/scipy_reference.py)
    too. (E printed to 4 digits moves t_c by < 0.003 ms and the peak by < 0.4 N.)"""
    ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=1.719e6)
    _, tc_ms, _, peak, _, _ = MEASURED_BALL_TABLE["paper"]
    for h, tc in zip((0.1, 1.0, 1.6), tc_ms, strict=True):
        ref = reference_impact(h, ball)
        assert 1e3 * ref.contact_time_s == pytest.approx(tc, abs=0.01), h
    assert reference_impact(1.6, ball).peak_force_N == pytest.approx(peak, abs=1.5)


def test_printed_eq4_limit():
    """The printed base 1 − (3 − x)(2x)² of Eq. 4 vanishes at the limit (x = δ/R)."""
    x = printed_eq4_limit_m(0.089) / 0.089
    assert 1 - (3 - x) * (2 * x) ** 2 == pytest.approx(0.0, abs=1e-12)
    assert 0 < x < 0.5
    # docs/accuracy.md: "as printed, Eq. 4 has no real value beyond δ = 27.1 mm" (R = 89 mm)
    assert 1e3 * printed_eq4_limit_m(0.089) == pytest.approx(27.1, abs=0.05)


#: docs/accuracy.md, "Against the paper" (the README's validated table quotes its first row):
#: rbjax's columns as printed, gas on and gas off: (quantity, height in m, unit) → (gas on, gas
#: off); and the differences from the paper's value printed beside them, in %.
ACCURACY_PAGE_PAPER_TABLE = {
    ("contact_time_s", 1.0, 1e-3): (20.43, 21.19),
    ("peak_force_N", 0.1, 1.0): (486.0, 481.0),
    ("peak_force_N", 1.6, 1.0): (2024.0, 1818.0),
    ("contact_resonance_Hz", 0.1, 1.0): (69.1, 68.4),
    ("contact_resonance_Hz", 1.6, 1.0): (81.7, 73.2),
}
ACCURACY_PAGE_DIFFERENCES = {  # (quantity, height, paper's value) → % (gas on, gas off)
    ("contact_time_s", 1.0, 20.8e-3): (-1.8, 1.9),
    ("peak_force_N", 1.6, 1800.0): (12.0, 1.0),
}
#: L_FE increase per doubling (dB): 31.5 Hz, 63 Hz, and the range over 125–1000 Hz.
ACCURACY_PAGE_GROWTH = {"adiabatic": (3.02, 3.72, 2.65, 2.89), "none": (2.87, 3.19, 2.74, 2.99)}


def _half_unit(printed: float) -> float:
    """Half a unit in the last printed digit (20.43 → 0.005, 69.1 → 0.05, 486.0 → 0.5: the
    tables here write integers as floats)."""
    decimals = repr(printed).removesuffix(".0").partition(".")[2]
    return 0.5 * 10.0 ** -len(decimals)


def test_the_accuracy_page_against_the_paper_table(results):
    """docs/accuracy.md, "Against the paper": rbjax's figures, gas on and off, at their printed
    digits (the report's own table is checked against the independent solver above); and, like
    the paper (§4.2, Fig. 8), the elastic model meets the L_FE tolerances at 1 m only in the 31.5
    and 63 Hz bands."""
    for (name, h, unit), printed in ACCURACY_PAGE_PAPER_TABLE.items():
        for gas, value in zip(GASES, printed, strict=True):
            got = at(results, gas, name, h) / unit
            assert got == pytest.approx(value, abs=_half_unit(value)), (name, h, gas, got)
    for (name, h, paper), printed in ACCURACY_PAGE_DIFFERENCES.items():
        for gas, pct in zip(GASES, printed, strict=True):
            got = 100 * (at(results, gas, name, h) / paper - 1)
            assert got == pytest.approx(pct, abs=_half_unit(pct)), (name, h, gas, got)
    for gas, (low, band63, lo, hi) in ACCURACY_PAGE_GROWTH.items():
        slopes = results["gas"][gas]["increase_per_doubling_dB"]
        assert slopes["31.5"] == pytest.approx(low, abs=0.005), (gas, slopes)
        assert slopes["63"] == pytest.approx(band63, abs=0.005), (gas, slopes)
        upper = [slopes[b] for b in ("125", "250", "500", "1000")]
        assert min(upper) == pytest.approx(lo, abs=0.005), (gas, slopes)
        assert max(upper) == pytest.approx(hi, abs=0.005), (gas, slopes)
    for gas in GASES:
        items = results["conformance_1m"][gas]["items"]
        bands = [i["name"] for i in items if i["name"].startswith("L_FE") and i["passed"]]
        assert bands == ["L_FE 31.5 Hz", "L_FE 63 Hz"], (gas, items)


#: docs/guides/fitting.md, "Growth of L_FE per doubling of drop height", the rows of the paper's
#: elastic model (16 heights, 10–160 cm): slope ± standard error per octave band, 31.5–1000 Hz.
FITTING_PAGE_GROWTH = {
    "adiabatic": (
        (3.02, 3.72, 2.65, 2.74, 2.75, 2.89),
        (0.00, 0.04, 0.05, 0.05, 0.03, 0.03),
    ),
    "none": ((2.87, 3.19, 2.99, 2.94, 2.74, 2.94), (0.01, 0.01, 0.01, 0.01, 0.03, 0.02)),
}


@pytest.mark.parametrize("gas", GASES)
def test_the_fitting_page_growth_rows_of_the_paper_model(results, gas):
    growth = results["growth_per_doubling"][gas]
    assert len(growth["heights_m"]) == 16
    slopes, errors = FITTING_PAGE_GROWTH[gas]
    np.testing.assert_allclose(growth["slope_dB_per_doubling"], slopes, rtol=0, atol=0.0051)
    np.testing.assert_allclose(growth["stderr_dB"], errors, rtol=0, atol=0.0051)


def test_bad_heights(tmp_path):
    with pytest.raises(ValueError, match="heights_m"):
        reproduce(tmp_path, heights_m=[-1.0, 1.0], progress=False)
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["reproduce", "--out", str(blocker / "sub")])
    assert code == 2 and out.getvalue() == ""
    assert len(err.getvalue().splitlines()) == 1 and err.getvalue().startswith("rbjax: error: ")


# ------------------------------------------------------------------------------ plot.py


@pytest.fixture(scope="module")
def result(run):
    # Same heights and options as the reproduce run: the compiled solve is reused.
    return rbjax.simulate(np.array(DEFAULT_HEIGHTS_M))


def test_impact_result_plot(result):
    fig = result.plot()
    (ax,) = fig.axes
    assert len(ax.lines) == len(DEFAULT_HEIGHTS_M)
    assert "(ms)" in ax.get_xlabel() and "(N)" in ax.get_ylabel()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[0] == "10 cm" and labels[-1] == "160 cm"
    peak = max(line.get_ydata().max() for line in ax.lines)
    assert peak == pytest.approx(
        float(np.max(result.peak_force_N)), rel=1e-3
    )  # 44.1 kHz samples near the peak
    assert ax.get_xlim()[1] == pytest.approx(1.05e3 * float(np.max(result.contact_time_s)))


def test_plot_lfe_bands_shades_the_tolerances():
    from rbjax.plot import plot_lfe_bands
    from rbjax.spectrum.standards import RUBBER_BALL_TOLERANCES

    levels = {"31.5": 39.0, "63": 31.0, "125": 23.0, "250": 17.0, "500": 12.5, "1000": 5.0}
    fig = plot_lfe_bands(levels, label="nominal")
    (ax,) = fig.axes
    (band,) = ax.collections  # the shaded tolerance band, 31.5-500 Hz
    verts = band.get_paths()[0].vertices
    tol = RUBBER_BALL_TOLERANCES.lfe_octave_dB
    assert verts[:, 1].min() == pytest.approx(min(t.lower for t in tol.values()))
    assert verts[:, 1].max() == pytest.approx(max(t.upper for t in tol.values()))
    (line,) = [ln for ln in ax.lines if ln.get_label() == "nominal"]
    np.testing.assert_array_equal(line.get_ydata(), list(levels.values()))
    assert "Hz" in ax.get_xlabel() and "dB" in ax.get_ylabel()

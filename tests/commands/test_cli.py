"""The ``rbjax`` command line: discovery, --help, --json, the table, and one-line errors.

Everything runs in-process through ``rbjax.cli.main`` (one JAX compilation for the heights
below, shared by every test that simulates) except one subprocess call of the installed
``rbjax`` entry point. Numbers are checked against ``rbjax.simulate`` called directly and
against the independent scipy solution of Eq. 7 (tests/scipy_reference.py) with an L_FE
computed here from NumPy's FFT and the IEC 61260-1 band edges.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import rbjax
from rbjax import commands
from rbjax.cli import build_parser, command_modules
from rbjax.spectrum.standards import check_conformance
from rbjax.terms.serialize import save_params

from cli_runner import run_cli
from scipy_reference import reference_impact

# A smoke test (tests/conftest.py: compiled with most optimisations off): the command line's
# plumbing; its numbers are the solve paths', held at the default level in tests/solve.
pytestmark = pytest.mark.xla_smoke

HEIGHTS_M = [0.1, 1.0, 1.6]
ARGS = ["simulate", "--height-m", *map(str, HEIGHTS_M)]
OCTAVES = ("31.5", "63", "125", "250", "500", "1000")
THIRDS = (
    "25",
    "31.5",
    "40",
    "50",
    "63",
    "80",
    "100",
    "125",
    "160",
    "200",
    "250",
    "315",
    "400",
    "500",
    "630",
    "800",
    "1000",
    "1250",
)


@pytest.fixture(scope="module")
def direct():
    return rbjax.simulate(np.array(HEIGHTS_M))


@pytest.fixture(scope="module")
def json_rows():
    code, out, err = run_cli([*ARGS, "--json"])
    assert code == 0, err
    assert "NaN" not in out and "Infinity" not in out
    rows = json.loads(out)
    # one row per height, in order: the tests that loop over these rows cannot pass on an empty list
    assert [row["height_m"] for row in rows] == HEIGHTS_M
    return rows


# ------------------------------------------------------------------------------ structure


def test_commands_are_discovered_in_sorted_order():
    names = command_modules()
    assert names == sorted(names)
    assert {"simulate", "reproduce"} <= set(names)


def test_a_new_command_module_is_picked_up(tmp_path, monkeypatch):
    (tmp_path / "zz_probe.py").write_text(
        "from rbjax.commands import add_command, emit_json\n"
        "def register(subparsers):\n"
        "    p = add_command(subparsers, 'zz-probe', help='probe')\n"
        "    p.add_argument('--x', type=float, required=True)\n"
        "    p.set_defaults(func=lambda a: emit_json({'x': a.x}) or 0)\n"
    )
    (tmp_path / "zz_helpers.py").write_text("VALUE = 1  # no register(): not a command\n")
    (tmp_path / "_zz_private.py").write_text(
        "raise RuntimeError('private modules must not be imported')\n"
    )
    monkeypatch.setattr(commands, "__path__", [*commands.__path__, str(tmp_path)])
    for name in ("zz_probe", "zz_helpers"):
        monkeypatch.delitem(sys.modules, f"rbjax.commands.{name}", raising=False)
    assert "zz_probe" in command_modules() and "_zz_private" not in command_modules()
    code, out, err = run_cli(["zz-probe", "--x", "2.5", "--json"])
    assert (code, json.loads(out)) == (0, {"x": 2.5}), err
    for name in ("zz_probe", "zz_helpers"):  # leave no trace for other tests
        sys.modules.pop(f"rbjax.commands.{name}", None)


def subcommands():
    parser = build_parser()
    (action,) = [a for a in parser._actions if a.dest == "command"]
    return sorted(action.choices)


@pytest.mark.parametrize("name", subcommands())
def test_help_for_every_command(name):
    code, out, err = run_cli([name, "--help"])
    assert code == 0, err
    assert out.startswith(f"usage: rbjax {name}")
    assert "--json" in out


def test_top_level_help_and_no_command():
    code, out, _ = run_cli(["--help"])
    assert code == 0 and "simulate" in out and "reproduce" in out
    code, out, err = run_cli([])
    assert code == 2 and out == "" and "usage: rbjax" in err


def test_installed_entry_point_help():
    exe = Path(sys.executable).with_name("rbjax")
    assert exe.exists(), f"the console script is not installed next to {sys.executable}"
    proc = subprocess.run([str(exe), "--help"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert (
        "usage: rbjax" in proc.stdout and "simulate" in proc.stdout and "reproduce" in proc.stdout
    )


# ------------------------------------------------------------------------------ simulate --json


def test_json_has_the_documented_keys(json_rows):
    assert len(json_rows) == len(HEIGHTS_M)
    keys = {
        "height_m",
        "contact_time_s",
        "peak_force_N",
        "restitution",
        "lfe_total_dB",
        "lfe_octave_dB",
        "lfe_third_octave_dB",
        "conformance",
        "status",
        "path",
    }
    for row, h in zip(json_rows, HEIGHTS_M):
        assert set(row) == keys
        assert row["height_m"] == h and row["status"] == "ok"
        assert row["path"] == "quadrature"  # the default --path auto, elastic model
        assert tuple(row["lfe_octave_dB"]) == OCTAVES
        assert tuple(row["lfe_third_octave_dB"]) == THIRDS
        assert {"passed", "clause", "items"} <= set(row["conformance"])


def test_json_agrees_with_simulate(json_rows, direct):
    for name in ("contact_time_s", "peak_force_N", "restitution"):
        np.testing.assert_allclose(
            [r[name] for r in json_rows], np.asarray(getattr(direct, name)), rtol=1e-12
        )
    octave = np.asarray(rbjax.spectrum.levels.lfe_octave_dB(direct.force_N, 44_100.0))
    np.testing.assert_allclose(
        [[r["lfe_octave_dB"][b] for b in OCTAVES] for r in json_rows], octave, rtol=0, atol=1e-9
    )
    i = HEIGHTS_M.index(1.0)
    expected = check_conformance(
        octave[i],
        contact_time_s=json_rows[i]["contact_time_s"],
        restitution=json_rows[i]["restitution"],
        mass_kg=2.5,
        height_m=1.0,
    )
    assert json_rows[i]["conformance"] == json.loads(json.dumps(expected.to_dict()))


def test_method_option_runs_the_ode_and_agrees(json_rows):
    code, out, err = run_cli([*ARGS, "--json", "--path", "ode"])
    assert code == 0, err
    rows = json.loads(out)
    assert [r["path"] for r in rows] == ["ode"] * len(HEIGHTS_M)
    for name in ("contact_time_s", "peak_force_N", "restitution"):
        np.testing.assert_allclose([r[name] for r in rows], [r[name] for r in json_rows], rtol=1e-8)
    code, out, err = run_cli(["simulate", "--help"])
    assert code == 0 and "--path {auto,ode,quadrature,angle}" in out


def test_json_agrees_with_the_scipy_reference(json_rows):
    """Contact time, peak force and restitution of Eq. 7 solved independently (DOP853,
    rtol 1e-12)."""
    for row in json_rows:
        ref = reference_impact(row["height_m"], rbjax.JIS_RUBBER_BALL)
        assert row["contact_time_s"] == pytest.approx(ref.contact_time_s, rel=1e-7)
        assert row["peak_force_N"] == pytest.approx(ref.peak_force_N, rel=1e-7)
        assert row["restitution"] == pytest.approx(ref.restitution, rel=1e-7)


def _band_lfe(force, rate, centres_exponents, fraction):
    """Octave/third-octave L_FE written out: rfft, one-sided ESD, base-ten IEC 61260-1 edges."""
    n = force.size
    spec = np.fft.rfft(force) / rate
    esd = 2.0 * np.abs(spec) ** 2
    esd[0] /= 2.0
    esd[-1] /= 2.0  # even n: Nyquist
    f = np.arange(esd.size) * rate / n
    g = 10**0.3
    out = []
    for x in centres_exponents:
        fm = 1000.0 * g ** (x / fraction)
        lo, hi = fm * g ** (-1 / (2 * fraction)), fm * g ** (1 / (2 * fraction))
        out.append(10 * math.log10(np.sum(esd[(f >= lo) & (f < hi)]) * rate / n))
    return np.array(out)


def test_lfe_against_an_independent_spectrum(json_rows):
    """L_FE (Eq. 11) at 1 m from the scipy force history on the 44.1 kHz × 1 s grid (§2.4)."""
    rate = 44_100.0
    row = json_rows[HEIGHTS_M.index(1.0)]
    force = reference_impact(1.0, rbjax.JIS_RUBBER_BALL).force_N(np.arange(44_100) / rate)
    assert row["lfe_total_dB"] == pytest.approx(10 * math.log10(np.sum(force**2) / rate), abs=1e-6)
    octave = _band_lfe(force, rate, range(-5, 1), 1)  # 31.5 Hz ... 1 kHz
    np.testing.assert_allclose([row["lfe_octave_dB"][b] for b in OCTAVES], octave, atol=1e-5)
    third = _band_lfe(force, rate, range(-16, 2), 3)  # 25 Hz ... 1.25 kHz
    np.testing.assert_allclose([row["lfe_third_octave_dB"][b] for b in THIRDS], third, atol=1e-5)


def test_octave_energy_is_the_sum_of_its_thirds(json_rows):
    """Base-ten octave edges are third-octave edges: E_octave = sum of its three thirds."""
    for row in json_rows:
        thirds = np.array([10 ** (row["lfe_third_octave_dB"][b] / 10) for b in THIRDS]).reshape(
            6, 3
        )
        octave = np.array([10 ** (row["lfe_octave_dB"][b] / 10) for b in OCTAVES])
        np.testing.assert_allclose(thirds.sum(axis=1), octave, rtol=1e-9)
        assert 10 * math.log10(octave.sum()) < row["lfe_total_dB"]


def test_failed_solves_are_null_with_the_status_name(json_rows):
    """A 10 m drop goes past δ_max = 2h, the limit of the small-deflection shell model (§2.1):
    that row has no numbers, only its status name, and the JSON has no NaN token; the other rows
    are those of the normal run. (Same batch shape and longest contact as HEIGHTS_M: no
    recompile.)"""
    heights = [0.1, 1.0, 10.0]
    code, out, err = run_cli(["simulate", "--height-m", *map(str, heights), "--json"])
    assert code == 0, err
    assert "NaN" not in out
    rows = json.loads(out)
    direct = rbjax.simulate(np.array(heights))
    assert (
        [r["status"] for r in rows] == list(direct.status_name) == ["ok", "ok", "deflection_limit"]
    )
    bad = rows[-1]
    assert bad["height_m"] == 10.0
    assert (
        bad["contact_time_s"] is None and bad["peak_force_N"] is None and bad["restitution"] is None
    )
    assert bad["lfe_total_dB"] is None and set(bad["lfe_octave_dB"].values()) == {None}
    assert set(bad["lfe_third_octave_dB"].values()) == {None} and bad["conformance"] is None
    assert rows[:2] == json_rows[:2]


def test_table_shows_failed_status():
    code, out, err = run_cli(["simulate", "--height-m", "0.1", "1.0", "10"])
    assert code == 0, err
    lines = out.splitlines()
    cells, solved = lines[4].split(), lines[2].split()  # the 10 m row and the 0.1 m row
    assert cells[0] == "10.00" and cells[-1] == "deflection_limit"
    assert (
        len(cells) == len(solved) == 13
    )  # height, t_c, F_peak, e, L_FE, 6 bands, conformance, status
    assert cells[1:-1] == ["—"] * 11


# ------------------------------------------------------------------------------ the table


def test_table_renders(direct):
    code, out, err = run_cli(ARGS)
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0].split()[:3] == ["height", "m", "t_c"]
    for band in OCTAVES:
        assert f"{band} Hz" in lines[0]
    data = lines[2 : 2 + len(HEIGHTS_M)]
    for line, h, tc, fp in zip(
        data, HEIGHTS_M, np.asarray(direct.contact_time_s), np.asarray(direct.peak_force_N)
    ):
        cells = line.split()
        assert cells[0] == f"{h:.2f}" and cells[1] == f"{tc * 1e3:.2f}" and cells[2] == f"{fp:.0f}"
        assert cells[-1] == "ok"
        assert cells[-2] == (
            "n/a" if h != 1.0 else "FAIL"
        )  # the elastic model misses 125-500 Hz (paper Fig. 8)
    assert "outside the tolerances" in out and "L_FE 125 Hz" in out
    assert "simulating 3 drop height(s)" in err


# ------------------------------------------------------------------------------ --params


def test_params_file_then_overrides(tmp_path):
    path = tmp_path / "fit.json"
    ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=2.0e6, poisson=0.45, mass_kg=2.4)
    save_params(path, ball, rbjax.Model(gas="none", blocked_force="momentum"))
    from rbjax.commands.simulate import load_ball_and_model

    args = build_parser().parse_args(
        [
            "simulate",
            "--height-m",
            "1",
            "--params",
            str(path),
            "--youngs-pa",
            "1.7e6",
            "--gas",
            "adiabatic",
        ]
    )
    loaded, model = load_ball_and_model(args)
    assert (loaded.youngs_Pa, loaded.poisson, loaded.mass_kg) == (1.7e6, 0.45, 2.4)
    assert (model.gas, model.blocked_force) == ("adiabatic", "momentum")


def test_params_end_to_end(tmp_path, json_rows):
    """A params file whose E is overridden back to 1.6 MPa reproduces the default run."""
    path = tmp_path / "fit.json"
    save_params(path, rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=2.2e6), rbjax.Model())
    code, out, err = run_cli([*ARGS, "--params", str(path), "--youngs-pa", "1.6e6", "--json"])
    assert code == 0, err
    assert [r["contact_time_s"] for r in json.loads(out)] == [
        r["contact_time_s"] for r in json_rows
    ]


# ------------------------------------------------------------------------------ bad input


@pytest.mark.parametrize(
    "argv, words",
    [
        (["simulate", "--height-m", "-1"], ["height_m", "-1", "(0, inf)"]),
        (["simulate", "--height-m", "nan"], ["height_m", "nan", "(0, inf)"]),
        (["simulate", "--height-m", "1", "--poisson", "0.7"], ["poisson", "0.7", "(-1, 0.5]"]),
        (["simulate", "--height-m", "1", "--youngs-pa", "-5"], ["youngs_Pa", "-5", "(0, inf)"]),
        (["simulate", "--height-m", "1", "--gas", "foo"], ["--gas", "foo", "adiabatic", "none"]),
        (["simulate", "--height-m", "abc"], ["--height-m", "abc"]),
        (
            ["simulate", "--height-m", "1", "--params", "/nonexistent/fit.json"],
            ["params", "/nonexistent/fit.json"],
        ),
        (["nosuchcommand"], ["nosuchcommand", "simulate"]),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, words):
    code, out, err = run_cli(argv)
    assert code == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("rbjax: error: ")
    assert "Traceback" not in err
    for w in words:
        assert w in lines[0], (w, lines[0])


@pytest.mark.parametrize(
    "content, words",
    [
        ("{not json", ["cannot read JSON"]),
        ('{"ball": {"radius_m": 0.089}, "model": {}}', ["missing", "wall_m"]),
        (
            '{"ball": {"radius_m": 0.089, "wall_m": 0.032, "mass_kg": 2.5, "youngs_Pa": 1.6e6, '
            '"poisson": 0.9}, "model": {}}',
            ["poisson", "0.9"],
        ),
        (
            '{"ball": {"radius_m": 0.089, "wall_m": 0.032, "mass_kg": 2.5, "youngs_Pa": 1.6e6, '
            '"poisson": 0.5}, "model": {"damping": {"name": "zener", "tau": 1}}}',
            ["params", "tau"],
        ),
    ],
)
def test_bad_params_file_exits_2_with_one_line(tmp_path, content, words):
    path = tmp_path / "bad.json"
    path.write_text(content)
    code, out, err = run_cli(["simulate", "--height-m", "1", "--params", str(path)])
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and err.startswith("rbjax: error: ")
    for w in words:
        assert w in err, (w, err)


def test_compile_cache_location_follows_the_environment(monkeypatch, tmp_path):
    from rbjax.cli import compile_cache_dir

    monkeypatch.setenv("RBJAX_CACHE_DIR", str(tmp_path / "c"))
    assert compile_cache_dir() == str(tmp_path / "c")
    monkeypatch.setenv("RBJAX_CACHE_DIR", "")
    assert compile_cache_dir() is None
    monkeypatch.delenv("RBJAX_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert compile_cache_dir() == str(tmp_path / "xdg" / "rbjax" / "jax")

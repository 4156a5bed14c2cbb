"""`rbjax design --out DIR` writes parameter files that `rbjax simulate --params` takes (issue 43,
item 3): design.json with one design, design_<model>_<geometry>.json per design, and the
--json output; simulating them reproduces the design's ball, model and conformance at 1 m.
(The design itself, its margins and the 32-start bar: benchmarks/fitting.py --only
design_check.)"""

import json

import numpy as np
import pytest

from rbjax.terms.serialize import ball_to_dict, load_params, model_to_dict

from cli_runner import run_cli

# A smoke test (tests/conftest.py: compiled with most optimisations off): one start, one step of
# the smallest model; the two runs share their compiled programs (the ball's geometry is data).
pytestmark = pytest.mark.xla_smoke

SMALLEST = ["--model", "paper", "--starts", "1", "--steps", "1", "--quiet"]


def _simulated_items(params_file) -> dict:
    code, out, err = run_cli(
        ["simulate", "--params", str(params_file), "--height-m", "1.0", "--json"]
    )
    assert code == 0, err
    (row,) = json.loads(out)
    return {i["name"]: i["value"] for i in row["conformance"]["items"]}


def _check_reproduces(params_file, design: dict):
    ball, model = load_params(params_file)
    assert ball_to_dict(ball) == design["ball"]
    assert json.loads(json.dumps(model_to_dict(model))) == design["model"]
    got = _simulated_items(params_file)
    expect = {i["name"]: i["value"] for i in design["conformance"]["items"]}
    assert expect.keys() <= got.keys()  # simulate also checks the drop height
    for name in expect:
        np.testing.assert_allclose(got[name], expect[name], rtol=1e-9, err_msg=name)


def test_one_design_writes_a_parameter_file_simulate_takes(tmp_path):
    code, out, err = run_cli(["design", *SMALLEST, "--out", str(tmp_path), "--json"])
    assert code == 0, err
    printed = json.loads(out)
    assert [d["geometry"] for d in printed["designs"]] == ["jis"]
    (design,) = printed["designs"]
    assert printed["ball"] == design["ball"] and printed["model"] == design["model"]
    written = json.loads((tmp_path / "design.json").read_text())
    assert written == printed
    assert json.loads((tmp_path / "design_paper_jis.json").read_text()) == design
    assert (tmp_path / "design_paper_jis.png").is_file()
    for name in ("design.json", "design_paper_jis.json"):
        _check_reproduces(tmp_path / name, design)


def test_both_geometries_write_one_parameter_file_each(tmp_path):
    code, out, err = run_cli(["design", *SMALLEST, "--geometry", "both", "--out", str(tmp_path)])
    assert code == 0, err
    summary = json.loads((tmp_path / "design.json").read_text())
    assert "ball" not in summary and [d["geometry"] for d in summary["designs"]] == ["jis", "iso"]
    for design in summary["designs"]:
        _check_reproduces(tmp_path / f"design_paper_{design['geometry']}.json", design)
    # design.json holds two designs: simulate says what it expects (pass one file per design)
    code, _, err = run_cli(
        ["simulate", "--params", str(tmp_path / "design.json"), "--height-m", "1.0"]
    )
    assert code != 0 and "'ball' and 'model'" in err


def test_help_names_every_model_of_the_fit():
    from rbjax.fit.layout import (
        ARREST_SUFFIX,
        BALL_MODE_SUFFIX,
        LAYER_SUFFIX,
        SERIES_SUFFIX,
        STIFFENING_SUFFIX,
    )
    from rbjax.terms.damping import DAMPING_MODELS

    code, out, _ = run_cli(["design", "--help"])
    assert code == 0 and "every model `rbjax fit` takes" in out
    suffixes = (STIFFENING_SUFFIX, LAYER_SUFFIX, ARREST_SUFFIX, BALL_MODE_SUFFIX, SERIES_SUFFIX)
    for name in (*DAMPING_MODELS, *suffixes):
        assert name in out, name
    assert "design_<model>_<geometry>.json" in out and "simulate --params" in out

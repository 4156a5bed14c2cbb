"""The fitted hunt-crossley+ball-mode/momentum model (values from ``results/ball_mode.json``)
against the bundled recordings: L_FE growth per doubling of the drop height per octave band
(bar: within 1 dB of the recordings' own growth) and the standard's tolerance check at 1 m
(bar: passes in every band where the recordings at 1 m do).

Prints tables and writes ``results/ball_mode_growth.json``. ``--quick``: the hunt-crossley
model at three heights.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import rbjax
from rbjax.data import load_examples
from rbjax.fit import prepare_data
from rbjax.spectrum import check_conformance, lfe_octave_dB
from rbjax.studies import model_growth, recording_growth

from _common import read_json, write_json

HEIGHTS_M = np.array([0.1, 0.2, 0.4, 0.8, 1.0, 1.6])
#: the fitted values when ``ball_mode`` has not run into this results folder: the committed run
COMMITTED = Path(__file__).resolve().parents[1] / "results" / "ball_mode.json"


def recordings_lfe_dB():
    """(heights, octave L_FE per drop) of the bundled recordings, conditioned as the fit does
    (``rbjax.fit.prepare_data``, one record per drop) and zero-padded to 1 s."""
    data = prepare_data(load_examples(), average=False)
    x = np.asarray(data.force_N)
    n = int(round(data.rate_Hz))
    padded = np.pad(x, ((0, 0), (0, max(0, n - x.shape[1]))))
    return np.asarray(data.height_m, float), np.asarray(lfe_octave_dB(padded, data.rate_Hz))


def main(quick: bool = False) -> None:
    fitted = (read_json("ball_mode") or json.loads(COMMITTED.read_text()))["held_out"]
    heights_m = HEIGHTS_M[[0, 4, 5]] if quick else HEIGHTS_M
    out = {}
    data = recording_growth()
    print("recordings", np.round(data.slope_dB, 2))
    for name in ("hunt-crossley",) if quick else ("hunt-crossley", "hunt-crossley+ball-mode"):
        p = fitted[name]["parameters"]
        ball = rbjax.JIS_RUBBER_BALL.replace(youngs_Pa=p["youngs_Pa"], poisson=p["poisson"])
        mode = (
            rbjax.BallMode(p["mode_mass_ratio"], p["mode_frequency_Hz"], p["mode_loss_factor"])
            if "mode_mass_ratio" in p
            else None
        )
        model = rbjax.Model(
            blocked_force="momentum", damping=rbjax.HuntCrossley(p["alpha_s_per_m"]), ball_mode=mode
        )
        growth = model_growth(heights_m, ball, model, label=name)
        diff = np.asarray(growth.slope_dB) - np.asarray(data.slope_dB)
        res = rbjax.simulate(
            1.0, ball, damping=model.damping, blocked_force="momentum", ball_mode=mode
        )
        lfe_1m = np.asarray(res.lfe_octave_dB()).reshape(-1)
        check = check_conformance(
            lfe_1m,
            contact_time_s=float(res.contact_time_s),
            restitution=float(res.restitution),
            mass_kg=2.5,
            height_m=1.0,
        )
        out[name] = {
            "growth_dB": np.asarray(growth.slope_dB).tolist(),
            "minus_recordings_dB": diff.tolist(),
            "max_abs_diff_dB": float(np.max(np.abs(diff))),
            "conformance_1m": check.to_dict(),
        }
        print(
            name,
            "growth",
            np.round(growth.slope_dB, 2),
            "Δ",
            np.round(diff, 2),
            "max |Δ|",
            round(float(np.max(np.abs(diff))), 2),
        )
        print(check)
    heights, levels = recordings_lfe_dB()
    at_1m = np.asarray(levels)[np.isclose(np.asarray(heights), 1.0, atol=0.02)]
    out["recordings"] = {
        "growth_dB": np.asarray(data.slope_dB).tolist(),
        "conformance_1m_per_drop": [check_conformance(row).to_dict() for row in at_1m],
    }
    for row in at_1m:
        print("recording at 1 m:", check_conformance(row))
    print(f"wrote {write_json('ball_mode_growth' + ('_quick' if quick else ''), out)}")

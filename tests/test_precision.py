"""docs/guides/solving.md, "Precision": every entry point that solves or analyses an impact
raises the named ``RuntimeError`` when ``jax_enable_x64`` is switched off after importing rbjax,
rather than computing in float32.

One subprocess (the flag is process-wide, so switching it off here would break the other tests)
imports rbjax, builds the few inputs that need float64 (an ``ImpactResult``), switches the flag
off and calls every entry point; each call must raise before anything is compiled, so the whole
check takes a few seconds. It prints one JSON line: the entry point → what happened.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

MESSAGE = "rbjax needs float64"

#: Every name below is called once in the child with x64 off (docs/guides/solving.md, "Precision").
SCRIPT = textwrap.dedent(
    """
    import json
    import jax
    import numpy as np
    import rbjax
    from rbjax import solve, spectrum, studies
    from rbjax.studies.sensitivity import conformance_probability, global_sensitivity, local_sensitivity

    ball, force = rbjax.JIS_RUBBER_BALL, np.hanning(900)
    result = rbjax.simulate(1.0)  # made with float64 on
    import rbjax.data
    import rbjax.fit
    records = rbjax.fit.load_data(rbjax.data.examples_dir())
    jax.config.update("jax_enable_x64", False)
    calls = {
        "simulate": lambda: rbjax.simulate(1.0),
        "simulate(method='ode')": lambda: rbjax.simulate(1.0, path="ode"),
        "trajectory": lambda: rbjax.trajectory(1.0, np.array([0.0, 1e-3])),
        "energy_balance": lambda: rbjax.energy_balance(1.0),
        "ImpactResult.history": lambda: result.history(),
        "ImpactResult.lfe_octave_dB": lambda: result.lfe_octave_dB(),
        "solve.force_history": lambda: solve.force_history(1.0, ball, rbjax.Model(), rbjax.Solver()),
        "solve.sampled_history": lambda: solve.sampled_history(1.0, ball, num_samples=10),
        "solve.impact_quadrature": lambda: solve.impact_quadrature(1.0, ball, rbjax.Model()),
        "solve.impact_angle": lambda: solve.impact_angle(1.0, ball, rbjax.Model(damping=rbjax.KelvinVoigt(10.0))),
        "solve.evaluate": lambda: solve.evaluate({"youngs_pa": np.array([1.6e6])}),
        "spectrum.energy_spectrum": lambda: spectrum.energy_spectrum(force, 44100.0),
        "spectrum.band_energies_N2s": lambda: spectrum.band_energies_N2s(force, 44100.0, [44.0], [88.0]),
        "spectrum.lfe_total_dB": lambda: spectrum.lfe_total_dB(force, 44100.0),
        "spectrum.lfe_octave_dB": lambda: spectrum.lfe_octave_dB(force, 44100.0),
        "spectrum.lfe_third_octave_dB": lambda: spectrum.lfe_third_octave_dB(force, 44100.0),
        "spectrum.force_spectrum_dB": lambda: spectrum.force_spectrum_dB(force, 44100.0),
        "spectrum.contact_resonance_Hz": lambda: spectrum.contact_resonance_Hz(force, 44100.0),
        "studies.local_sensitivity": lambda: local_sensitivity(1.0),
        "studies.global_sensitivity": lambda: global_sensitivity({"youngs_pa": (1.5e6, 1.7e6)}, 8, outputs=("peak_force_N",)),
        "studies.conformance_probability": lambda: conformance_probability(8, {"youngs_pa": ("uniform", 1.5e6, 1.7e6)}),
        "studies.model_growth": lambda: studies.model_growth([0.5, 1.0]),
        "studies.recording_growth": lambda: studies.recording_growth(),
        "fit.fit": lambda: rbjax.fit.fit(records, "kelvin-voigt"),
        "fit.predict": lambda: rbjax.fit.predict(records),
        "studies.select_model": lambda: studies.select_model(records, ["paper"]),
    }
    outcome = {}
    for name, call in calls.items():
        try:
            call()
            outcome[name] = "returned"
        except Exception as err:  # report the type and the message, judged by the parent
            outcome[name] = f"{type(err).__name__}: {err}"
    print(json.dumps(outcome))
    """  # noqa: E501
)

ENTRY_POINTS = [
    line.split('"')[1]
    for line in SCRIPT.splitlines()
    if line.startswith('    "') and "lambda" in line
]


@pytest.fixture(scope="module")
def outcomes() -> dict[str, str]:
    src = str(Path(__file__).resolve().parents[1] / "src")
    env = os.environ | {
        "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]),
        "RBJAX_CACHE_DIR": "",
    }
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=300
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_entry_point_is_called(outcomes):
    assert len(ENTRY_POINTS) >= 20 and list(outcomes) == ENTRY_POINTS


@pytest.mark.parametrize("name", ENTRY_POINTS)
def test_float32_is_refused_with_the_named_error(outcomes, name):
    # docs/guides/solving.md, "Precision": a RuntimeError naming float64, never a silent float32
    # result
    assert outcomes[name].startswith(f"RuntimeError: {MESSAGE}"), outcomes[name]

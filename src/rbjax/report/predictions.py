"""The computation of ``reproduce``: rbjax's predictions for the paper's JIS ball (§4).

The drop heights (1 m always among them), one batched ``simulate`` call per gas option (one
compilation) with the spectra and band levels of its 44.1 kHz × 1 s records (§2.4), the
conformance at 1 m with the rubber-ball tolerances, the growth of L_FE per doubling of the
bundled recordings beside the model's (``rbjax.studies.growth``) and the ball's shell modes
(``rbjax.terms.shell_modes``). Nothing is drawn or written here.
"""

from __future__ import annotations

import numpy as np

from .._validate import check_range
from ..solve.inputs import PAPER_RATE_Hz
from ..solve.simulate import simulate
from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.levels import (
    contact_resonance_Hz,
    lfe_increase_per_doubling_dB,
    lfe_octave_dB,
    lfe_third_octave_dB,
    lfe_total_dB,
)
from ..spectrum.standards import check_conformance
from ..studies.growth import growth_per_doubling_dB, recording_growth
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.model import Model
from ..terms.shell_modes import THEORIES, shell_frequencies_Hz
from .paper import GAS, STANDARD_HEIGHT_M


def drop_heights(heights_m) -> np.ndarray:
    """The sorted, distinct drop heights of ``heights_m`` (m), the standard 1 m added."""
    h = np.asarray(heights_m, dtype=float).reshape(-1)
    check_range("heights_m", h, lower=0.0)
    if h.size < 2:
        raise ValueError(
            f"heights_m={h.tolist()} needs at least two heights (valid: two or more heights > 0 m)"
        )
    # The standard height is always included (Figs. 3 and 8; the normalisation of Fig. 9).
    return np.unique(np.round(np.append(h, STANDARD_HEIGHT_M), 12))


def standard_index(heights) -> int:
    """The index of the standard height (1 m) in ``heights`` (as :func:`drop_heights` makes
    them)."""
    return int(np.flatnonzero(np.isclose(heights, STANDARD_HEIGHT_M))[0])


def simulate_heights(heights: np.ndarray, gas: str) -> dict:
    """Simulate all heights with one gas option; spectra and band levels of the 1 s records."""

    res = simulate(heights, model=Model(gas=gas))
    hist = res.history()  # the paper's 44.1 kHz x 1 s grid (§2.4)
    force = np.asarray(hist.force_N)
    ok = np.asarray(res.status) == 0
    octave = np.array(lfe_octave_dB(force, PAPER_RATE_Hz))
    octave[~ok] = np.nan
    third = np.array(lfe_third_octave_dB(force, PAPER_RATE_Hz))
    third[~ok] = np.nan
    total = np.where(ok, np.asarray(lfe_total_dB(force, PAPER_RATE_Hz)), np.nan)
    slope = np.full(octave.shape[1], np.nan)
    if ok.sum() >= 2:
        slope = np.asarray(lfe_increase_per_doubling_dB(heights[ok], octave[ok], STANDARD_HEIGHT_M))
    resonance = np.where(ok, np.asarray(contact_resonance_Hz(force, PAPER_RATE_Hz)), np.nan)
    # The paper's contact time: the first 44.1 kHz sample after the end of contact (§2.4).
    in_contact = np.asarray(hist.in_contact)
    first_out = np.argmax(~in_contact[:, 1:], axis=1) + 1
    return {
        "result": res,
        "time_s": np.asarray(hist.time_s),
        "deflection_m": np.asarray(hist.deflection_m),
        "force_N": force,
        "in_contact": in_contact,
        "ok": ok,
        "status": [str(s) for s in np.atleast_1d(res.status_name)],
        "contact_time_s": np.asarray(res.contact_time_s),
        "grid_contact_time_s": np.where(ok, first_out / PAPER_RATE_Hz, np.nan),
        "peak_force_N": np.asarray(res.peak_force_N),
        "restitution": np.asarray(res.restitution),
        "max_deflection_m": np.asarray(res.max_deflection_m),
        "lfe_total_dB": total,
        "lfe_octave_dB": octave,
        "lfe_third_octave_dB": third,
        "increase_per_doubling_dB": slope,
        "contact_resonance_Hz": resonance,
    }


def conformance_at_standard_height(runs, heights) -> dict:
    """{gas: the conformance at 1 m with the rubber-ball tolerances, as a dict} (None where the
    1 m solve failed)."""

    i1 = standard_index(heights)
    conformance = {}
    for g, run in runs.items():
        conformance[g] = (
            check_conformance(
                run["lfe_octave_dB"][i1],
                contact_time_s=run["contact_time_s"][i1],
                restitution=run["restitution"][i1],
                mass_kg=JIS_RUBBER_BALL.mass_kg,
                height_m=STANDARD_HEIGHT_M,
            ).to_dict()
            if run["ok"][i1]
            else None
        )
    return conformance


def growth_results(runs, heights) -> dict:
    """Growth of L_FE per doubling (``rbjax.studies.growth``): the bundled recordings (one point per
    drop) and the paper's model, gas on and off, from the runs' octave bands (§4.2, Fig. 11).
    The recordings are left out (with a note) if they cannot be read."""

    out: dict = {}
    try:
        out["recordings"] = recording_growth(label="emulated recordings (bundled, per drop)")
    except (OSError, ValueError) as exc:  # DataError is a ValueError
        out["recordings_error"] = str(exc)
    for g, run in runs.items():
        out[g] = growth_per_doubling_dB(
            heights,
            run["lfe_octave_dB"],
            OCTAVE_BANDS,
            ref_height_m=STANDARD_HEIGHT_M,
            label=f"paper's elastic model, {GAS[g]}",
        )
    return out


def shell_mode_fundamentals() -> dict:
    """The JIS ball's fundamental axisymmetric mode (n = 2) by the three theories of
    ``rbjax.terms.shell_modes``, beside the paper's ~60 Hz (§4.1)."""

    return {
        t: shell_frequencies_Hz(JIS_RUBBER_BALL, 2, t, n_roots=1).fundamental_Hz for t in THEORIES
    }

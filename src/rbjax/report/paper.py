"""The values the paper reports (Schoenwald, Zeitler & Nightingale 2011, §4.1–4.2) and the
comparison of rbjax's predictions with them: the table rows and one explanation per row, every
number in it computed here."""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_float
from ..spectrum.bands import OCTAVE_BANDS, band_edges_Hz
from ..terms.ball import JIS_RUBBER_BALL
from ..terms.forces import gas_force_N, shell_force_N

#: The paper's drop heights, 10 cm to 160 cm in 10 cm steps (§3).
DEFAULT_HEIGHTS_M = tuple(round(0.1 * i, 1) for i in range(1, 17))


#: The standard drop height (JIS A 1418-2; ISO 10140-5 Annex F).
STANDARD_HEIGHT_M = 1.0


#: The heights of the paper's Fig. 9 (doublings from 10 cm, and 120 cm).
FIG9_HEIGHTS_M = (0.1, 0.2, 0.4, 0.8, 1.2, 1.6)


#: Gas options and their labels.
GAS = {"adiabatic": "gas on", "none": "gas off"}


#: Values the paper reports in its text (§4.1, §4.2). "≈" values are read as stated.
PAPER = {
    "predicted_contact_time_s": {"1.0": 20.8e-3},  # §4.1: "the prediction (20.8 ms)"
    "peak_force_N": {"0.1": 500.0, "1.6": 1800.0},  # §4.1: "roughly 500 N" / "about 1800 N"
    "measured_contact_time_s": {"0.1": 21.3e-3, "1.0": 19.6e-3, "1.6": 19.3e-3},  # §4.1
    "increase_per_doubling_dB": {
        "31.5": 3.0,
        "63": 5.0,
        "125": 3.0,
        "250": 3.0,
        "500": 3.0,
        "1000": 3.0,
    },  # §4.2
    "contact_resonance_Hz": {"0.1": 66.0, "1.6": 73.0},  # §4.2, Fig. 12
}


def solved_ends(run) -> tuple[int, int]:
    """Indices of the lowest and highest heights whose solve succeeded (Fig. 12, §4.2)."""
    ok = np.flatnonzero(run["ok"])
    return (int(ok[0]), int(ok[-1])) if ok.size else (0, len(run["ok"]) - 1)


def _rel(value, reference):
    return None if value is None or not np.isfinite(value) else float(value / reference - 1.0)


def _at(runs, heights, name, h):
    """{gas: value of ``name`` at height h} (None where h was not simulated)."""
    idx = np.flatnonzero(np.isclose(heights, h))
    return {gas: (float(run[name][idx[0]]) if idx.size else None) for gas, run in runs.items()}


def comparison_rows(runs, heights) -> list[dict]:
    """Rows of the report: paper value, rbjax gas on/off, relative differences."""

    rows = []

    def add(key, label, source, h, paper, values, unit, scale=1.0, series=None):
        rows.append(
            {
                "key": key,
                "series": series or label,
                "quantity": label,
                "source": source,
                "height_m": h,
                "unit": unit,
                "paper": paper * scale,
                "rbjax": {
                    g: (None if v is None or not np.isfinite(v) else v * scale)
                    for g, v in values.items()
                },
                "relative_difference": {g: _rel(v, paper) for g, v in values.items()},
                "difference": {
                    g: (None if v is None or not np.isfinite(v) else (v - paper) * scale)
                    for g, v in values.items()
                },
            }
        )

    for h, v in PAPER["predicted_contact_time_s"].items():
        add(
            f"contact_time_{h}m",
            f"predicted contact time at {float(h) * 100:.0f} cm",
            "paper's prediction (§4.1)",
            float(h),
            v,
            _at(runs, heights, "contact_time_s", float(h)),
            "ms",
            1e3,
            "contact time vs paper's prediction",
        )
    for h, v in PAPER["peak_force_N"].items():
        add(
            f"peak_force_{h}m",
            f"peak force at {float(h) * 100:.0f} cm",
            "paper, prediction ≈ measurement (§4.1, Fig. 5)",
            float(h),
            v,
            _at(runs, heights, "peak_force_N", float(h)),
            "N",
            series="peak force vs paper",
        )
    for h, v in PAPER["measured_contact_time_s"].items():
        add(
            f"measured_contact_time_{h}m",
            f"measured contact time at {float(h) * 100:.0f} cm",
            "measurement (§4.1)",
            float(h),
            v,
            _at(runs, heights, "contact_time_s", float(h)),
            "ms",
            1e3,
            "contact time vs measurement",
        )
    for j, band in enumerate(OCTAVE_BANDS):
        values = {g: float(run["increase_per_doubling_dB"][j]) for g, run in runs.items()}
        add(
            f"increase_per_doubling_{band}Hz",
            f"L_FE increase per doubling, {band} Hz",
            "paper's prediction (§4.2, Fig. 11)",
            None,
            PAPER["increase_per_doubling_dB"][band],
            values,
            "dB",
        )
    for h, v in PAPER["contact_resonance_Hz"].items():
        add(
            f"contact_resonance_{h}m",
            f"contact resonance at {float(h) * 100:.0f} cm",
            "paper's prediction (§4.2, Fig. 12)",
            float(h),
            v,
            _at(runs, heights, "contact_resonance_Hz", float(h)),
            "Hz",
        )
    return rows


def fnum(x, spec=".1f"):
    return "—" if x is None or not np.isfinite(x) else format(x, spec)


def _pct(x):
    return "—" if x is None or not np.isfinite(x) else f"{100 * x:+.1f} %"


def printed_eq4_limit_m(radius_m: float) -> float:
    """Deflection beyond which the paper's Eq. 4 *as printed* has no real value.

    The printed base 1 − (3 − δ/R)(2δ/R)² of the power γ turns negative where
    4x²(3 − x) = 1, x = δ/R (the smallest positive root).
    """
    roots = np.roots([-4.0, 12.0, 0.0, -1.0])  # 4x²(3 − x) − 1 = −4x³ + 12x² − 1
    x = min(r.real for r in roots if abs(r.imag) < 1e-12 and r.real > 0)
    return float(x * radius_m)


def diff_text(row, gas) -> str:
    """Relative difference in %, or the difference in dB for levels."""
    if row["unit"] == "dB":
        d = row["difference"][gas]
        return "—" if d is None else f"{d:+.2f} dB"
    return _pct(row["relative_difference"][gas])


def explain_comparison(runs, heights, comparison) -> dict[str, str]:
    """One paragraph per compared quantity; every number in it is computed here."""

    ball = JIS_RUBBER_BALL
    on, off = runs["adiabatic"], runs["none"]
    rows = {r["key"]: r for r in comparison}
    text: dict[str, str] = {}
    i1 = int(np.flatnonzero(np.isclose(heights, STANDARD_HEIGHT_M))[0])
    printed_limit = printed_eq4_limit_m(as_float(ball.radius_m))

    def gas_share(run, i):
        d = float(run["max_deflection_m"][i])
        return d, float(gas_force_N(d, ball)), float(shell_force_N(d, ball))

    def closer(row):
        rel = {g: v for g, v in row["relative_difference"].items() if v is not None}
        return GAS[min(rel, key=lambda g: abs(rel[g]))]

    r = rows["contact_time_1.0m"]
    if None in r["rbjax"].values():
        return text  # the solve at the standard height failed: nothing to explain
    d1, fg1, fb1 = gas_share(on, i1)
    between = min(r["rbjax"].values()) <= r["paper"] <= max(r["rbjax"].values())
    text["contact_time_1.0m"] = (
        f"At 1 m the corrected gas force (Eq. 4) reaches F_G = {fg1:.0f} N at maximum compression "
        f"(δ_max = {d1 * 1e3:.1f} mm = {d1 / ball.wall_m:.2f} h), {100 * fg1 / fb1:.1f} % of the "
        f"shell force F_B = {fb1:.0f} N; this stiffening shortens the contact from "
        f"{r['rbjax']['none']:.2f} ms (gas off) to {r['rbjax']['adiabatic']:.2f} ms (gas on). "
        + (
            f"The paper's {r['paper']:.1f} ms lies between the two: its gas force was weaker than "
            "the corrected Eq. 4 (as printed, Eq. 4 has no real value beyond "
            f"δ = {printed_limit * 1e3:.1f} mm). "
            if between
            else f"The paper's {r['paper']:.1f} ms lies outside both. "
        )
        + "The paper took the first sign change of δ on its 44.1 kHz grid (§2.4), which rounds "
        "up by less than one sample (0.023 ms): on that grid rbjax gives "
        f"{on['grid_contact_time_s'][i1] * 1e3:.2f} ms (gas on) and "
        f"{off['grid_contact_time_s'][i1] * 1e3:.2f} ms (gas off), so the grid accounts for at "
        f"most 0.023 ms of the {min(abs(v - r['paper']) for v in r['rbjax'].values()):.2f} ms or "
        "more between rbjax and the paper; rbjax's contact time is the end-of-contact event "
        "located by a root finder."
    )
    for h in PAPER["peak_force_N"]:
        key = f"peak_force_{h}m"
        r = rows.get(key)
        if r is None or r["rbjax"]["adiabatic"] is None or r["rbjax"]["none"] is None:
            continue
        i = int(np.flatnonzero(np.isclose(heights, float(h)))[0])
        d, fg, fb = gas_share(on, i)
        share = fg / (fg + fb)
        head = (
            f"At {float(h) * 100:.0f} cm the peak deflection is {d * 1e3:.1f} mm "
            f"({d / ball.wall_m:.2f} h) and the corrected Eq. 4 adds F_G = {fg:.0f} N "
            f"({100 * share:.1f} % of the peak) to F_B = {fb:.0f} N: gas on gives "
            f"{r['rbjax']['adiabatic']:.0f} N ({_pct(r['relative_difference']['adiabatic'])}), "
            f"gas off {r['rbjax']['none']:.0f} N ({_pct(r['relative_difference']['none'])}). "
        )
        if share < 0.03:
            tail = (
                "The gas force hardly matters at this height; the remaining "
                f"{_pct(r['relative_difference']['adiabatic'])} / "
                f"{_pct(r['relative_difference']['none'])} (gas on / off) is within the precision "
                f"of the paper's '{'roughly' if h == '0.1' else 'about'} {r['paper']:.0f} N', a "
                "value read from text and figure, not a computed number."
            )
        else:
            tail = (
                f"The paper's '{'roughly' if h == '0.1' else 'about'} {r['paper']:.0f} N' is "
                f"closer to rbjax with {closer(r)}: the corrected Eq. 4 grows steeply with δ (the "
                "cavity volume term), while the paper's own gas force must have been much "
                "smaller, as its Fig. 3 and its remark that F_G 'might be negligible' suggest"
                + (
                    f"; the printed Eq. 4 has no real value beyond δ = {printed_limit * 1e3:.1f} "
                    "mm, below this δ_max."
                    if d > printed_limit
                    else "."
                )
            )
        text[key] = head + tail
    meas = [rows[k] for k in rows if k.startswith("measured_contact_time_")]
    meas = [m for m in meas if all(m["rbjax"][g] is not None for g in GAS)]
    if meas:
        over = {g: float(np.mean([m["rbjax"][g] - m["paper"] for m in meas])) for g in GAS}
        listing = ", ".join(
            f"{m['height_m'] * 100:.0f} cm: {m['paper']:.1f} ms vs {m['rbjax']['adiabatic']:.2f} "
            f"/ {m['rbjax']['none']:.2f} ms"
            for m in meas
        )
        text["measured_contact_time"] = (
            f"Measured ({listing}; gas on / gas off): the elastic model is longer by "
            f"{over['adiabatic']:.2f} ms (gas on) and {over['none']:.2f} ms (gas off) on average; "
            "the paper found its own prediction about 1 ms (≈ +6 %) too long. The model has no "
            "material damping and no shell modes, while the measured pulse rises faster: the "
            "real rubber is stiffer and lossier than E = 1.6 MPa with no damping (§4.1)."
        )
    j63 = OCTAVE_BANDS.index("63")
    others = [j for j in range(len(OCTAVE_BANDS)) if j != j63]
    ideal = 10 * math.log10(2)
    slope = {g: runs[g]["increase_per_doubling_dB"] for g in GAS}
    spread = {g: float(np.nanmax(np.abs(slope[g][others] - ideal))) for g in GAS}
    lo, hi = solved_ends(on)  # the lowest and highest heights solved
    res = {
        g: (runs[g]["contact_resonance_Hz"][lo], runs[g]["contact_resonance_Hz"][hi]) for g in GAS
    }
    lo63, hi63 = (float(x[0]) for x in band_edges_Hz(1, 63, 63))
    paper63 = PAPER["increase_per_doubling_dB"]["63"]
    text["increase_per_doubling"] = (
        "If the pulse kept its shape, F ∝ v0 ∝ √h (Eq. 10) and every band would rise by "
        f"10·log10(2) = {ideal:.2f} dB per doubling. In the bands other than 63 Hz rbjax stays "
        f"within {spread['adiabatic']:.2f} dB (gas on) and {spread['none']:.2f} dB (gas off) of "
        f"that (paper: about 3 dB). The 63 Hz band ({lo63:.1f}–{hi63:.1f} Hz) holds the contact "
        "resonance, the first minimum of the spectrum, which moves up as the contact shortens "
        f"({fnum(res['adiabatic'][0])} → {fnum(res['adiabatic'][1])} Hz gas on, "
        f"{fnum(res['none'][0])} → {fnum(res['none'][1])} Hz gas off, {heights[lo] * 100:.0f} → "
        f"{heights[hi] * 100:.0f} cm), so the band gains energy faster: rbjax gives "
        f"{slope['adiabatic'][j63]:.2f} dB (gas on) and {slope['none'][j63]:.2f} dB (gas off) at "
        f"63 Hz against the paper's about {paper63:.0f} dB. "
        + (
            "rbjax reproduces the direction of the 63 Hz excess but not its size; "
            if all(slope[g][j63] > np.nanmax(slope[g][others]) for g in GAS)
            else "rbjax does not reproduce a clear 63 Hz excess; "
        )
        + "the excess depends on where the notch sits relative to the band edges (ideal base-ten "
        "filters on the FFT here; the paper does not specify its band filtering) and on the "
        f"height range of the least-squares fit ({heights[lo] * 100:.0f}–{heights[hi] * 100:.0f} "
        "cm in log2 h), and the paper gives its value only as 'about 5 dB' (§4.2, Fig. 11). We "
        "found no cause within the model for the rest of the difference."
    )
    tc = {g: (runs[g]["contact_time_s"][lo], runs[g]["contact_time_s"][hi]) for g in GAS}
    r160 = rows.get(f"contact_resonance_{list(PAPER['contact_resonance_Hz'])[-1]}m")
    match = (
        f" The paper's shift is closest to rbjax with {closer(r160)}."
        if r160 and all(v is not None for v in r160["rbjax"].values())
        else ""
    )
    text["contact_resonance"] = (
        "The notch sits near 1.5/t_c, the first zero of a half-sine pulse: "
        f"1.5/t_c = {1.5 / tc['adiabatic'][0]:.1f} → {1.5 / tc['adiabatic'][1]:.1f} Hz gas on and "
        f"{1.5 / tc['none'][0]:.1f} → {1.5 / tc['none'][1]:.1f} Hz gas off, against the located "
        f"minima {fnum(res['adiabatic'][0])} → {fnum(res['adiabatic'][1])} Hz and "
        f"{fnum(res['none'][0])} → {fnum(res['none'][1])} Hz. The gas force makes the pulse "
        "peakier than a half-sine at large heights, which moves the notch above 1.5/t_c. The "
        "paper read 66 → 73 Hz from a 1 Hz FFT of its 1 s record; rbjax refines the minimum on a "
        f"0.1 Hz grid.{match}"
    )
    return text

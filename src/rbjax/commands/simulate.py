"""``rbjax simulate``: contact time, peak force, restitution and L_FE bands per drop height."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from . import add_command, add_parallel_options, emit_json, fmt, format_table, parallel_of, progress

if TYPE_CHECKING:
    import numpy as np

#: The floor presets named in --help: rbjax.terms.floors.presets.FLOOR_PRESETS, written out so that
#: --help imports no library (tests/commands/test_cli_startup.py checks they agree).
FLOOR_PRESET_NAMES = (
    "rigid",
    "concrete-140mm",
    "concrete-150mm",
    "concrete-200mm",
    "clt-140mm",
    "steel-10mm",
    "chipboard-22mm",
    "osb-15mm",
    "osb-22mm",
)

DESCRIPTION = """\
Predict the blocked force of the rubber ball dropped on a rigid floor (paper §2, Eq. 7) for
each drop height: contact time, peak force, coefficient of restitution, the force exposure
level L_FE (Eq. 11) in octave bands 31.5-1000 Hz and one-third-octave bands from the
44.1 kHz x 1 s force history (§2.4), and the check against the rubber-ball tolerance table
(JIS A 1418-2 / ISO 10140-5 Annex F) at the standard drop height.

With --floor the ball falls on a floor that moves under it (rbjax.terms.floors.kinds; solved by \
the ODE):
the outputs are those of the force that floor receives, and each JSON row adds "floor" (its
name), "floor_energy_J" (the energy injected into the floor, rbjax.energy_balance) and
"lfe_ratio_dB" (per octave band: L_FE on the floor minus L_FE of the blocked force of the
same ball and model on the rigid floor). --floor takes a preset,
  {presets}
(infinite plates of rbjax.terms.floors.materials, Z = 8 sqrt(B'm''); \
rbjax.terms.floors.presets), or a
.toml/.json floor file (type = "infinite-plate", "dashpot", "modal" or "rigid"; see
rbjax.terms.floors.presets and src/rbjax/examples/floors/).

examples:
  rbjax simulate --height-m 1.0
  rbjax simulate --height-m 0.1 1.0 1.6 --gas none --json
  rbjax simulate --height-m 1.0 --params fit.json --youngs-pa 1.8e6
  rbjax simulate --height-m 1.0 --path ode
  rbjax simulate --height-m 1.0 --floor osb-15mm --json
  rbjax simulate --height-m 1.0 --floor my-floor.toml
"""


def register(subparsers) -> None:
    description = DESCRIPTION.format(presets=", ".join(FLOOR_PRESET_NAMES))
    p = add_command(
        subparsers,
        "simulate",
        help="predict the blocked force for drop heights",
        description=description,
    )
    p.add_argument(
        "--height-m",
        type=float,
        nargs="+",
        required=True,
        metavar="H",
        help="drop height(s) in m (> 0)",
    )
    p.add_argument(
        "--gas",
        choices=("adiabatic", "none"),
        default=None,
        help="gas force F_G (Eq. 4, corrected); default: from --params, else adiabatic",
    )
    p.add_argument(
        "--blocked-force",
        choices=("paper", "momentum"),
        default=None,
        help=(
            "floor force: 'paper' = F_B+F_G, 'momentum' adds the flux (M/2R)δ̇² in compression; "
            "default: from --params, else paper"
        ),
    )
    p.add_argument(
        "--youngs-pa",
        type=float,
        default=None,
        metavar="E",
        help="Young's modulus of the rubber in Pa (default: from --params, else 1.6e6)",
    )
    p.add_argument(
        "--poisson",
        type=float,
        default=None,
        metavar="NU",
        help="Poisson's ratio, -1 < ν <= 0.5 (default: from --params, else 0.5)",
    )
    p.add_argument(
        "--params",
        default=None,
        metavar="FIT.json",
        help="ball and model from a params/fit JSON file (options above override it)",
    )
    p.add_argument(
        "--path",
        choices=(
            "auto",
            "ode",
            "quadrature",
            "angle",
        ),  # rbjax.solve.options.PATHS (not imported: --help stays fast)
        default="auto",
        help=(
            "path of the scalar outputs: 'quadrature' integrates Eq. 7 in δ (undamped models on "
            "the rigid floor, fastest), 'angle' takes fixed steps in the phase angle (any "
            "damping, rigid floor), 'ode' runs the diffrax ODE, 'auto' (default) picks the "
            "fastest the model allows; the JSON rows record the path that ran"
        ),
    )
    p.add_argument(
        "--floor",
        default=None,
        metavar="NAME|FILE",
        help=(
            "the floor under the ball: a preset name (rigid, concrete-150mm, osb-15mm, ...; see "
            "above) or a .toml/.json floor file; default: rigid (the blocked force)"
        ),
    )
    add_parallel_options(p, what=None, device_flags=True)
    p.set_defaults(func=run)


def load_ball_and_model(args):
    """The ball and model from ``--params`` (if given) with the command-line overrides applied."""
    from .. import JIS_RUBBER_BALL, Model

    if args.params is not None:
        from ..terms.serialize import load_params

        try:
            ball, model = load_params(args.params)
        except ValueError as err:
            raise ValueError(f"--params {args.params}: {err}") from err
    else:
        ball, model = JIS_RUBBER_BALL, Model()
    if args.youngs_pa is not None:
        ball = ball.replace(youngs_Pa=args.youngs_pa)
    if args.poisson is not None:
        ball = ball.replace(poisson=args.poisson)
    changes = {}
    floor = getattr(args, "floor", None)  # (commands that reuse this helper may not have --floor)
    if floor is not None:
        from ..terms.floors.presets import load_floor

        changes["floor"] = load_floor(floor)
    if args.gas is not None:
        changes["gas"] = args.gas
    if args.blocked_force is not None:
        changes["blocked_force"] = args.blocked_force
    return ball, (_rebuilt(model, **changes) if changes else model)


def _rebuilt(model, **changes):
    """``model`` with some of its options (gas, blocked_force, floor) replaced (validated)."""
    from .. import Model

    options = dict(
        gas=model.gas,
        damping=model.damping,
        stiffening=model.stiffening,
        max_deflection_ratio=model.max_deflection_ratio,
        floor=model.floor,
        series_elements=model.series_elements,
        layer=model.layer,
        arrest=model.arrest,
    )
    if "blocked_force" not in changes:  # keep the file's weight, fractional ones too
        options["momentum_flux_weight"] = model.momentum_flux_weight
    return Model(**(options | changes))


def _simulate(heights, ball, model, path: str, floor=None, parallel=None):
    """``rbjax.simulate`` of ``model`` (on ``floor`` if given, else on the model's floor)."""
    from ..solve import simulate

    model = model if floor is None else _rebuilt(model, floor=floor)
    return simulate(heights, ball, model, path=path, parallel=parallel)


def _octave_lfe(result):
    """(L_FE total, octave, third-octave) of every impact of ``result`` (NaN if every solve
    failed)."""
    import numpy as np

    from ..solve.inputs import PAPER_RATE_Hz
    from ..spectrum.bands import OCTAVE_BANDS, THIRD_OCTAVE_BANDS
    from ..spectrum.levels import lfe_octave_dB, lfe_third_octave_dB, lfe_total_dB

    n = np.size(result.status)
    total, octave, third = (
        np.full(n, np.nan),
        np.full((n, len(OCTAVE_BANDS)), np.nan),
        np.full((n, len(THIRD_OCTAVE_BANDS)), np.nan),
    )
    if np.any(np.asarray(result.status) == 0):  # no history to integrate when every solve failed
        force = np.asarray(result.force_N).reshape(
            n, -1
        )  # (n, 44100): the paper's 44.1 kHz x 1 s record (§2.4)
        total = np.asarray(lfe_total_dB(force, PAPER_RATE_Hz))
        octave = np.asarray(lfe_octave_dB(force, PAPER_RATE_Hz))
        third = np.asarray(lfe_third_octave_dB(force, PAPER_RATE_Hz))
    return total, octave, third


def floor_outputs(
    heights_m, ball, model, octave_dB, path: str = "auto", parallel=None
) -> tuple[np.ndarray, np.ndarray]:
    """(floor energy in J per height, octave L_FE on the floor less that of the blocked force on
    the rigid floor, per height and band) for a model on a moving floor."""
    import numpy as np

    from ..solve.energy import energy_balance
    from ..terms.floors.kinds import Rigid

    heights = np.asarray(heights_m, dtype=float)
    blocked = _simulate(heights, ball, model, path, floor=Rigid(), parallel=parallel)
    energy = np.asarray(energy_balance(heights, ball, model).floor_energy_J, dtype=float).reshape(
        -1
    )
    return energy, np.asarray(octave_dB) - _octave_lfe(blocked)[1]


def simulate_rows(
    heights_m, ball, model, path: str = "auto", floor_name: str | None = None, parallel=None
) -> list[dict]:
    """One dict per height with the keys of ``rbjax simulate --json`` (NaN where not ok);
    ``path`` and ``parallel`` are ``simulate``'s, and each row's ``"path"`` the path that ran.
    On a floor
    that moves (``model.floor`` not rigid) each row adds ``floor`` (``floor_name``, default the
    floor's type), ``floor_energy_J`` and ``lfe_ratio_dB`` (``floor_outputs``)."""
    import numpy as np

    from ..spectrum.bands import OCTAVE_BANDS, THIRD_OCTAVE_BANDS
    from ..spectrum.standards import check_conformance

    heights = np.asarray(heights_m, dtype=float)
    result = _simulate(heights, ball, model, path, parallel=parallel)
    total, octave, third = _octave_lfe(result)
    moving = not model.floor.rigid
    if moving:
        floor_energy, ratio = floor_outputs(heights, ball, model, octave, path, parallel)
    names = np.atleast_1d(result.status_name)
    rows = []
    for i, h in enumerate(heights):
        ok = names[i] == "ok"
        nan = float("nan")
        row = {
            "height_m": float(h),
            "contact_time_s": float(result.contact_time_s[i]),
            "peak_force_N": float(result.peak_force_N[i]),
            "restitution": float(result.restitution[i]),
            "lfe_total_dB": float(total[i]) if ok else nan,
            "lfe_octave_dB": {
                b: (float(octave[i, j]) if ok else nan) for j, b in enumerate(OCTAVE_BANDS)
            },
            "lfe_third_octave_dB": {
                b: (float(third[i, j]) if ok else nan) for j, b in enumerate(THIRD_OCTAVE_BANDS)
            },
            "conformance": None,
            "status": str(names[i]),
            "path": result.path,
        }
        if moving:
            row["floor"] = floor_name or model.floor.name
            row["floor_energy_J"] = float(floor_energy[i]) if ok else nan
            row["lfe_ratio_dB"] = {
                b: (float(ratio[i, j]) if ok else nan) for j, b in enumerate(OCTAVE_BANDS)
            }
        if ok:
            row["conformance"] = check_conformance(
                octave[i],
                contact_time_s=row["contact_time_s"],
                restitution=row["restitution"],
                mass_kg=float(np.asarray(ball.mass_kg)),
                height_m=float(h),
            ).to_dict()
        rows.append(row)
    return rows


def _verdict(conformance) -> str:
    """pass/FAIL against the table; n/a off the standard drop height (1.00 ± 0.01 m)."""
    if conformance is None:
        return "—"
    if any(i["name"] == "drop height" and not i["passed"] for i in conformance["items"]):
        return "n/a"
    return "pass" if conformance["passed"] else "FAIL"


def _failures(rows) -> list[str]:
    lines = []
    for r in rows:
        if _verdict(r["conformance"]) == "FAIL":
            bad = [
                f"{i['name']} {i['value']:.4g} not in [{i['lower']:g}, {i['upper']:g}] {i['unit']}"
                for i in r["conformance"]["items"]
                if not i["passed"]
            ]
            lines.append(f"  {r['height_m']:g} m: " + "; ".join(bad))
    return lines


def _floor_notes(rows: list[dict]) -> list[str]:
    """On a moving floor: the floor's name, the energy it took and the L_FE ratios per height."""
    from ..spectrum.bands import OCTAVE_BANDS

    if not rows or "floor" not in rows[0]:
        return []
    lines = [
        f"floor {rows[0]['floor']}: the force is the force this floor receives; "
        "E_floor: energy injected into the floor;",
        "ΔL_FE: L_FE on this floor minus L_FE of the blocked force (rigid floor), "
        "per octave band (Hz):",
    ]
    for r in rows:
        bands = ", ".join(f"{b} {fmt(r['lfe_ratio_dB'][b], '+.2f')}" for b in OCTAVE_BANDS)
        lines.append(
            f"  {r['height_m']:g} m: E_floor {fmt(r['floor_energy_J'], '.3g')} J; ΔL_FE {bands} dB"
        )
    return lines


def render_table(rows: list[dict]) -> str:
    from ..spectrum.bands import OCTAVE_BANDS

    header = [
        "height m",
        "t_c ms",
        "F_peak N",
        "e",
        "L_FE dB",
        *(f"{b} Hz" for b in OCTAVE_BANDS),
        "conformance",
        "status",
    ]
    body = []
    for r in rows:
        body.append(
            [
                fmt(r["height_m"], ".2f"),
                fmt(r["contact_time_s"] * 1e3 if r["contact_time_s"] is not None else None, ".2f"),
                fmt(r["peak_force_N"], ".0f"),
                fmt(r["restitution"], ".3f"),
                fmt(r["lfe_total_dB"], ".1f"),
                *(fmt(r["lfe_octave_dB"][b], ".1f") for b in OCTAVE_BANDS),
                _verdict(r["conformance"]),
                r["status"],
            ]
        )
    notes = [
        "t_c: contact time; F_peak: peak blocked force; e: coefficient of restitution;",
        "L_FE: force exposure level (paper Eq. 11), dB re 1 N, T0 = 1 s: "
        "total and per octave band (Hz).",
        "conformance: rubber-ball table (ISO 10140-5 Table F.1 = JIS A 1418-2 Table A.2), "
        "only at the",
        "standard drop height 1.00 ± 0.01 m (n/a elsewhere).",
    ]
    notes += _floor_notes(rows)
    failures = _failures(rows)
    if failures:
        notes += ["outside the tolerances:", *failures]
    return format_table(header, body) + "\n\n" + "\n".join(notes)


def run(args) -> int:
    parallel = parallel_of(args)  # one JAX CPU device per core: the heights split over them
    for i, h in enumerate(args.height_m):  # before any output, so bad input gives one line
        if not (math.isfinite(h) and h > 0.0):
            raise ValueError(
                f"height_m={h!r} (--height-m value {i + 1}) "
                "is outside the valid range (0, inf) and finite"
            )
    ball, model = load_ball_and_model(args)
    floor_name = None
    if args.floor is not None:
        from ..terms.floors.presets import load_named_floor

        floor_name = load_named_floor(args.floor)[0]
    on = "" if model.floor.rigid else f", floor {floor_name}"
    progress(
        f"simulating {len(args.height_m)} drop height(s), model {model.name}, gas {model.gas}{on}"
    )
    rows = simulate_rows(
        args.height_m, ball, model, path=args.path, floor_name=floor_name, parallel=parallel
    )
    if args.json:
        emit_json(rows)
    else:
        print(render_table(rows))
    return 0

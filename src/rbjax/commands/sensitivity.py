"""``rbjax sensitivity``: local derivatives and elasticities of the impact outputs per drop
height."""

from __future__ import annotations

from . import add_command, emit_json, fmt, format_table, progress, use_cpu_devices

DESCRIPTION = """\
Local sensitivity of the rubber-ball impact (paper §2, Eq. 7) by forward-mode automatic
differentiation through the ODE solver and its events: the derivatives of the contact time,
peak force, restitution coefficient and the octave-band force exposure levels L_FE 31.5 Hz -
1 kHz (Eq. 11, from the 44.1 kHz x 1 s history, §2.4) with respect to the drop height, the
ball parameters and the damping parameters (from --params), and the elasticities
(% change of the output per % change of the parameter; for L_FE, of the band energy).

Parameter names (any case): height_m radius_m wall_m mass_kg youngs_pa poisson, and the
damping fields of a --params model (damping_ns_per_m, alpha_s_per_m, stiffness_ratio,
relaxation_time_s) and beta with stiffening.

examples:
  rbjax sensitivity --height-m 1.0
  rbjax sensitivity --height-m 0.5 1.0 1.6 --wrt youngs_pa poisson mass_kg --json
  rbjax sensitivity --height-m 1.0 --params fit.json --plot tornado.png
"""


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "sensitivity",
        help="local derivatives and elasticities of the impact outputs",
        description=DESCRIPTION,
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
        "--wrt",
        nargs="+",
        default=None,
        metavar="NAME",
        help="parameters to differentiate against (default: all)",
    )
    p.add_argument(
        "--gas",
        choices=("adiabatic", "none"),
        default=None,
        help="gas force F_G (Eq. 4, corrected); default adiabatic",
    )
    p.add_argument(
        "--blocked-force",
        choices=("paper", "momentum"),
        default=None,
        help="floor force definition; default paper",
    )
    p.add_argument(
        "--youngs-pa",
        type=float,
        default=None,
        metavar="E",
        help="Young's modulus of the rubber in Pa (default 1.6e6)",
    )
    p.add_argument(
        "--poisson",
        type=float,
        default=None,
        metavar="NU",
        help="Poisson's ratio, -1 < ν <= 0.5 (default 0.5)",
    )
    p.add_argument(
        "--params",
        default=None,
        metavar="FIT.json",
        help="ball and model (with damping) from a params/fit JSON file",
    )
    p.add_argument(
        "--no-lfe", action="store_true", help="skip the L_FE bands (faster: no force history)"
    )
    p.add_argument(
        "--plot",
        default=None,
        metavar="FILE.png",
        help="save a tornado chart of the elasticities at the first height",
    )
    p.set_defaults(func=run)


def render_table(rows: list[dict]) -> str:
    blocks = []
    for row in rows:
        outputs = list(row["values"])
        header = ["parameter", "value", *outputs]
        body = [
            [
                p,
                fmt(row["parameters"][p], ".4g"),
                *(fmt(row["elasticity"][o][p], "+.3f") for o in outputs),
            ]
            for p in row["parameters"]
        ]
        values = ["output value", "", *(fmt(row["values"][o], ".4g") for o in outputs)]
        title = (
            f"drop height {row['height_m']:g} m ({row['status']}): elasticity, % per % "
            "(L_FE: of the band energy)"
        )
        blocks.append(title + "\n" + format_table(header, [values, *body]))
    return "\n\n".join(blocks)


def run(args) -> int:
    use_cpu_devices()  # one JAX CPU device per core: forward batches split over them
    import numpy as np

    from .._validate import check_range
    from ..solve.batch import canonical_name
    from ..studies.sensitivity import local_sensitivity
    from ..terms.parameters import parameter_names
    from .simulate import load_ball_and_model

    check_range("height_m", np.asarray(args.height_m), lower=0.0)
    ball, model = load_ball_and_model(args)
    wrt = None
    if args.wrt is not None:
        wrt = [canonical_name(w, model) for w in args.wrt]  # unknown names fail before any solve
    progress(
        f"differentiating at {len(args.height_m)} drop height(s) w.r.t. "
        f"{', '.join(wrt or parameter_names(model=model))}"
    )
    result = local_sensitivity(
        args.height_m,
        ball,
        wrt=wrt,
        model=model,
        lfe=not args.no_lfe,
    )
    rows = result.to_dict()
    if args.plot:
        result.plot(0).savefig(args.plot, dpi=150)
        progress(f"tornado chart written to {args.plot}")
    if args.json:
        emit_json(rows)
    else:
        print(render_table(rows))
    return 0

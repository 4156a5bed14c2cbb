"""``rbjax design``: the rubber that sits deepest inside the standard's tolerances."""

from __future__ import annotations

from pathlib import Path

from . import add_command, emit_json, progress, use_cpu_devices, write_json_file

DESCRIPTION = """\
Find the parameters of a model (E with ν held at 0.5, the parameters of its terms; with
--vary-wall also the wall thickness, the mass following it) that maximise the smallest margin
to the rubber-ball table at 1 m (ISO 16283-2 Table A.1 = ISO 10140-5 Table F.1 = JIS A 1418-2
Table A.2): L_FE in the octave bands 31.5-500 Hz, contact time 20 ± 2 ms, restitution
0.8 ± 0.1, mass 2.5 ± 0.1 kg. Margins are compared in units of each tolerance's half-width;
a smooth minimum of them is maximised by Adam (optax) with exact gradients from several
starts. The margins are recomputed by `rbjax simulate` and the tolerance check at the design.
Where no parameter set conforms, it says so with the best margin and the item that blocks it.

models: every model `rbjax fit` takes: paper (elastic, §2), kelvin-voigt, hunt-crossley,
zener, each optionally +stiffening, then +contact-layer (a nonlinear layer F = K y^p in series
with the shell) and/or +arrest (the wall column's arrest, with --blocked-force paper), then
+ball-mode (one mode of the ball in series with the shell) and/or +series-kelvin-voigt (its
overdamped, massless limit), in this order; e.g. hunt-crossley+ball-mode. The searched
parameters are the fit's (those of --fix in `rbjax fit --help`, with ν held at 0.5). Models
without a suffix after +stiffening run on the fast exact paths; +contact-layer and +arrest
(which the fast paths do not solve) and the coupled +ball-mode and +series-kelvin-voigt run on
the ODE, slower to compile and to step: the progress lines say so.

geometries: jis (R = 89 mm, h = 32 mm, the paper's §4), iso (ISO 10140-5 Annex F's
informative ball: 180 mm outer diameter, 30 mm wall); both 2.5 kg.

output (--out DIR): per design a parameter file design_<model>_<geometry>.json (its "ball" and
"model" as a fit's, then the margins and the verdict) and the margin plot
design_<model>_<geometry>.png; design.json lists every design under "designs" and, with one
geometry, is that design's parameter file too (as is the --json output). Predict with it:
`rbjax simulate --params DIR/design.json --height-m 1.0`; with --geometry both pass
DIR/design_<model>_jis.json or DIR/design_<model>_iso.json.

examples:
  rbjax design --model kelvin-voigt --out design/
  rbjax simulate --params design/design.json --height-m 0.5
  rbjax design --model hunt-crossley+ball-mode --blocked-force momentum
  rbjax design --model zener --geometry iso --starts 16 --out design/ --json
"""


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "design",
        help="design a ball to the middle of the standard's tolerances",
        description=DESCRIPTION,
    )
    p.add_argument(
        "--model",
        default="kelvin-voigt",
        metavar="NAME",
        help="any model of `rbjax fit` (see above); default kelvin-voigt",
    )
    p.add_argument(
        "--blocked-force",
        choices=("paper", "momentum"),
        default="paper",
        help=(
            "floor force: 'paper' = F_B+F_G(+F_d), 'momentum' adds the flux (M/2R)δ̇² in "
            "compression; default paper (+arrest: paper only, the law is its own flux)"
        ),
    )
    p.add_argument("--geometry", choices=("jis", "iso", "both"), default="jis", help="default jis")
    p.add_argument("--starts", type=int, default=8, metavar="N", help="starts (default 8)")
    p.add_argument("--steps", type=int, default=150, metavar="N", help="Adam steps (default 150)")
    p.add_argument(
        "--vary-wall",
        action="store_true",
        help="also vary the wall thickness (20-45 mm), the mass following it",
    )
    p.add_argument(
        "--gas",
        choices=("adiabatic", "none"),
        default="adiabatic",
        help="gas force F_G (Eq. 4, corrected); default adiabatic",
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help=(
            "write design.json, a parameter file and a margin plot per design "
            "(design_<model>_<geometry>.json, .png) into DIR"
        ),
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=run)


def run(args) -> int:
    use_cpu_devices()  # one JAX CPU device per core: forward batches split over them
    from ..studies.design import DesignSearch, design

    geometries = ("jis", "iso") if args.geometry == "both" else (args.geometry,)
    results = [
        design(
            args.model,
            g,
            search=DesignSearch(n_starts=args.starts, steps=args.steps),
            vary_wall=args.vary_wall,
            gas=args.gas,
            blocked_force=args.blocked_force,
            progress=not args.quiet,
        )
        for g in geometries
    ]
    designs = [r.to_dict() for r in results]
    # one design: design.json (and --json) is its parameter file too (`rbjax simulate --params`)
    out = {**designs[0], "designs": designs} if len(designs) == 1 else {"designs": designs}
    if args.out is not None:
        for r, d in zip(results, designs):
            progress(f"wrote {r.plot(Path(args.out))}")
            name = f"design_{r.model_name}_{r.geometry}.json"
            progress(f"wrote {write_json_file(args.out, name, d)}")
        progress(f"wrote {write_json_file(args.out, 'design.json', out)}")
    if args.json:
        emit_json(out)
    else:
        print("\n\n".join(r.table() for r in results))
    return 0

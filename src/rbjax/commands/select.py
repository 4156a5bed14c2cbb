"""``rbjax select``: which impact model do the force histories support? (cross-validation)"""

from __future__ import annotations

from . import add_command, add_parallel_options, emit_json, parallel_of, progress, write_json_file
from .fit import add_data_options, add_race_options, load_fit_data, race_of

DESCRIPTION = """\
Fit every candidate model (damping: paper = elastic, kelvin-voigt, hunt-crossley, zener;
blocked force: paper and momentum) to all drop heights, refit each without one height at a
time and predict it (leave-one-height-out cross-validation), and recommend the smallest
model whose held-out error is within the noise of the best (paired one-standard-error
rule). The table gives the held-out history error (% of peak), contact time, peak force and
octave-band L_FE errors, and AIC/BIC; the unfitted paper model (E = 1.6 MPa) is the
baseline. The selection races: after the full fits the folds run in rounds, and a
candidate that every contender beats at every height (its held-out error, or its full fit's
in-sample error, a lower bound, where the fold has not run) is dropped with its remaining
folds; the recommendation is that of --exhaustive (every fold of every candidate). Any model
name of
`rbjax fit` is a candidate, e.g. hunt-crossley+ball-mode (a mode of the ball in series with
the shell; the other candidates then run with it held off, μ = 0, in the same program) or
hunt-crossley+series-kelvin-voigt (its massless limit, held off at C = 0).

examples:
  rbjax select recordings/
  rbjax select recordings/ --candidates paper,hunt-crossley --blocked-force momentum
  rbjax select recordings/ --candidates hunt-crossley,hunt-crossley+ball-mode \
--blocked-force momentum
  rbjax select recordings/ --hold-out 0.2,0.8 --json > selection.json
  rbjax select recordings/ --exhaustive          # every fold: the full table
"""


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "select",
        help="choose the impact model by cross-validation over drop heights",
        description=DESCRIPTION,
    )
    add_data_options(p)
    add_parallel_options(p, fit_flags=True)
    add_race_options(p)
    p.add_argument(
        "--candidates",
        default=None,
        metavar="NAMES",
        help=(
            "comma-separated model names (suffixes +stiffening, +ball-mode, "
            "+series-kelvin-voigt), each optionally NAME/paper or NAME/momentum "
            "(default: paper,kelvin-voigt,hunt-crossley,zener,hunt-crossley+ball-mode,"
            "hunt-crossley+series-kelvin-voigt)"
        ),
    )
    p.add_argument(
        "--blocked-force",
        choices=("paper", "momentum", "both"),
        default="both",
        help="blocked-force definitions to compare (default both)",
    )
    p.add_argument(
        "--hold-out",
        default=None,
        metavar="HEIGHTS",
        help=(
            "also fit without these heights (comma-separated, m) and tabulate the errors "
            "predicting them"
        ),
    )
    p.add_argument("--out", default=None, metavar="DIR", help="write selection.json into DIR")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=run)


def _parse_candidates(text, forces):
    from ..fit import MODEL_NAMES
    from ..studies.selection.candidates import candidate_pairs

    if text is None:
        return MODEL_NAMES
    names = tuple(t.strip() for t in text.split(",") if t.strip())
    if not names:
        raise ValueError("--candidates: give at least one model name")
    try:
        candidate_pairs(names, forces)
    except ValueError as err:
        raise ValueError(f"--candidates: {err}") from None
    return names


def _parse_heights(text):
    if text is None:
        return None
    try:
        heights = [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise ValueError(
            f"--hold-out {text!r}: expected comma-separated heights in m, e.g. 0.2,0.8"
        ) from None
    if not heights or any(not h > 0 for h in heights):
        raise ValueError(f"--hold-out {text!r}: heights must be positive (m)")
    return heights


def run(args) -> int:
    from ..studies.parallel.executors import prestart
    from ..studies.parallel.worker_pool import single_threaded_blas

    single_threaded_blas()  # the fit's host-side linear algebra: small matrices
    from ..studies.selection.hold_out_comparison import held_out_comparison
    from ..studies.selection.select import select_model
    from ..terms.model import BLOCKED_FORCE_OPTIONS

    forces = BLOCKED_FORCE_OPTIONS if args.blocked_force == "both" else (args.blocked_force,)
    candidates = _parse_candidates(args.candidates, forces)
    held = _parse_heights(args.hold_out)
    exhaustive, race = race_of(args)
    parallel = parallel_of(args)
    prestart(parallel)  # the workers import rbjax while the files are read
    data = load_fit_data(args)
    if held is not None:
        import numpy as np

        missing = [h for h in held if not np.any(np.isclose(data.heights_m, h, atol=5e-4))]
        if missing:
            raise ValueError(
                f"--hold-out: no record at {', '.join(f'{h:g}' for h in missing)} m; heights: "
                f"{', '.join(f'{h:g}' for h in data.heights_m)}"
            )
    selection = select_model(
        data,
        candidates,
        blocked_forces=forces,
        parallel=parallel,
        gas=args.gas,
        progress=not args.quiet,
        exhaustive=exhaustive,
        race=race,
    )
    comparison = None
    if held is not None:
        import numpy as np

        keep = [h for h in data.heights_m if not np.any(np.isclose(held, h, atol=5e-4))]
        starts = {(c.model_name, c.blocked_force): c.fit for c in selection.candidates}
        comparison = held_out_comparison(
            data,
            keep,
            candidates,
            blocked_forces=forces,
            starts=starts,
            parallel=parallel,
            gas=args.gas,
            progress=not args.quiet,
        )
    out = {"selection": selection.to_dict()}
    if comparison is not None:
        out["held_out"] = comparison.to_dict()
    if args.out is not None:
        progress(f"wrote {write_json_file(args.out, 'selection.json', out)}")
    if args.json:
        emit_json(out)
    else:
        print(selection.table())
        if comparison is not None:
            print()
            print(comparison.table())
    return 0

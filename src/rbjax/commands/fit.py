"""``rbjax fit``: fit the rubber's properties (and a damping model) to measured force histories."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from . import add_command, add_parallel_options, parallel_of, progress
from ._fit_output import finish

DESCRIPTION = """\
Fit Young's modulus E (with ν held at 0.5: only E/√(1−ν²) is identifiable, paper Eqs. 1–3)
and the parameters of a damping model to force histories of drops from several heights,
through the measuring chain (causal 4th-order low-pass) as the data went through it.
Without --model every candidate is fitted and cross-validated over the heights (as
`rbjax select`: a race that drops a candidate once every contender beats it at every height;
--exhaustive runs every fold) and the recommended one is kept.

models: paper (elastic, §2), kelvin-voigt, hunt-crossley, zener, each optionally
+stiffening and then +ball-mode (one mode of the ball in series with the shell, the
ringing of measured pulses; e.g. hunt-crossley+ball-mode) or +series-kelvin-voigt (its
overdamped, massless limit: a spring and a damper in series with the shell). Parameters for --fix:
youngs_Pa, poisson, damping_Ns_per_m (kelvin-voigt), alpha_s_per_m (hunt-crossley),
stiffness_ratio and relaxation_time_s (zener), beta (+stiffening), mode_mass_ratio,
mode_frequency_Hz, mode_loss_factor (+ball-mode), series_compliance_m_per_N,
series_time_constant_s (+series-kelvin-voigt), and the ball's radius_m, wall_m, mass_kg.

examples:
  rbjax fit recordings/ --model hunt-crossley --blocked-force momentum
  rbjax fit h*.csv --model zener --fix poisson=0.49 --json > fit.json
  rbjax fit recordings/ --model hunt-crossley+ball-mode --blocked-force momentum
  rbjax simulate --height-m 1.0 --params fit.json

summary figures instead of histories (--summary TABLE: contact time, peak force,
restitution, L_FE per band, per drop height; see `rbjax.fit.summary_table`):
  rbjax fit --summary src/rbjax/examples/paper-measured-ball/summary.csv --model paper
  rbjax fit --summary certificate.toml            # models compared by held-out figures
"""


def add_data_options(p: argparse.ArgumentParser, paths: str = "+") -> None:
    """Options shared by ``fit`` and ``select`` for reading and conditioning the recordings."""
    p.add_argument(
        "paths",
        nargs=paths,
        metavar="FILES_OR_DIR",
        help="recordings (*.csv, *.wav, *.npy, *.mat, *.uff, *.unv, *.tdms) or directories of them",
    )
    p.add_argument(
        "--lowpass-hz",
        default="auto",
        metavar="HZ",
        help=(
            "cutoff of the measuring chain's causal 4th-order Butterworth low-pass, applied to "
            "the predictions too; 'none' for no filter; default 'auto' (as the recordings "
            "declare; 1250 Hz for the shipped emulated recordings)"
        ),
    )
    p.add_argument(
        "--all-drops",
        action="store_true",
        help="fit every drop as its own record (default: the frequency-domain average per height)",
    )
    p.add_argument(
        "--gas",
        choices=("adiabatic", "none"),
        default="adiabatic",
        help="gas force F_G (Eq. 4, corrected); default adiabatic",
    )
    p.add_argument(
        "--strict",
        action="store_true",
        help=(
            "refuse a clipped recording (default: leave it out, fit the others and say so in the "
            "report)"
        ),
    )


def add_race_options(p: argparse.ArgumentParser) -> None:
    """Options shared by ``fit`` (without ``--model``) and ``select``: how the model selection
    races (:mod:`rbjax.studies.selection.race`) or runs every fold."""
    p.add_argument(
        "--exhaustive",
        action="store_true",
        help=(
            "run every fold of every candidate (the full table); default: race, dropping a "
            "candidate once every contender beats it at every height (the same recommendation)"
        ),
    )
    p.add_argument(
        "--race-margin",
        type=float,
        default=None,
        metavar="X",
        help=(
            "how far (relatively, >= 0) a candidate's in-sample error at a height whose fold has "
            "not run must exceed a contender's held-out error to count as beaten (default 0.6)"
        ),
    )


def race_of(args):
    """``(exhaustive, race)`` for :func:`~rbjax.studies.selection.select.select_model` from
    ``--exhaustive`` and ``--race-margin`` (named errors: a bad margin, or both given)."""
    from ..studies.selection.race import Race

    if args.race_margin is None:
        return bool(args.exhaustive), None
    if args.exhaustive:
        raise ValueError(
            "--race-margin applies to the race and --exhaustive runs every fold: give one or "
            "the other"
        )
    try:
        return False, Race(margin=args.race_margin)
    except ValueError as err:
        raise ValueError(f"--race-margin {args.race_margin!r}: {err}") from None


def parse_lowpass(value: str):
    if value == "auto":
        return "auto"
    if value.lower() == "none":
        return None
    try:
        cutoff = float(value)
    except ValueError:
        raise ValueError(f"--lowpass-hz={value!r}: give a cutoff in Hz, 'none' or 'auto'") from None
    if not cutoff > 0:
        raise ValueError(f"--lowpass-hz={value!r} must be positive (valid range: (0, inf))")
    return cutoff


def parse_fix(items) -> dict:
    out = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ValueError(f"--fix {item!r}: expected NAME=VALUE, e.g. poisson=0.49")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ValueError(f"--fix {item!r}: {value!r} is not a number") from None
    return out


def load_fit_data(args):
    """Read and condition the recordings named on the command line (warnings as stderr lines)."""
    from ..fit import load_data, prepare_data

    lowpass = parse_lowpass(args.lowpass_hz)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        recs = load_data([Path(p) for p in args.paths], lowpass_Hz=lowpass, strict=args.strict)
        data = prepare_data(recs, average=not args.all_drops)
    for w in caught:
        progress(f"warning: {w.message}")
    for e in data.excluded:
        progress(f"excluded {e['source']}: {e['reason']}")
    chain = f"{data.lowpass_Hz:g} Hz low-pass" if data.lowpass_Hz else "no low-pass"
    progress(
        f"{len(recs)} recordings, {data.n_records} records at "
        f"{', '.join(f'{h:g}' for h in data.heights_m)} m ({chain})"
    )
    return data


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "fit",
        help="fit E and a damping model to measured force histories",
        description=DESCRIPTION,
    )
    add_data_options(p, paths="*")
    add_parallel_options(p, what="fits of the model selection (without --model)", fit_flags=True)
    add_race_options(p)
    p.add_argument(
        "--summary",
        default=None,
        metavar="TABLE",
        help=(
            "fit to a table of summary figures per drop height (.csv or .toml) instead of "
            "recordings"
        ),
    )
    p.add_argument(
        "--model",
        default=None,
        metavar="NAME",
        help=(
            "paper, kelvin-voigt, hunt-crossley, zener (+stiffening) (+ball-mode or "
            "+series-kelvin-voigt); default: choose by cross-validation"
        ),
    )
    p.add_argument(
        "--blocked-force",
        choices=("paper", "momentum"),
        default=None,
        help=(
            "floor force definition (paper: F_B+F_G+F_d; momentum: adds (M/2R)δ̇² in "
            "compression); default paper with --model, both compared without"
        ),
    )
    p.add_argument(
        "--fix",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="hold a parameter at a value (repeatable)",
    )
    p.add_argument(
        "--optimizer",
        choices=("lm", "gauss-newton"),
        default="lm",
        help="default lm (optimistix Levenberg–Marquardt)",
    )
    p.add_argument(
        "--path",
        choices=("auto", "samples", "ode"),
        default="auto",
        help=(
            "the prediction: samples (the force at the records' own samples by fixed steps; "
            "auto's choice) or ode (the diffrax ODE with its events, the reference)"
        ),
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="write fit.json and plots (histories, L_FE bands, correlations) into DIR",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=run)


def _check_model_and_fix(model, fix):
    from ..fit.layout import CONSTANT_PARAMETERS, fitted_parameter_names, model_from_name
    from ..fit.setup import validate_fix

    geometry = set(CONSTANT_PARAMETERS[:3])
    if model is not None:
        # raises on an unknown model or parameter
        validate_fix(set(fitted_parameter_names(model_from_name(model))) | geometry, fix)
        return
    common = {"youngs_Pa", "poisson", *geometry}
    extra = sorted(set(fix) - common)
    if extra:
        raise ValueError(
            f"--fix {', '.join(extra)}: without --model only parameters every candidate has can "
            f"be fixed ({', '.join(sorted(common))}); give --model"
        )
    validate_fix(common, fix)


def run(args) -> int:
    from ..studies.parallel.executors import prestart
    from ..studies.parallel.worker_pool import single_threaded_blas

    single_threaded_blas()  # the fit's host-side linear algebra: small matrices
    from ..fit import FitOptions, fit

    if args.summary is not None or not args.paths:
        from ._summary_fit import run_summary

        return run_summary(args, parse_fix(args.fix))
    fix = parse_fix(args.fix)
    _check_model_and_fix(args.model, fix)
    parallel = parallel_of(args) if args.model is None else None
    exhaustive, race = race_of(args)
    if parallel is not None:
        prestart(parallel)  # the workers import rbjax while the files are read
    data = load_fit_data(args)
    options = FitOptions(optimizer=args.optimizer, path=args.path)
    selection = None
    if args.model is None:
        from ..studies.selection.select import select_model
        from ..terms.model import BLOCKED_FORCE_OPTIONS

        forces = BLOCKED_FORCE_OPTIONS if args.blocked_force is None else (args.blocked_force,)
        progress(
            "no --model: choosing one by leave-one-height-out cross-validation (see `rbjax select`)"
        )
        selection = select_model(
            data,
            blocked_forces=forces,
            gas=args.gas,
            fix=fix,
            options=options,
            parallel=parallel,
            progress=not args.quiet,
            exhaustive=exhaustive,
            race=race,
        )
        result = selection.recommended.fit
        progress(f"recommended: {selection.recommended.label}")
    else:
        result = fit(
            data,
            args.model,
            blocked_force=args.blocked_force or "paper",
            gas=args.gas,
            fix=fix,
            options=options,
            progress=not args.quiet,
        )
    extra = {"conditioning": list(data.conditioning), "excluded": list(data.excluded)}
    return finish(args, result, selection, extra=extra, after=data.conditioning_report())

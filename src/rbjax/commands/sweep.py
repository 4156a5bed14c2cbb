"""``rbjax sweep CONFIG.toml``: global sensitivity (SALib: Sobol, Morris, eFAST, PAWN, DGSM) and
conformance probability."""

from __future__ import annotations

from . import add_command, emit_json, progress, use_cpu_devices

DESCRIPTION = """\
Run a batched study of the rubber-ball impact described by a TOML file: a SALib design,
evaluated on the fastest exact path the model allows and sharded over all JAX devices (on a
CPU: one device per core, see --cpu-devices; or GPUs), analysed by SALib:

  kind = "sobol"        Sobol first-, total- (and second-) order indices on a Sobol'-sequence
                        design, with bootstrap intervals
  kind = "morris"       Morris elementary-effect screening
  kind = "fast"         extended FAST first- and total-order indices
  kind = "pawn"         PAWN moment-independent indices
  kind = "dgsm"         derivative-based measures from exact gradients beside SALib's finite
                        differences, and the total-index upper bound
  kind = "conformance"  Monte Carlo probability of meeting the rubber-ball tolerances
                        (ISO 16283-2 Table A.1 = ISO 10140-5 Table F.1 = JIS A 1418-2 Table A.2)

The format is described in the rbjax.studies.sweep module docstring; examples are shipped in
rbjax/examples/sweeps/. A progress bar goes to stderr. With --out FILE.json the summary is
written as JSON (plain text, readable anywhere) and every evaluated sample beside it as
FILE.samples.npz (compact float64 arrays with their names, numpy.load).

examples:
  rbjax sweep src/rbjax/examples/sweeps/sobol.toml --out sobol.json
  rbjax sweep conformance.toml --json
"""


def register(subparsers) -> None:
    p = add_command(
        subparsers,
        "sweep",
        help="global sensitivity and conformance probability from a TOML config",
        description=DESCRIPTION,
    )
    p.add_argument("config", metavar="CONFIG.toml", help="the study to run")
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE.json",
        help="write the summary (JSON) and the samples (FILE.samples.npz)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--distributed",
        action="store_true",
        help="multi-host run: call jax.distributed.initialize() first (SLURM/Open MPI/TPU detected); "
        "start the same command on every host; process 0 writes the output",
    )
    p.add_argument(
        "--cpu-devices",
        type=int,
        default=None,
        metavar="N",
        help="JAX CPU devices to shard over (default: one per core; each runs its share of the batch on one core)",
    )
    p.set_defaults(func=run)


def run(args) -> int:
    import time

    import jax

    from ..studies.sweep import load_config, run_sweep, write_outputs

    use_cpu_devices(args.cpu_devices)
    if args.distributed:
        jax.distributed.initialize()
    config = load_config(args.config)
    progress(f"running {config.get('kind')!r} sweep from {args.config}")
    start = time.perf_counter()
    result = run_sweep(config, progress=not args.no_progress)
    seconds = time.perf_counter() - start
    evaluations = result.n_evaluations if hasattr(result, "n_evaluations") else result.n_samples
    progress(
        f"{evaluations} impact evaluations in {seconds:.1f} s ({evaluations / seconds:.0f} per s)"
    )
    if jax.process_index() != 0:
        return 0
    if args.out:
        for path in write_outputs(result, args.out, config):
            progress(f"wrote {path}")
    if args.json:
        emit_json({"config": config, **result.to_dict()})
    else:
        print(result.table())
    return 0

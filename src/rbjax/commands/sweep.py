"""``rbjax sweep CONFIG.toml``: global sensitivity (SALib: Sobol, Morris, eFAST, PAWN, DGSM) and
conformance probability; in this process, on local worker processes, on a Dask cluster, or in
parts for a job array (``--shard I/P``, then ``--merge``)."""

from __future__ import annotations

import sys

from . import add_command, add_parallel_options, emit_json, parallel_of, progress

DESCRIPTION = """\
Run a batched study of the rubber-ball impact described by a TOML file: a SALib design,
evaluated on the fastest exact path the model allows, analysed by SALib:

  kind = "sobol"        Sobol first-, total- (and second-) order indices on a Sobol'-sequence
                        design, with bootstrap intervals
  kind = "morris"       Morris elementary-effect screening
  kind = "fast"         extended FAST first- and total-order indices
  kind = "pawn"         PAWN moment-independent indices
  kind = "dgsm"         derivative-based measures from exact gradients beside SALib's finite
                        differences, and the total-index upper bound
  kind = "conformance"  Monte Carlo probability of meeting the rubber-ball tolerances
                        (ISO 16283-2 Table A.1 = ISO 10140-5 Table F.1 = JIS A 1418-2 Table A.2)

The format is described in the rbjax.studies.sweeps.sweep module docstring; examples are shipped in
rbjax/examples/sweeps/. A progress bar goes to stderr. With --out FILE.json the summary is
written as JSON (plain text, readable anywhere) and every evaluated sample beside it as
FILE.samples.npz (compact float64 arrays with their names, numpy.load).

Where the impacts run (the flags are the fields of rbjax.Parallel): by default (--workers 1), in
this process, split over its JAX devices (one CPU device per core, --devices N) in chunks of
--chunk-size impacts (default: the config's chunk_size, else sized per solve path); with
--workers N, the design is cut into chunks run
by N worker processes (one JAX CPU device each); with --scheduler
ADDRESS, the chunks run on a Dask distributed cluster (pip install 'rbjax[cluster]'; on
SLURM, PBS, SGE or LSF, dask-jobqueue starts one:
  from dask_jobqueue import SLURMCluster
  cluster = SLURMCluster(cores=8, processes=8, memory="16GB"); cluster.scale(jobs=4)
  then --scheduler cluster.scheduler_address). The chunks' outputs are joined here and
analysed; a failed chunk is reported with its rows, and nothing is written.

A job array without a scheduler: --shard I/P evaluates part I of P of the design (rows cut
deterministically) and writes it (--out, default CONFIG.part-I-of-P.npz) with the digest of
the design; --merge PART... joins all P parts of the same configuration (refusing a missing,
repeated or foreign part), analyses them and writes the result as a single run would.

examples:
  rbjax sweep src/rbjax/examples/sweeps/sobol.toml --out sobol.json
  rbjax sweep conformance.toml --json --workers 2
  rbjax sweep study.toml --scheduler tcp://10.0.0.5:8786 --out study.json
  rbjax sweep study.toml --shard $SLURM_ARRAY_TASK_ID/8       (sbatch --array=1-8)
  rbjax sweep study.toml --merge study.part-*-of-8.npz --out study.json
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
        metavar="FILE",
        help="write the summary (FILE.json) and the samples (FILE.samples.npz); with --shard: "
        "the part (default: CONFIG.part-I-of-P.npz)",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_parallel_options(p, what="design's chunks", default=1, device_flags=True)
    split = p.add_mutually_exclusive_group()
    split.add_argument(
        "--shard",
        default=None,
        metavar="I/P",
        help="evaluate part I of P (1 ≤ I ≤ P) of the design and write it for --merge",
    )
    split.add_argument(
        "--merge",
        nargs="+",
        default=None,
        metavar="PART",
        help="join the parts written by --shard (all P of them) and analyse the whole",
    )
    p.set_defaults(func=run)


def run(args) -> int:
    import time
    from pathlib import Path

    from ..studies.parallel.executors import TaskError
    from ..studies.sweeps.parts import merge_parts, parse_part, run_part
    from ..studies.sweeps.sweep import load_config, run_sweep, write_outputs

    parallel = parallel_of(args)
    config = load_config(args.config)
    show = not args.no_progress
    start = time.perf_counter()
    try:
        if args.shard is not None:
            part, parts = parse_part(args.shard)
            out = args.out or f"{Path(args.config).stem}.part-{part}-of-{parts}.npz"
            progress(f"running part {part}/{parts} of the {config.get('kind')!r} sweep")
            path = run_part(config, part, parts, out, progress=show, parallel=parallel)
            seconds = time.perf_counter() - start
            progress(f"wrote {path} in {seconds:.1f} s")
            if args.json:
                emit_json({"part": part, "parts": parts, "path": str(path), "seconds": seconds})
            return 0
        if args.merge is not None:
            progress(f"merging {len(args.merge)} parts of the {config.get('kind')!r} sweep")
            result = merge_parts(config, args.merge, progress=show)
        else:
            progress(f"running {config.get('kind')!r} sweep from {args.config}")
            result = run_sweep(config, progress=show, parallel=parallel)
    except TaskError as err:
        print(f"rbjax: error: {str(err).splitlines()[0]}", file=sys.stderr)
        return 1
    seconds = time.perf_counter() - start
    evaluations = result.n_evaluations if hasattr(result, "n_evaluations") else result.n_samples
    progress(
        f"{evaluations} impact evaluations in {seconds:.1f} s ({evaluations / seconds:.0f} per s)"
    )
    if args.out:
        for path in write_outputs(result, args.out, config):
            progress(f"wrote {path}")
    if args.json:
        emit_json({"config": config, **result.to_dict()})
    else:
        print(result.table())
    return 0

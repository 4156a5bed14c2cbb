"""Subcommands of the ``rbjax`` command line, one module each, discovered automatically.

A command module in this package exposes ``register(subparsers)``: it adds its subparser
(preferably with :func:`add_command`, which gives it ``--json`` and the one-line error
handling) and sets ``func`` to a callable ``func(args) -> int`` (the exit code)::

    def register(subparsers):
        p = add_command(subparsers, "mycmd", help="one line", description="longer text")
        p.add_argument("--height-m", type=float, required=True)
        p.set_defaults(func=run)

Modules whose name starts with ``_`` and modules without ``register`` are skipped, so a
package-private helper module can live here too. A command module imports the library (and
NumPy) inside its ``run``, never at its top or in ``register``: ``rbjax --help`` and
``rbjax COMMAND --help`` build every parser without importing JAX
(``tests/commands/test_cli_startup.py``). Helpers for the commands: :func:`emit_json`
(strict JSON on stdout, NaN → null), :func:`progress` (one line on stderr) and
:func:`format_table`.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .._progress import progress  # noqa: F401  (re-exported for the commands)
from ..text import fmt, format_table  # noqa: F401  (re-exported for the commands)

# The parsers are built without importing the library (JAX, SciPy): `rbjax --help` and
# `rbjax COMMAND --help` answer at once. Each command imports what it runs in its `run`.


class UsageError(ValueError):
    """A bad command line (unknown option, bad choice, unparsable number)."""


class ArgumentParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors raise :class:`UsageError` instead of printing usage.

    ``rbjax.cli.main`` turns the error into the single line ``rbjax: error: <message>`` and
    exit code 2, like every other bad input.
    """

    def error(self, message):
        command = self.prog.removeprefix("rbjax").strip()
        raise UsageError(f"{command}: {message}" if command else message)


def add_command(
    subparsers, name: str, *, help: str, description: str | None = None
) -> argparse.ArgumentParser:
    """Add a subcommand parser with ``--json`` and the house formatting."""
    parser = subparsers.add_parser(
        name,
        help=help,
        description=description or help,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_json_flag(parser)
    return parser


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """Add ``--json`` (machine-readable output on stdout) unless the parser already has it."""
    try:
        parser.add_argument(
            "--json",
            action="store_true",
            help="print machine-readable JSON on stdout (progress stays on stderr)",
        )
    except argparse.ArgumentError:
        pass  # the command defined its own --json


def add_parallel_options(
    parser: argparse.ArgumentParser,
    what: str | None = "fits",
    default: int | None = None,
    fit_flags: bool = False,
    device_flags: bool = False,
) -> None:
    """The flags of an :class:`rbjax.Parallel`, one per field. ``what`` (the tasks, ``None``:
    no task flags): ``--workers N`` (``workers``; ``default``: the worker count without it,
    ``None``: the usable cores) or ``--scheduler ADDRESS`` (``scheduler``); ``fit_flags``:
    also ``--batch-fits`` (``batch_fits``); ``device_flags``: ``--devices N`` (``devices``: N
    JAX devices, N CPU devices made before JAX starts) and ``--chunk-size N``
    (``chunk_size``)."""
    if what is not None:
        where = parser.add_mutually_exclusive_group()
        where.add_argument(
            "--workers",
            type=int,
            default=default,
            metavar="N",
            help=f"worker processes to run the {what} in (default: "
            + ("the cores this process may use" if default is None else str(default))
            + "; 1: in this process; at most the usable cores)",
        )
        where.add_argument(
            "--scheduler",
            default=None,
            metavar="ADDRESS",
            help=f"send the {what} to the Dask scheduler at ADDRESS (tcp://host:port) instead; "
            "needs pip install 'rbjax[cluster]' (dask-jobqueue starts such a cluster on SLURM/PBS)",
        )
        if fit_flags:
            where.add_argument(
                "--batch-fits",
                action="store_true",
                default=None,
                help="run the fits in this process, every call of a fit program gathered into "
                "one batch of it (the default where JAX's default device is a GPU or TPU; on a "
                "CPU it is slower than worker processes)",
            )
    if device_flags:
        parser.add_argument(
            "--devices",
            type=int,
            default=None,
            metavar="N",
            help="JAX devices a batch of impacts is split over (default: all; on a CPU, one "
            "device per usable core is made before JAX starts, N with this flag)",
        )
        parser.add_argument(
            "--chunk-size",
            type=int,
            default=None,
            metavar="N",
            help="impacts per device chunk (default: sized for the solve path and the platform)",
        )


def parallel_of(args):
    """The :class:`rbjax.Parallel` of the flags of :func:`add_parallel_options` (a worker count
    above the usable cores is clamped, and said so); ``--devices`` also makes that many JAX CPU
    devices before JAX starts (:func:`use_cpu_devices`)."""
    from ..solve.parallel import Parallel, usable_cores

    workers = getattr(args, "workers", None)
    devices = getattr(args, "devices", None)
    if hasattr(args, "devices"):
        use_cpu_devices(devices)
    if workers is not None and workers < 1:
        raise ValueError(f"--workers={workers!r} is outside the valid range: an integer ≥ 1")
    cores = usable_cores()
    if workers is not None and workers > cores:
        progress(f"--workers={workers}: this process may use {cores} cores; using {cores}")
        workers = cores
    if devices is not None and devices < 1:
        raise ValueError(f"--devices={devices!r} is outside the valid range: an integer ≥ 1")
    return Parallel(
        devices=devices,
        chunk_size=getattr(args, "chunk_size", None),
        workers=None if getattr(args, "scheduler", None) else workers,
        scheduler=getattr(args, "scheduler", None),
        batch_fits=getattr(args, "batch_fits", None),
    )


def use_cpu_devices(count: int | None = None) -> None:
    """Give JAX ``count`` CPU devices (default: one per usable core) before it starts, so that
    forward batches are split over every core (:func:`rbjax.solve.simulate` and
    :func:`rbjax.solve.batch.evaluate` do so when there are several devices). Left alone where
    ``JAX_NUM_CPU_DEVICES`` or ``XLA_FLAGS`` already sets a count, or JAX's backend is running
    (a second command in one process): its devices are used as they are."""
    import jax

    from ..solve.parallel import usable_cores

    if count is not None and (isinstance(count, bool) or not isinstance(count, int) or count < 1):
        raise ValueError(f"--devices={count!r} must be an integer ≥ 1")
    if "JAX_NUM_CPU_DEVICES" in os.environ or "xla_force_host_platform_device_count" in (
        os.environ.get("XLA_FLAGS", "")
    ):
        return  # the user chose
    try:
        jax.config.update("jax_num_cpu_devices", count or usable_cores())
    except RuntimeError:  # the backend is running
        pass


def emit_json(obj, file=None) -> None:
    """Write ``obj`` as strict JSON (no NaN tokens) to stdout."""
    from ..terms.serialize import to_json

    print(to_json(obj), file=file or sys.stdout)


def write_json_file(folder, name: str, obj):
    """Write ``obj`` as strict JSON to ``folder/name`` (the folder is made); return the path."""
    from ..terms.serialize import to_json

    path = Path(folder) / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(to_json(obj))
    return path

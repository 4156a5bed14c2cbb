"""The ``rbjax`` command line: ``rbjax <command> [options]``.

Commands are the modules of :mod:`rbjax.commands`, discovered with ``pkgutil`` (sorted by
name), each adding its subparser in ``register(subparsers)``. Every command has ``--help``
and ``--json``. Bad input (a ``ValueError`` from the library, a ``rbjax.data.DataError``,
an unreadable params file, a bad option) exits with code 2 and one line on stderr,
``rbjax: error: <message>``; no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys

from . import __version__, commands
from ._exit import skip_final_collection
from .commands import ArgumentParser, UsageError, add_json_flag


def command_modules() -> list[str]:
    """Names of the command modules in :mod:`rbjax.commands`, in a stable (sorted) order."""
    names = (m.name for m in pkgutil.iter_modules(commands.__path__))
    return sorted(n for n in names if not n.startswith("_"))


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subparser per discovered command."""
    parser = ArgumentParser(
        prog="rbjax",
        description=(
            "Blocked force of the JIS A 1418-2 / ISO 10140-5 Annex F rubber-ball impact source "
            "(Schoenwald, Zeitler & Nightingale 2011)."
        ),
    )
    parser.add_argument("--version", action="version", version=f"rbjax {__version__}")
    subparsers = parser.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=ArgumentParser
    )
    for name in command_modules():
        module = importlib.import_module(f"{commands.__name__}.{name}")
        register = getattr(module, "register", None)
        if register is None:
            continue
        register(subparsers)
    for sub in subparsers.choices.values():
        add_json_flag(sub)
    return parser


def compile_cache_dir() -> str | None:
    """Where the command line keeps compiled programs between runs (``None``: nowhere).

    ``$RBJAX_CACHE_DIR`` if set (empty: no cache), else ``$XDG_CACHE_HOME/rbjax/jax`` or
    ``~/.cache/rbjax/jax``. JAX's persistent compilation cache: a second ``rbjax fit`` or
    ``rbjax simulate`` skips the XLA compilation of the programs the first one built; the fit's
    programs are also kept traced (:mod:`rbjax.fit.program_store`), so a second fit skips tracing
    too. Only the command line switches it on; importing rbjax does not.
    """
    if "RBJAX_CACHE_DIR" in os.environ:
        return os.environ["RBJAX_CACHE_DIR"] or None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "rbjax", "jax")


def _enable_compile_cache() -> None:
    import jax  # lazy: JAX costs ~1 s at import, which --help and --version do not need

    path = compile_cache_dir()
    # Off, or the caller chose one. (JAX's config options are attributes set at run time;
    # its type stubs do not list them.)
    if path is None or jax.config.jax_compilation_cache_dir:  # type: ignore[attr-defined]
        return
    jax.config.update("jax_compilation_cache_dir", path)
    # JAX keeps only programs that took ≥ 1 s to compile; the fit's small helpers (features,
    # the substeps' Jacobian, θ's transforms) take less each but ~1 s together on every run.
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)


def _one_line(message) -> str:
    return " ".join(str(message).split())


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); return the exit code."""
    parser = build_parser()
    try:
        try:
            args = parser.parse_args(argv)
        except SystemExit as done:  # --help, --version
            return int(done.code or 0)
        if getattr(args, "func", None) is None:
            parser.print_help(sys.stderr)
            return 2
        _enable_compile_cache()
        skip_final_collection()
        return int(args.func(args) or 0)
    except (UsageError, ValueError, OSError) as err:  # rbjax.data.DataError is a ValueError
        print(f"rbjax: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rbjax: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

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
import pkgutil
import sys

from . import commands
from .commands import ArgumentParser, UsageError, add_json_flag


def command_modules() -> list[str]:
    """Names of the command modules in :mod:`rbjax.commands`, in a stable (sorted) order."""
    names = (m.name for m in pkgutil.iter_modules(commands.__path__))
    return sorted(n for n in names if not n.startswith("_"))


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subparser per discovered command."""
    from . import __version__

    parser = ArgumentParser(
        prog="rbjax",
        description="Blocked force of the JIS A 1418-2 / ISO 10140-5 Annex F rubber-ball impact source "
        "(Schoenwald, Zeitler & Nightingale 2011).",
    )
    parser.add_argument("--version", action="version", version=f"rbjax {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=ArgumentParser)
    for name in command_modules():
        module = importlib.import_module(f"{commands.__name__}.{name}")
        register = getattr(module, "register", None)
        if register is None:
            continue
        register(subparsers)
    for sub in subparsers.choices.values():
        add_json_flag(sub)
    return parser


def _one_line(message) -> str:
    return " ".join(str(message).split())


def main(argv: list[str] | None = None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); return the exit code."""
    from .data import DataError

    parser = build_parser()
    try:
        try:
            args = parser.parse_args(argv)
        except SystemExit as done:  # --help, --version
            return int(done.code or 0)
        if getattr(args, "func", None) is None:
            parser.print_help(sys.stderr)
            return 2
        return int(args.func(args) or 0)
    except (UsageError, DataError, ValueError, OSError) as err:
        print(f"rbjax: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rbjax: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

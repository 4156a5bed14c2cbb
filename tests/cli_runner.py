"""Run the command line in-process (shared by the CLI tests and the floor-preset tests)."""

from __future__ import annotations

import contextlib
import io

from rbjax.cli import main


def run_cli(argv):
    """(exit code, stdout, stderr) of ``main(argv)`` in-process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()

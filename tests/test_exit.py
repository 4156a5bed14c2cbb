"""The quick exit of the command line's processes (rbjax._exit): the collector is frozen at exit,
and every atexit handler and the output still run and arrive."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import atexit, gc
atexit.register(lambda: print("last:", gc.get_freeze_count() > 0))  # runs after the freeze
from rbjax._exit import skip_final_collection
skip_final_collection()
skip_final_collection()  # once per process
atexit.register(lambda: print("first:", gc.get_freeze_count() == 0))  # runs before it
print("output", end="")  # unflushed at exit
"""


def test_a_process_that_skips_the_final_collection_still_runs_its_handlers():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == "outputfirst: True\nlast: True\n"

"""Session-wide JAX settings for the test run: tests/ and the notebooks (nbmake runs each in its
own kernel, which inherits this process's environment, as do the xdist workers).

Almost all of the suite's time is XLA compiling diffrax solves once per process, so:

* ``JAX_DISABLE_MOST_OPTIMIZATIONS=1`` (JAX's own option: LLVM backend optimisation level 0,
  no expensive LLVM passes) for the notebooks' kernels, smoke runs whose programs run once or a
  few times each, so a cheaper compile wins over faster code. The tests under tests/ compile at
  XLA's default level, as users do, unless marked ``xla_smoke`` (tests/conftest.py sets the
  level per module and test, and this variable for the subprocesses a test starts).
* One JAX persistent compilation cache per pytest session, in a temporary folder shared by the
  xdist workers and the notebooks' kernels: a program compiled by one process (the paper model's
  solves, the fits of the shipped example set) is read back by the others instead of compiled
  again. The folder is removed at the end of the session; nothing is written to ``~/.cache``.

Either is left as the caller set it where the variable is already in the environment (an empty
``JAX_COMPILATION_CACHE_DIR`` or ``JAX_DISABLE_MOST_OPTIMIZATIONS=0`` switches it off).
"""

import os
import shutil
import tempfile

os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
_OWN_CACHE = "JAX_COMPILATION_CACHE_DIR" not in os.environ
if _OWN_CACHE:  # the first process of the session (the xdist controller): made once, inherited
    os.environ["JAX_COMPILATION_CACHE_DIR"] = tempfile.mkdtemp(prefix="rbjax-test-jax-cache-")
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")


def pytest_unconfigure(config):
    if _OWN_CACHE:
        shutil.rmtree(os.environ["JAX_COMPILATION_CACHE_DIR"], ignore_errors=True)

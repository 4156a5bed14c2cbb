"""Test configuration: float64 everywhere (as rbjax itself sets on import); no persistent
compilation cache for the command line (tests stay hermetic: nothing written to ~/.cache).

The session's JAX compilation cache (../conftest.py) only saves XLA compiles between processes:
the fit's program store, which switches itself on wherever a compilation cache is set
(``rbjax.fit.program_store``), stays off for it, so that the fits under test run the library's
default path (traced in the process) as they do for a user without a cache. The store's own tests
set a cache folder of their own and get the store.
"""

import os

import jax
import pytest

jax.config.update("jax_enable_x64", True)
os.environ["RBJAX_CACHE_DIR"] = ""
# One CPU device in every test process, whichever test comes first: a command run in process
# (tests/cli_runner.py) asks for one device per core, which JAX grants only before it starts.
# The split over several devices is tested in subprocesses (tests/solve/test_devices.py).
jax.devices()

import rbjax  # noqa: E402,F401  (importing rbjax also enables x64; kept explicit above)
from rbjax.fit import program_store  # noqa: E402

_SESSION_CACHE = os.environ.get("JAX_COMPILATION_CACHE_DIR") or None
_store_dir = program_store.store_dir


def _store_dir_but_not_the_session_cache():
    if _SESSION_CACHE is not None and jax.config.jax_compilation_cache_dir == _SESSION_CACHE:  # type: ignore[attr-defined]
        return None
    return _store_dir()


program_store.store_dir = _store_dir_but_not_the_session_cache


# XLA's optimisation per test module. The session compiles with most optimisations off
# (../conftest.py): nearly every program runs once or a few times. A module whose programs run
# hundreds of times (a model selection: thousands of Levenberg–Marquardt steps) marks itself
# ``pytestmark = pytest.mark.xla_optimised`` and compiles with XLA's full optimisation: its runs
# are then faster than the compile is slower. Measured per module on 2 cores (CPU seconds, each
# flag in its own process): tests/studies/test_selection_end_to_end.py 85 → 48 s; the fit tests,
# the notebooks, the solver and room tests were 6–20 % slower with full optimisation, so the low
# level stays the default. The numbers do not change beyond round-off; every test keeps its
# tolerance against its independent reference.


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "xla_optimised: compile this module's programs with XLA's full optimisation (programs "
        "that run many times)",
    )


@pytest.fixture(autouse=True, scope="module")
def _xla_optimisation(request):
    before = jax.config.values["jax_disable_most_optimizations"]
    if request.node.get_closest_marker("xla_optimised") is not None:
        jax.config.update("jax_disable_most_optimizations", False)
    yield
    jax.config.update("jax_disable_most_optimizations", before)

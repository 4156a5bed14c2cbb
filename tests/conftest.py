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


# XLA's optimisation level. Users compile with XLA's default optimisation, so the tests do too:
# every accuracy test (each solve path against its independent reference, the fit's recovery, the
# gradients against finite differences) runs at the default level. The session's environment
# (../conftest.py) says most optimisations off, for the notebooks' kernels, which are smoke runs
# (six notebooks, each program run once); this file sets the default level back for tests/.
#
# A smoke test whose programs compile for longer than they run, and which holds no accuracy
# claim at its own level (it checks an interface, an error, a file, or one program against the
# same program elsewhere), marks itself ``pytest.mark.xla_smoke`` (a module: ``pytestmark``) and
# compiles with most optimisations off. The level is set before each module and each test and
# put back after it, in this process and in the environment that subprocesses, worker pools and
# Dask workers started by a test inherit, so a level never leaks from one module to the next.
# JAX's in-memory caches do not key on the level, so a switch clears them (``jax.clear_caches``):
# no program compiled at one level is reused at the other (the persistent cache keys on it).
# The difference between the two levels, per path: benchmarks/accuracy.py --only opt_levels,
# figures in benchmarks/RESULTS.md, "XLA optimisation level".

SMOKE = "xla_smoke"
_ENV = "JAX_DISABLE_MOST_OPTIMIZATIONS"


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        f"{SMOKE}: compile with most of XLA's optimisations off (a smoke test: programs that "
        "compile for longer than they run; no accuracy claim at this level)",
    )


def _set_level(smoke: bool) -> None:
    os.environ[_ENV] = "1" if smoke else "0"
    if jax.config.values["jax_disable_most_optimizations"] != smoke:
        jax.config.update("jax_disable_most_optimizations", smoke)
        jax.clear_caches()


def _restore_env(before: str | None) -> None:
    if before is None:
        os.environ.pop(_ENV, None)
    else:
        os.environ[_ENV] = before


@pytest.fixture(autouse=True, scope="module")
def _xla_level_of_module(request):
    env = os.environ.get(_ENV)
    smoke = any(m.name == SMOKE for m in request.node.iter_markers())
    _set_level(smoke)
    yield smoke
    _set_level(False)
    _restore_env(env)


@pytest.fixture(autouse=True)
def _xla_level_of_test(request, _xla_level_of_module):
    env = os.environ.get(_ENV)
    _set_level(request.node.get_closest_marker(SMOKE) is not None)
    yield
    _set_level(_xla_level_of_module)
    _restore_env(env)

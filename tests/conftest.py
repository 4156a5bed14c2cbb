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

jax.config.update("jax_enable_x64", True)
os.environ["RBJAX_CACHE_DIR"] = ""

import rbjax  # noqa: E402,F401  (importing rbjax also enables x64; kept explicit above)
from rbjax.fit import program_store  # noqa: E402

_SESSION_CACHE = os.environ.get("JAX_COMPILATION_CACHE_DIR") or None
_store_dir = program_store.store_dir


def _store_dir_but_not_the_session_cache():
    if _SESSION_CACHE is not None and jax.config.jax_compilation_cache_dir == _SESSION_CACHE:  # type: ignore[attr-defined]
        return None
    return _store_dir()


program_store.store_dir = _store_dir_but_not_the_session_cache

"""Test configuration: float64 everywhere (as rbjax itself sets on import); no persistent
compilation cache for the command line (tests stay hermetic: nothing written to ~/.cache)."""

import os

import jax

jax.config.update("jax_enable_x64", True)
os.environ["RBJAX_CACHE_DIR"] = ""

import rbjax  # noqa: E402,F401  (importing rbjax also enables x64; kept explicit above)

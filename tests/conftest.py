"""Test configuration: float64 everywhere (as rbjax itself sets on import)."""

import jax

jax.config.update("jax_enable_x64", True)

import rbjax  # noqa: E402,F401  (importing rbjax also enables x64; kept explicit above)

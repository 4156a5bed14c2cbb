"""float64 for every rbjax computation.

rbjax switches JAX's ``jax_enable_x64`` flag on when it is imported (documented in
docs/guides/solving.md, "Precision"). The flag is process-wide: code that imports rbjax gets
float64 as JAX's default dtype too. ``rbjax/__init__.py`` imports this module where JAX is imported
already; otherwise it sets ``JAX_ENABLE_X64=1``, which JAX reads when it is first imported (so
``import rbjax`` itself need not import JAX; the variable is inherited by child processes).
Each public entry point checks the flag and raises if a caller switched it off again
afterwards, rather than silently computing in float32.
"""

import jax

jax.config.update("jax_enable_x64", True)


def require_x64() -> None:
    """Raise ``RuntimeError`` if float64 has been switched off after importing rbjax."""
    # JAX's config options are attributes set at run time; its type stubs do not list them.
    if not jax.config.jax_enable_x64:  # type: ignore[attr-defined]
        raise RuntimeError(
            "rbjax needs float64: jax_enable_x64 was switched off after importing rbjax; "
            "call jax.config.update('jax_enable_x64', True)"
        )

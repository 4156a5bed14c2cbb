"""float64 for every rbjax computation: the check.

Importing rbjax switches JAX's ``jax_enable_x64`` flag on, once, in the package ``__init__``
(documented in docs/guides/solving.md, "Precision"): where JAX is imported already it sets the
flag; otherwise it sets ``JAX_ENABLE_X64=1``, which JAX reads when it is first imported (so
``import rbjax`` itself need not import JAX; the variable is inherited by child processes).
Every rbjax module is imported after that ``__init__`` and relies on it; none sets the flag.
The flag is process-wide: code that imports rbjax gets float64 as JAX's default dtype too.
Each public entry point calls :func:`require_x64`, which raises if a caller switched the flag
off afterwards, rather than silently computing in float32.
"""

import jax


def require_x64() -> None:
    """Raise ``RuntimeError`` if float64 has been switched off after importing rbjax."""
    # JAX's config options are attributes set at run time; its type stubs do not list them.
    if not jax.config.jax_enable_x64:  # type: ignore[attr-defined]
        raise RuntimeError(
            "rbjax needs float64: jax_enable_x64 was switched off after importing rbjax; "
            "call jax.config.update('jax_enable_x64', True)"
        )

"""A quick exit for the processes of the command line and of its local workers.

When Python exits it first collects its cyclic garbage, walking every object it tracks: with
JAX, diffrax and SciPy loaded that walk took ~0.25 s of the ~0.3 s a process spent exiting
(2 cores; a selection's worker exits while the command waits for it). Freezing the collector
(``gc.freeze``) as the last thing before that walk leaves those objects to the operating system
instead. Every ``atexit`` handler still runs, the standard streams are still flushed, and every
object outside a reference cycle is still finalized; only objects in cycles are not (rbjax
closes the files it writes with ``with``, never leaving that to a finalizer).
"""

import atexit
import gc

_REGISTERED: list[bool] = []


def skip_final_collection() -> None:
    """Freeze the garbage collector when this process exits (once per process; the handler
    registered first runs last, so the earlier a caller registers it the later it runs)."""
    if not _REGISTERED:
        _REGISTERED.append(True)
        atexit.register(gc.freeze)

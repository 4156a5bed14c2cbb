"""Traced programs kept on disk beside JAX's persistent compilation cache.

JAX's persistent cache keeps the *compiled* program, but a new process still traces the Python
code again before it can look the program up, and tracing a fit (diffrax solves with events,
under ``jax.jacfwd``, inside optimistix) takes longer than compiling it. So where the
compilation cache is switched on (``jax.config.jax_compilation_cache_dir``, which the command
line sets), a program is also exported once with :mod:`jax.export` (StableHLO) and the next
process deserializes it instead of tracing; its compilation then comes from the compilation
cache.

The file name is a digest of the program's static description, the shapes and dtypes of its
arguments, the JAX version and the source code of the installed ``rbjax`` package, so an edit
of any module makes a new program rather than reusing a stale one.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

import jax
from equinox import _errors  # EQX_ON_ERROR (equinox has no public switch for it)

_LOADED: dict[str, Callable] = {}


PACKAGE_ROOT = Path(__file__).parents[1]


def source_files() -> list[Path]:
    """Every source file of the installed ``rbjax`` package (all layers), sorted."""
    return sorted(PACKAGE_ROOT.rglob("*.py"))


@functools.cache
def source_digest() -> str:
    """SHA-256 over the source files of the installed ``rbjax`` package (sorted by path)."""
    h = hashlib.sha256()
    for path in source_files():
        h.update(str(path.relative_to(PACKAGE_ROOT)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def store_dir() -> Path | None:
    """Where exported programs are kept: ``<compilation cache>/rbjax-programs``, or ``None``."""
    cache = jax.config.jax_compilation_cache_dir  # type: ignore[attr-defined]  # options are not in the stubs
    return Path(cache) / "rbjax-programs" if cache else None


@functools.lru_cache(maxsize=256)
def _described(description) -> str:
    """``repr(description)``, once per description (hashable: the program's structure and
    settings): the pretty-printing of its equinox modules took 10 ms a call, 2 s of a warm
    ``rbjax fit``'s 210 program calls."""
    return repr(description)


def program_key(description, args) -> str:
    """The file name of a program: a digest of its description and its arguments' types."""
    types = jax.tree_util.tree_map(lambda x: (tuple(x.shape), str(x.dtype)), args)
    text = repr(
        (
            _described(description),
            jax.tree_util.tree_structure(args),
            jax.tree_util.tree_leaves(types),
            jax.__version__,
            jax.default_backend(),
            source_digest(),
        )
    )
    return hashlib.sha256(text.encode()).hexdigest()


def _write_atomic(path: Path, blob: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "wb") as f:
        f.write(blob)
    os.replace(tmp, path)


@contextlib.contextmanager
def _errors_as_nan():
    """Equinox's runtime errors (lineax, optimistix) as NaN outputs instead of host callbacks.

    A host callback cannot be serialized; with ``EQX_ON_ERROR=nan`` semantics a failed linear
    solve inside the program gives NaN, which the fit reports as a failure (it never reports
    success on NaN).
    """
    before = getattr(_errors, "EQX_ON_ERROR", None)
    if before is None:  # a future equinox: leave it alone, export will say if it cannot
        yield
        return
    # Jitted library functions (lineax's linear_solve, equinox's check) cache their traces:
    # drop them before, so that no trace with a host callback is reused, and after, so that no
    # trace with NaN semantics leaks into later plain calls (an export happens once per program).
    jax.clear_caches()
    _errors.EQX_ON_ERROR = "nan"
    try:
        yield
    finally:
        _errors.EQX_ON_ERROR = before
        jax.clear_caches()


def _export(fn, args):
    """``jax.export`` of ``fn`` at ``args``, or ``None`` where it cannot be exported.

    The program is only ever read back by the same JAX version on the same platform (both are
    in its key), so custom calls without cross-version guarantees (LAPACK's QR in diffrax's root
    finder) are allowed by name when export refuses them.
    """
    disabled: list = []
    with _errors_as_nan():
        for _ in range(8):
            try:
                return jax.export.export(fn, disabled_checks=disabled)(*args)
            except ValueError as err:
                targets = set(re.findall(r"custom_call @(\w+)", str(err)))
                if "custom calls" not in str(err) or not targets:
                    return None
                disabled += [jax.export.DisabledSafetyCheck.custom_call(t) for t in sorted(targets)]
            except NotImplementedError:  # e.g. a host callback
                return None
    return None


def load_or_export(description, make: Callable[[], Callable], args) -> Callable:
    """A callable of ``args``: the stored export of the program if there is one, else ``make()``.

    ``make()`` returns the jitted program. With a store (see :func:`store_dir`) a missing
    program is exported from ``make()`` at ``args``' shapes, written, and called through its
    export, so that the first and every later process compile the same module. Without a store,
    or where the program cannot be exported, ``make()`` itself is returned.
    """
    folder = store_dir()
    if folder is None:
        return make()
    key = program_key(description, args)
    if key in _LOADED:
        return _LOADED[key]
    path = folder / f"{key}.jaxexport"
    exported = _read(path)
    if exported is None:
        # One process a machine traces and compiles a program: the others (worker processes
        # of a model selection, started together) wait for it instead of tracing and compiling
        # it too on the same cores, then find its export and its compilation in the caches.
        # The export is written once it is compiled, so a process that reads it never compiles.
        with _exclusive(folder / f"{key}.lock"):
            exported = _read(path)
            if exported is None:
                exported = _export(make(), args)
                if exported is None:
                    return make()
                program = jax.jit(exported.call)
                program.lower(*args).compile()  # kept by the jit and the compilation cache
                try:
                    _write_atomic(path, exported.serialize())
                except OSError:
                    pass  # a read-only cache: this process still runs the exported program
                _LOADED[key] = program
                return program
    _LOADED[key] = jax.jit(exported.call)
    return _LOADED[key]


def _read(path: Path):
    """The stored export at ``path``, or ``None`` (missing, truncated or foreign)."""
    try:
        return jax.export.deserialize(bytearray(path.read_bytes()))
    except Exception:  # any failure to read means export anew
        return None


@contextlib.contextmanager
def _exclusive(lock: Path):
    """An exclusive lock on the file ``lock`` (``fcntl.flock``; released when the process
    dies); where locking is not possible (no ``fcntl``, a read-only store), no lock."""
    try:
        # lazy: fcntl exists on POSIX only
        import fcntl

        lock.parent.mkdir(parents=True, exist_ok=True)
        handle = open(lock, "a+b")  # noqa: SIM115  (closed below)
    except (ImportError, OSError):
        yield
        return
    try:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield
    finally:
        handle.close()

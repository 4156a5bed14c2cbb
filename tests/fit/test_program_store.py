"""Exported programs on disk (rbjax.fit.program_store): read back, keyed, and never stale.

The reference for every value is the same computation in NumPy.
"""

import logging
from pathlib import Path

import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import pytest

from rbjax.fit import program_store


def _program():
    # A small program with what the fit program carries: a pytree result, a while loop, and a
    # lineax solve (an equinox runtime check, serialized as NaN-on-error).
    def run(a, b, x):
        sol = lx.linear_solve(lx.MatrixLinearOperator(a), b)
        y = jax.lax.fori_loop(0, 5, lambda i, y: y + jnp.sin(y) * x, sol.value)
        return {"y": y, "norm": jnp.linalg.norm(y)}

    return jax.jit(run)


ARGS = (jnp.array([[3.0, 1.0], [1.0, 2.0]]), jnp.array([1.0, -1.0]), jnp.asarray(0.3))


def _expected(a, b, x):
    y = np.linalg.solve(np.asarray(a), np.asarray(b))
    for _ in range(5):
        y = y + np.sin(y) * float(x)
    return {"y": y, "norm": np.linalg.norm(y)}


@pytest.fixture
def store(tmp_path, monkeypatch):
    monkeypatch.setattr(program_store, "_LOADED", {})
    before = jax.config.jax_compilation_cache_dir
    jax.config.update("jax_compilation_cache_dir", str(tmp_path))
    yield tmp_path / "rbjax-programs"
    jax.config.update("jax_compilation_cache_dir", before)


def test_exported_program_is_written_read_back_and_agrees_with_jit(store, monkeypatch):
    expected = _expected(*ARGS)
    fn = program_store.load_or_export("toy", _program, ARGS)
    files = list(store.glob("*.jaxexport"))
    assert len(files) == 1
    np.testing.assert_allclose(fn(*ARGS)["y"], expected["y"], rtol=1e-14)

    # a new process: nothing loaded in memory, and make() must not be called (no tracing)
    monkeypatch.setattr(program_store, "_LOADED", {})

    def fail():
        raise AssertionError("the stored program should have been read, not rebuilt")

    again = program_store.load_or_export("toy", fail, ARGS)
    out = again(*ARGS)
    np.testing.assert_allclose(out["y"], expected["y"], rtol=1e-14)
    np.testing.assert_allclose(out["norm"], expected["norm"], rtol=1e-14)


def test_key_changes_with_description_shapes_dtypes_and_source(monkeypatch):
    key = program_store.program_key("toy", ARGS)
    assert program_store.program_key("toy", ARGS) == key
    assert program_store.program_key("other", ARGS) != key
    assert program_store.program_key("toy", (ARGS[0], ARGS[1], jnp.zeros(3))) != key
    assert program_store.program_key("toy", (ARGS[0], ARGS[1], jnp.asarray(True))) != key
    monkeypatch.setattr(program_store, "source_digest", lambda: "an edited rbjax")
    assert program_store.program_key("toy", ARGS) != key


def test_a_corrupt_file_is_replaced_by_a_fresh_export(store, monkeypatch):
    path = store / f"{program_store.program_key('toy', ARGS)}.jaxexport"
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not a program")
    fn = program_store.load_or_export("toy", _program, ARGS)
    np.testing.assert_allclose(fn(*ARGS)["y"], _expected(*ARGS)["y"], rtol=1e-14)
    assert path.read_bytes() != b"not a program"


def test_a_failed_linear_solve_gives_nan_not_a_host_error(store):
    fn = program_store.load_or_export("toy", _program, ARGS)
    singular = (jnp.zeros((2, 2)), ARGS[1], ARGS[2])
    fn2 = program_store.load_or_export("toy", _program, singular)
    assert fn2 is fn  # same shapes: the same program
    assert len(list(store.glob("*.jaxexport"))) == 1  # exported, not the plain program
    assert not np.all(np.isfinite(np.asarray(fn(*singular)["y"])))


def test_without_a_cache_dir_the_program_itself_is_used(monkeypatch):
    monkeypatch.setattr(program_store, "store_dir", lambda: None)
    made = []
    fn = program_store.load_or_export("toy", lambda: made.append(1) or _program(), ARGS)
    assert made == [1]
    np.testing.assert_allclose(fn(*ARGS)["y"], _expected(*ARGS)["y"], rtol=1e-14)


def test_a_program_run_before_without_a_store_is_still_exported(store):
    # equinox caches the trace of its runtime checks; one traced with host-callback semantics
    # (a plain run) must not leak into the export
    args = (ARGS[0][:1, :1] + 1.0, ARGS[1][:1], ARGS[2])
    np.testing.assert_allclose(_program()(*args)["y"], _expected(*args)["y"], rtol=1e-14)
    fn = program_store.load_or_export("toy-after-plain", _program, args)
    assert len(list(store.glob("*.jaxexport"))) == 1
    np.testing.assert_allclose(fn(*args)["y"], _expected(*args)["y"], rtol=1e-14)


def test_the_key_covers_the_source_of_every_layer():
    """A stored program is the whole model's: an edit to a term or a solve path must change its
    key, not only an edit to the fit package that holds the store."""
    import rbjax

    root = Path(rbjax.__file__).parent
    files = {p.relative_to(root).as_posix() for p in program_store.source_files()}
    assert {
        "terms/forces.py",
        "solve/ode.py",
        "solve/record_samples.py",
        "fit/program.py",
        "__init__.py",
    } <= files
    assert files == {p.relative_to(root).as_posix() for p in root.rglob("*.py")}


def test_the_export_is_written_once_its_program_is_compiled(store, monkeypatch, caplog):
    """Worker processes that need a new program wait for the one that traces it, then read its
    export: the export is written only after the program is compiled (so a reader finds the
    compilation in the cache and never compiles it beside the writer), and the program returned
    runs without compiling again."""
    written_after = []

    def spy(path, blob):
        written_after.append("XLA compilation of jit(call)" in caplog.text)
        return write(path, blob)

    write = program_store._write_atomic
    monkeypatch.setattr(program_store, "_write_atomic", spy)
    before = jax.config.jax_log_compiles
    jax.config.update("jax_log_compiles", True)
    try:
        with caplog.at_level(logging.WARNING):
            fn = program_store.load_or_export("toy-compiled-first", _program, ARGS)
            assert written_after == [True]
            caplog.clear()
            out = fn(*ARGS)
            assert "XLA compilation of jit(call)" not in caplog.text
    finally:
        jax.config.update("jax_log_compiles", before)
    np.testing.assert_allclose(out["y"], _expected(*ARGS)["y"], rtol=1e-14)

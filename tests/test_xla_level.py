"""The XLA optimisation level of the tests (tests/conftest.py): the default level unless a test
or its module is marked ``xla_smoke``, set in this process and in the environment that
subprocesses inherit, and put back after each marked test (no leak to the next test). A switch
of level drops the programs compiled at the other level (JAX's in-memory caches do not key on
it), so no test runs a program compiled at a level it did not ask for."""

import os

import jax
import pytest

PLUS_ONE = jax.jit(lambda x: x + 1.0)


def level():
    return jax.config.values["jax_disable_most_optimizations"], os.environ.get(
        "JAX_DISABLE_MOST_OPTIMIZATIONS"
    )


def test_an_unmarked_test_compiles_at_the_default_level():
    assert level() == (False, "0")
    PLUS_ONE(1.0)
    assert PLUS_ONE._cache_size() == 1


@pytest.mark.xla_smoke
def test_a_marked_test_compiles_with_most_optimisations_off():
    assert level() == (True, "1")
    assert PLUS_ONE._cache_size() == 0  # the default level's program is not reused
    PLUS_ONE(1.0)
    assert PLUS_ONE._cache_size() == 1


def test_the_next_test_is_back_at_the_default_level():
    assert level() == (False, "0")
    assert PLUS_ONE._cache_size() == 0  # nor is the smoke test's

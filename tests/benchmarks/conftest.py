"""``bench_quick``: the full ``--quick`` run of every benchmark suite (minutes); deselected
unless asked for with ``-m bench_quick``."""

import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "bench_quick: run every benchmark suite with --quick")


def pytest_collection_modifyitems(config, items):
    if "bench_quick" in (config.getoption("-m") or ""):
        return
    skip = pytest.mark.skip(reason="minutes: run with -m bench_quick")
    for item in items:
        if "bench_quick" in item.keywords:
            item.add_marker(skip)

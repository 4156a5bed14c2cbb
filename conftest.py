"""Session-wide JAX settings for the test run: tests/ and the notebooks (nbmake runs each in its
own kernel, which inherits this process's environment, as do the xdist workers).

Almost all of the suite's time is XLA compiling diffrax solves once per process, so:

* ``JAX_DISABLE_MOST_OPTIMIZATIONS=1`` (JAX's own option: LLVM backend optimisation level 0,
  no expensive LLVM passes) for the notebooks' kernels, smoke runs whose programs run once or a
  few times each, so a cheaper compile wins over faster code. The tests under tests/ compile at
  XLA's default level, as users do, unless marked ``xla_smoke`` (tests/conftest.py sets the
  level per module and test, and this variable for the subprocesses a test starts).
* One JAX persistent compilation cache per pytest session, in a temporary folder shared by the
  xdist workers and the notebooks' kernels: a program compiled by one process (the paper model's
  solves, the fits of the shipped example set) is read back by the others instead of compiled
  again. The folder is removed at the end of the session; nothing is written to ``~/.cache``.

Either is left as the caller set it where the variable is already in the environment (an empty
``JAX_COMPILATION_CACHE_DIR`` or ``JAX_DISABLE_MOST_OPTIMIZATIONS=0`` switches it off).

``--compile-report=PATH`` writes where each test's time went: its wall time (setup, call and
teardown) and the seconds JAX reported (``jax.monitoring``) for tracing, lowering and XLA
compiling in the test's process, as JSON ``{test id: {event: seconds}}``, and under
``"programs"`` the programs themselves in order, from JAX's own log: ``["trace", name, s]``,
``["args", "jit(name) with global shapes and types …", 0]`` and ``["xla", "jit(name)", s]`` (which
programs a test compiled, for which shapes, and whether one was traced again); under xdist one
file per worker (``PATH`` with the worker's name before the suffix). A notebook's kernel and a
test's subprocesses are other processes: their time is wall time only.
"""

import json
import logging
import os
import re
import shutil
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

import pytest

os.environ.setdefault("JAX_DISABLE_MOST_OPTIMIZATIONS", "1")
_OWN_CACHE = "JAX_COMPILATION_CACHE_DIR" not in os.environ
if _OWN_CACHE:  # the first process of the session (the xdist controller): made once, inherited
    os.environ["JAX_COMPILATION_CACHE_DIR"] = tempfile.mkdtemp(prefix="rbjax-test-jax-cache-")
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")


def pytest_addoption(parser):
    parser.addoption(
        "--compile-report",
        metavar="PATH",
        default=None,
        help="write each test's wall time and JAX's tracing, lowering and XLA compile seconds "
        "to PATH (JSON; under xdist one file per worker)",
    )


class CompileReport(logging.Handler):
    """Seconds per test: ``wall`` and every duration event JAX reports while the test runs; the
    programs from JAX's log (its dispatch and pxla loggers at DEBUG, not propagated)."""

    TIMED = re.compile(r"Finished (tracing|XLA compilation of) (.+?) (?:for jit )?in ([0-9.]+) sec")

    def __init__(self, path: Path):
        super().__init__(logging.DEBUG)
        self.path, self.current, self.seconds = path, None, defaultdict(Counter)
        self.programs: defaultdict[str, list] = defaultdict(list)
        import jax.monitoring  # lazy: only with the option

        jax.monitoring.register_event_duration_secs_listener(self.record)
        for name in ("jax._src.dispatch", "jax._src.interpreters.pxla"):
            log = logging.getLogger(name)
            log.setLevel(logging.DEBUG)
            log.addHandler(self)
            log.propagate = False

    def record(self, event: str, duration: float, **_) -> None:
        if self.current is not None:
            self.seconds[self.current][event] += duration

    def emit(self, record: logging.LogRecord) -> None:
        if self.current is None:
            return
        message = record.getMessage()
        if message.startswith("Compiling "):
            args = message.removeprefix("Compiling ").split(". Argument mapping")[0]
            self.programs[self.current].append(["args", args, 0.0])
        elif timed := self.TIMED.match(message):
            kind = "trace" if timed[1] == "tracing" else "xla"
            self.programs[self.current].append([kind, timed[2], float(timed[3])])

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):
        self.current, start = item.nodeid, time.perf_counter()
        yield
        self.seconds[item.nodeid]["wall"] += time.perf_counter() - start
        self.current = None

    def pytest_sessionfinish(self, session):
        worker = os.environ.get("PYTEST_XDIST_WORKER")
        path = (
            self.path.with_name(f"{self.path.stem}.{worker}{self.path.suffix}")
            if worker
            else self.path
        )
        path.parent.mkdir(parents=True, exist_ok=True)
        rows = {
            k: dict(v) | {"programs": self.programs.get(k, [])} for k, v in self.seconds.items()
        }
        path.write_text(json.dumps(rows, indent=1))


def pytest_configure(config):
    path = config.getoption("--compile-report")
    # the xdist controller runs no test: its workers (``workerinput``) report
    controller = config.getoption("numprocesses", None) and not hasattr(config, "workerinput")
    if path and not controller:
        config.pluginmanager.register(CompileReport(Path(path).resolve()), "compile-report")


def pytest_unconfigure(config):
    if _OWN_CACHE:
        shutil.rmtree(os.environ["JAX_COMPILATION_CACHE_DIR"], ignore_errors=True)

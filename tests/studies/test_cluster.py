"""A real Dask cluster on localhost: a scheduler and two single-threaded worker processes, started
by this module (``dask scheduler``, ``dask worker --nworkers 2``) and stopped by it.

* a sweep sent to the cluster (``Parallel(scheduler=)``) equals the in-process sweep (rtol 1e-12);
* a worker killed in the middle of a sweep costs time, not results;
* a scheduler address that does not answer is a named error within seconds, nothing written;
* a two-candidate model selection sent to the cluster equals the in-process one (rtol 1e-12);
* every process the module starts is gone after it (the fixture's finalizer: SIGTERM to each
  process group, SIGKILL after a bounded wait, then a check).

The ``cluster`` fixture (module scope) is shared: further tests that need a cluster go in the
marked place at the end of this file and take its ``address``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
psutil = pytest.importorskip("psutil")

from rbjax import Parallel  # noqa: E402
from rbjax.cli import main  # noqa: E402
from rbjax.studies.sweeps.sweep import run_sweep  # noqa: E402

# A smoke test (tests/conftest.py: compiled with most optimisations off): one program on a cluster
# against the same program in this process.
pytestmark = pytest.mark.xla_smoke

#: Seconds a started process gets to stop after SIGTERM before SIGKILL; to start, to finish.
STOP_S = 10.0
START_S = 60.0
SWEEP_S = 120.0

#: A small elastic study: 64 × (3 + 2) = 320 impacts with L_FE (the quadrature and the sampled
#: history), chunks of 16: about twenty tasks a pass.
CONFIG = {
    "kind": "sobol",
    "seed": 3,
    "outputs": ["contact_time_s", "peak_force_N", "restitution", "lfe_63_dB"],
    "chunk_size": 16,
    "sobol": {"n_base": 64, "second_order": False, "n_bootstrap": 20},
    "ranges": {"youngs_Pa": [1.2e6, 2.0e6], "mass_kg": [2.4, 2.6], "height_m": [0.5, 1.5]},
}


@dataclasses.dataclass
class Cluster:
    address: str
    client: object  # distributed.Client: the test's own view of the cluster
    processes: list  # the subprocess.Popen of the scheduler and the worker command


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _tree(proc: subprocess.Popen) -> list:
    """The process and all its descendants (psutil), while they run."""
    try:
        root = psutil.Process(proc.pid)
        return [root, *root.children(recursive=True)]
    except psutil.NoSuchProcess:
        return []


def _stop(processes: list) -> None:
    """SIGTERM to each started process group, SIGKILL after ``STOP_S``; assert all are gone."""
    started = [p for proc in processes for p in _tree(proc)]
    for proc in processes:
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + STOP_S
    for proc in processes:
        try:
            proc.wait(timeout=max(deadline - time.monotonic(), 0.1))
        except subprocess.TimeoutExpired:
            pass
    _, alive = psutil.wait_procs(started, timeout=max(deadline - time.monotonic(), 0.1))
    for proc in processes:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(timeout=STOP_S)
    for p in alive:
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass
    _, alive = psutil.wait_procs(alive, timeout=STOP_S)
    running = [p.pid for p in alive if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    assert not running, f"processes {running} outlived the cluster fixture"


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A Dask scheduler on 127.0.0.1 (random port, no dashboard) and two worker processes of one
    thread each, in their own process groups; stopped (and checked gone) after the module."""
    folder = tmp_path_factory.mktemp("dask")
    scheduler_file = folder / "scheduler.json"
    env = dict(os.environ, JAX_PLATFORMS="cpu", PYTHONWARNINGS="ignore")
    processes: list[subprocess.Popen] = []
    client = None

    def start(*args, log):
        processes.append(
            subprocess.Popen(
                [sys.executable, "-m", "dask", *args],
                stdout=open(folder / log, "wb"),  # noqa: SIM115  (closed with the process)
                stderr=subprocess.STDOUT,
                env=env,
                cwd=folder,
                start_new_session=True,
            )
        )

    try:
        start(
            "scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            "0",
            "--no-dashboard",
            "--scheduler-file",
            str(scheduler_file),
            log="scheduler.log",
        )
        deadline = time.monotonic() + START_S
        while not scheduler_file.exists():
            assert processes[0].poll() is None, (folder / "scheduler.log").read_text()
            assert time.monotonic() < deadline, "the Dask scheduler did not start"
            time.sleep(0.1)
        time.sleep(0.2)  # the file is written whole, but give it a moment
        address = json.loads(scheduler_file.read_text())["address"]
        start(
            "worker",
            address,
            "--nworkers",
            "2",
            "--nthreads",
            "1",
            "--no-dashboard",
            "--local-directory",
            str(folder),
            log="workers.log",
        )
        client = distributed.Client(address, timeout=START_S)
        client.wait_for_workers(2, timeout=START_S)
        yield Cluster(address, client, processes)
    finally:
        if client is not None:
            client.close()
        _stop(processes)


@pytest.fixture(scope="module")
def reference():
    """The sweep in this process (``Parallel(workers=1)``): what every other way must give."""
    return run_sweep(CONFIG)


def _assert_same(result, reference):
    assert result.n_evaluations == reference.n_evaluations
    for k, v in reference.samples.items():
        np.testing.assert_allclose(result.samples[k], v, rtol=1e-12, atol=0, err_msg=k)
    for o in reference.outputs:
        for field in ("first_order", "total_order", "first_order_ci", "total_order_ci"):
            np.testing.assert_allclose(
                getattr(result, field)[o], getattr(reference, field)[o], rtol=1e-12, err_msg=o
            )


def test_an_address_that_does_not_answer_is_a_named_error_within_seconds(tmp_path, capsys):
    config = tmp_path / "study.toml"
    config.write_text('kind = "sobol"\n[ranges]\nmass_kg = [2.4, 2.6]\n')
    out = tmp_path / "study.json"
    address = f"tcp://127.0.0.1:{_closed_port()}"
    start = time.monotonic()
    code = main(["sweep", str(config), "--scheduler", address, "--out", str(out), "--devices", "1"])
    seconds = time.monotonic() - start
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("rbjax: error:") and address in err and "no Dask scheduler" in err
    assert seconds < 10.0, f"{seconds:.1f} s to give up"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study.toml"]  # nothing written


def test_a_sweep_on_the_cluster_equals_the_in_process_sweep(cluster, reference):
    result = run_sweep(CONFIG, parallel=Parallel(scheduler=cluster.address))
    _assert_same(result, reference)
    ran = cluster.client.run(lambda: "rbjax.studies.sweeps.sweep" in sys.modules)
    assert any(ran.values()), "no chunk ran on a Dask worker"


def test_a_worker_killed_in_the_middle_of_a_sweep_costs_time_not_results(cluster, reference):
    client = cluster.client
    pids = client.run(os.getpid)  # worker address → pid of the worker process
    box: dict = {}

    def sweep():
        try:
            box["result"] = run_sweep(CONFIG, parallel=Parallel(scheduler=cluster.address))
        except BaseException as err:  # noqa: BLE001  (reported by the test below)
            box["error"] = err

    thread = threading.Thread(target=sweep, daemon=True)
    thread.start()
    victim = None
    deadline = time.monotonic() + SWEEP_S
    while victim is None and thread.is_alive() and time.monotonic() < deadline:
        busy = [addr for addr, keys in client.processing().items() if keys and addr in pids]
        if busy:
            victim = pids[busy[0]]
            os.kill(victim, signal.SIGKILL)
        else:
            time.sleep(0.005)
    assert victim is not None, "the sweep ended before a worker could be killed"
    assert thread.is_alive(), "the sweep ended as the worker was killed: not in the middle"
    thread.join(SWEEP_S)
    assert not thread.is_alive(), "the sweep did not finish after a worker died"
    assert "error" not in box, box.get("error")
    assert not psutil.pid_exists(victim) or psutil.Process(victim).status() == "zombie"
    _assert_same(box["result"], reference)
    client.wait_for_workers(2, timeout=START_S)  # the nanny started a new worker process
    assert victim not in client.run(os.getpid).values()


# ----------------------------------------------------------------------------------------------
# A model selection on the same cluster


def test_a_two_candidate_selection_on_the_cluster_equals_the_in_process_one(cluster):
    from rbjax.data import examples_dir
    from rbjax.fit import load_data, prepare_data
    from rbjax.studies import select_model

    files = [examples_dir() / f"h{h:03d}_d1.csv" for h in (10, 40, 100)]
    data = prepare_data(load_data(files))
    kwargs = dict(blocked_forces=("paper",), progress=False)
    here = select_model(data, ["paper", "kelvin-voigt"], parallel=Parallel(workers=1), **kwargs)
    there = select_model(
        data, ["paper", "kelvin-voigt"], parallel=Parallel(scheduler=cluster.address), **kwargs
    )
    assert there.recommended.label == here.recommended.label
    for a, b in zip(here.candidates, there.candidates, strict=True):
        assert b.label == a.label
        np.testing.assert_allclose(b.fold_errors_pct, a.fold_errors_pct, rtol=1e-12, atol=0)
        np.testing.assert_allclose(b.fit.theta, a.fit.theta, rtol=1e-12, atol=0)
    ran = cluster.client.run(lambda: "rbjax.studies.selection.select" in sys.modules)
    assert any(ran.values()), "no fit ran on a Dask worker"

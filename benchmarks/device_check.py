"""One prepared run for a machine with an accelerator (e.g. one H100 beside 16 CPU cores): the
library's throughput on the accelerator and on the same machine's CPU, with one JAX CPU device
and with one per core, in under 8 minutes, without the network.

Each measurement runs in a subprocess of its own, with its environment set before JAX starts:

* ``accelerator``: JAX's default platform (skipped, and said so, where JAX sees no GPU/TPU);
* ``cpu, all devices``: ``JAX_PLATFORMS=cpu``, ``JAX_NUM_CPU_DEVICES`` = the usable cores
  (``simulate`` and ``evaluate`` split their batches over them, ``rbjax.solve.devices``);
* ``cpu, 1 device``: ``JAX_PLATFORMS=cpu``, ``JAX_NUM_CPU_DEVICES=1``.

Steps, in this order, each with its own timeout (and none started once the run's budget is
spent: 450 s, quick 125 s):

1. forward throughput of ``rbjax.simulate`` (scalar outputs at its defaults: the quadrature for
   the elastic model, the phase-angle path for Zener and Hunt–Crossley) at 10⁴, 10⁵ and 10⁶
   impacts (quick: 10⁴, elastic and Zener), first call (compile: no persistent cache) and best of
   the repeats; then the force histories and their octave-band L_FE
   (``ImpactResult.lfe_octave_dB()``: the contact samples of the 44.1 kHz × 1 s record) and
   ``evaluate(..., lfe=True)`` at 10³ and 10⁴ impacts (quick: 10³, elastic), per configuration;
2. ``rbjax fit src/rbjax/examples/emulated-rubber-ball --model hunt-crossley+ball-mode
   --blocked-force momentum``, cold (an empty ``RBJAX_CACHE_DIR``) then warm (the same cache),
   per configuration (quick: ``cpu, all devices`` only);
3. the full selection ``rbjax select src/rbjax/examples/emulated-rubber-ball``, cold then warm:
   on the accelerator with ``--batch-fits`` (every fit a lane of one batched program per
   structure, :mod:`rbjax.fit.batching`), on the CPU with ``--workers N`` (N: the usable cores);
   quick: one candidate; a command line that fails is reported with its error.

Prints a table and writes ``$OUT/device_check.json`` where ``OUT`` is set, else
``benchmarks/results/device_check.json`` (quick: ``device_check_quick.json``).

Run: ``.venv/bin/python benchmarks/device_check.py [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
EXAMPLE = REPO / "src" / "rbjax" / "examples" / "emulated-rubber-ball"
FIT_ARGS = ["--model", "hunt-crossley+ball-mode", "--blocked-force", "momentum"]
QUICK_CANDIDATES = ["--candidates", "hunt-crossley", "--blocked-force", "momentum"]
BUDGET_S = {"full": 450.0, "quick": 125.0}
#: (step, timeout in s) per mode.
TIMEOUTS = {
    "full": {"probe": 60, "forward": 150, "fit": 120, "select": 200},
    "quick": {"probe": 40, "forward": 60, "fit": 45, "select": 60},
}
MODELS = ("elastic", "zener", "hunt-crossley")


def usable_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def environment(config: str) -> dict:
    """The environment of a subprocess of ``config`` (set before its JAX starts): no
    compilation cache of the caller's (a step that wants one sets its own)."""
    drop = ("JAX_PLATFORMS", "JAX_NUM_CPU_DEVICES", "JAX_COMPILATION_CACHE_DIR", "RBJAX_CACHE_DIR")
    env = {k: v for k, v in os.environ.items() if k not in drop}
    flags = [f for f in env.get("XLA_FLAGS", "").split() if "device_count" not in f]
    env["XLA_FLAGS"] = " ".join(flags)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO / "src"), env.get("PYTHONPATH")]))
    if config != "accelerator":
        env["JAX_PLATFORMS"] = "cpu"
        env["JAX_NUM_CPU_DEVICES"] = "1" if config == "cpu, 1 device" else str(usable_cores())
    return env


# ------------------------------------------------------------------------------------------------
# the measurements, inside the subprocesses (``--worker``): one JSON line per result


def _emit(**row) -> None:
    print(json.dumps(row), flush=True)


def _timed(fn, min_total_s: float = 1.0, max_repeats: int = 5) -> tuple[float, float, object]:
    """(first call s, best repeat s, output): repeats until ``min_total_s`` or ``max_repeats``."""
    t0 = time.perf_counter()
    out = fn()
    first = time.perf_counter() - t0
    times: list[float] = []
    while not times or (sum(times) < min_total_s and len(times) < max_repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return first, min(times), out


def worker_forward(
    names: list[str], sizes: list[int], history: list[str], history_sizes: list[int], deadline
) -> None:
    import jax
    import numpy as np

    import rbjax
    from rbjax.solve import evaluate

    devices = jax.local_devices()
    _emit(
        kind="devices",
        backend=jax.default_backend(),
        count=len(devices),
        device=str(devices[0].device_kind),
    )
    models = {
        "elastic": rbjax.Model(),
        "zener": rbjax.Model(
            damping=rbjax.Zener(stiffness_ratio=0.3, relaxation_time_s=2e-3),
            blocked_force="momentum",
        ),
        "hunt-crossley": rbjax.Model(damping=rbjax.HuntCrossley(alpha_s_per_m=0.3)),
    }
    for n in sizes:
        heights = np.linspace(0.1, 1.6, n)
        for name in names:
            if time.time() > deadline:
                _emit(kind="skipped", what=f"forward {name} {n}", why="step's time is up")
                continue

            def run(model=models[name]):
                r = rbjax.simulate(heights, model=model)
                return r.method, np.asarray(r.contact_time_s)

            first, best, (method, tc) = _timed(run)
            _emit(
                kind="forward",
                model=name,
                impacts=n,
                method=method,
                first_s=first,
                best_s=best,
                per_s=n / best,
                failed=int(np.sum(~np.isfinite(tc))),
            )
    for n in history_sizes:
        heights = np.linspace(0.1, 1.6, n)
        for name in history:
            if time.time() > deadline:
                _emit(kind="skipped", what=f"histories {name} {n}", why="step's time is up")
                continue
            result = rbjax.simulate(heights, model=models[name])
            first, best, _ = _timed(lambda r=result: np.asarray(r.lfe_octave_dB()))
            _emit(
                kind="lfe_octave (history + bands)",
                model=name,
                impacts=n,
                first_s=first,
                best_s=best,
                per_s=n / best,
            )
            first, best, _ = _timed(
                lambda m=models[name]: evaluate({"height_m": heights}, model=m, lfe=True)
            )
            _emit(
                kind="evaluate lfe=True",
                model=name,
                impacts=n,
                first_s=first,
                best_s=best,
                per_s=n / best,
            )


# ------------------------------------------------------------------------------------------------
# the steps, from the parent


class Budget:
    def __init__(self, seconds: float):
        self.end = time.time() + seconds

    def left(self) -> float:
        return self.end - time.time()


def _run(cmd: list[str], env: dict, timeout: float) -> dict:
    """Run ``cmd``; wall time, exit code, the stdout (also what came before a timeout) and the
    tail of stderr."""
    t0 = time.perf_counter()
    # a session of its own: on timeout, the command and its worker processes go together
    proc = subprocess.Popen(
        cmd,
        env=env,
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=timeout)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        code = "timeout"
    return {
        "wall_s": time.perf_counter() - t0,
        "exit": code,
        "stdout": out,
        "stderr_tail": err[-1500:],
        "timeout_s": timeout,
    }


def probe(budget: Budget, timeouts: dict) -> dict:
    """What JAX sees by default (the accelerator, if any) and on the CPU."""
    code = (
        "import json, jax; d = jax.devices(); "
        "print(json.dumps({'backend': jax.default_backend(), 'count': len(d), "
        "'device': str(d[0].device_kind)}))"
    )
    run = _run(
        [sys.executable, "-c", code],
        environment("accelerator"),
        min(timeouts["probe"], budget.left()),
    )
    try:
        seen = json.loads(run["stdout"].strip().splitlines()[-1])
    except (IndexError, ValueError):
        seen = {"backend": "unknown", "error": run["stderr_tail"]}
    seen["accelerator"] = seen.get("backend") not in ("cpu", "unknown")
    return seen


def forward_step(config: str, quick: bool, budget: Budget, timeouts: dict) -> dict:
    """Step 1, in a subprocess of ``config`` (no persistent compilation cache: the first call
    compiles)."""
    timeout = min(timeouts["forward"], budget.left())
    if timeout < 10:
        return {"skipped": "the run's time budget is spent"}
    sizes = [10_000] if quick else [10_000, 100_000, 1_000_000]
    history = [1_000] if quick else [1_000, 10_000]
    cmd = [
        sys.executable,
        str(Path(__file__).resolve()),
        "--worker",
        "forward",
        "--models",
        "elastic,zener" if quick else ",".join(MODELS),
        "--sizes",
        ",".join(map(str, sizes)),
        "--history-models",
        "elastic" if quick else "elastic,zener",
        "--history-sizes",
        ",".join(map(str, history)),
        "--deadline",
        str(time.time() + timeout - 5),
    ]
    run = _run(cmd, environment(config), timeout)
    rows = []
    for line in run.pop("stdout").splitlines():
        try:
            rows.append(json.loads(line))
        except ValueError:
            pass
    return run | {"rows": rows}


def cli_step(config: str, argv: list[str], budget: Budget, timeout: float, cache: str) -> dict:
    timeout = min(timeout, budget.left())
    if timeout < 10:
        return {"skipped": "the run's time budget is spent"}
    env = environment(config) | {"RBJAX_CACHE_DIR": cache}
    run = _run([sys.executable, "-m", "rbjax.cli", *argv, "--json"], env, timeout)
    summary = {}
    try:
        out = json.loads(run.pop("stdout"))
        if "selection" in out:
            summary["recommended"] = out["selection"]["recommended"]
            summary["candidates"] = len(out["selection"]["candidates"])
        else:
            summary["residual_rms_N"] = out.get("residual_rms_N")
            summary["converged"] = out.get("converged")
    except (ValueError, KeyError, TypeError):
        pass
    return run | summary


def fit_step(config: str, budget: Budget, timeouts: dict) -> dict:
    argv = ["fit", str(EXAMPLE), *FIT_ARGS, "--quiet"]
    with tempfile.TemporaryDirectory(prefix="rbjax-device-check-") as cache:
        cold = cli_step(config, argv, budget, timeouts["fit"], cache)
        warm = cli_step(config, argv, budget, timeouts["fit"], cache)
    return {"cold": cold, "warm": warm}


def select_step(config: str, quick: bool, budget: Budget, timeouts: dict) -> dict:
    """The selection cold then warm: on the accelerator its fits as lanes of batched programs
    (``--batch-fits``, the default there), on the CPU in one worker process per core."""
    where = ["--batch-fits"] if config == "accelerator" else ["--workers", str(usable_cores())]
    argv = ["select", str(EXAMPLE), *where, "--quiet"]
    argv += QUICK_CANDIDATES if quick else []
    with tempfile.TemporaryDirectory(prefix="rbjax-device-check-") as cache:
        cold = cli_step(config, argv, budget, timeouts["select"], cache)
        warm = cli_step(config, argv, budget, timeouts["select"], cache)
    return {"cold": cold, "warm": warm, "where": " ".join(where)}


# ------------------------------------------------------------------------------------------------
# the report


def _fmt(x, spec) -> str:
    return "—" if x is None else format(x, spec)


def table(report: dict) -> str:
    lines = ["| step | configuration | what | time | rate | note |", "|---|---|---|---|---|---|"]
    for config, step in report["forward"].items():
        if "skipped" in step:
            lines.append(f"| forward | {config} | — | — | — | {step['skipped']} |")
            continue
        devices = next((r for r in step["rows"] if r["kind"] == "devices"), {})
        where = f"{devices.get('count', '?')} × {devices.get('device', '?')}"
        for r in step["rows"]:
            if r["kind"] == "skipped":
                lines.append(f"| forward | {config} | {r['what']} | — | — | {r['why']} |")
            elif r["kind"] != "devices":
                what = f"{r['kind']} {r['model']} {r['impacts']:,}"
                note = r.get("method", "") + (f", {r['failed']} NaN" if r.get("failed") else "")
                lines.append(
                    f"| forward | {config} ({where}) | {what} | first {r['first_s']:.2f} s, "
                    f"best {r['best_s']:.3f} s | {r['per_s']:,.0f}/s | {note} |"
                )
        if step.get("exit") not in (0, None):
            lines.append(f"| forward | {config} | — | — | — | exit {step['exit']} |")
    for config, step in report["fit"].items():
        for phase in ("cold", "warm"):
            s = step[phase]
            if "skipped" in s:
                lines.append(f"| fit ({phase}) | {config} | — | — | — | {s['skipped']} |")
                continue
            note = f"exit {s['exit']}, rms {_fmt(s.get('residual_rms_N'), '.4g')} N"
            lines.append(
                f"| fit ({phase}) | {config} | hunt-crossley+ball-mode/momentum | "
                f"{s['wall_s']:.1f} s | — | {note} |"
            )
    for config, step in report["select"].items():
        for phase in ("cold", "warm"):
            s = step[phase]
            if "skipped" in s:
                lines.append(f"| select ({phase}) | {config} | — | — | — | {s['skipped']} |")
                continue
            rec = s.get("recommended")
            note = f"exit {s['exit']}" + (
                f", recommended {rec['model_name']}/{rec['blocked_force']}" if rec else ""
            )
            if s["exit"] != 0:
                note += ": " + " ".join(s["stderr_tail"].split())[-200:]
            lines.append(
                f"| select {step['where']} ({phase}) | {config} | {s.get('candidates', '?')} "
                f"candidates | {s['wall_s']:.1f} s | — | {note} |"
            )
    return "\n".join(lines)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="the local smoke run (~2 min)")
    p.add_argument("--worker", choices=("forward",), help=argparse.SUPPRESS)
    p.add_argument("--models", default=",".join(MODELS), help=argparse.SUPPRESS)
    p.add_argument("--sizes", default="", help=argparse.SUPPRESS)
    p.add_argument("--history-models", default="elastic,zener", help=argparse.SUPPRESS)
    p.add_argument("--history-sizes", default="", help=argparse.SUPPRESS)
    p.add_argument("--deadline", type=float, default=0.0, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.worker == "forward":
        ints = lambda s: [int(x) for x in s.split(",") if x]  # noqa: E731
        names, history = args.models.split(","), args.history_models.split(",")
        worker_forward(names, ints(args.sizes), history, ints(args.history_sizes), args.deadline)
        return 0

    mode = "quick" if args.quick else "full"
    timeouts, budget, t0 = TIMEOUTS[mode], Budget(BUDGET_S[mode]), time.perf_counter()
    seen = probe(budget, timeouts)
    configs = ["cpu, all devices", "cpu, 1 device"]
    if seen["accelerator"]:
        configs.insert(0, "accelerator")
        print(f"accelerator: {seen['count']} × {seen['device']} ({seen['backend']})", flush=True)
    else:
        print(
            f"no accelerator: JAX's default backend is {seen.get('backend')!r}; "
            "measuring the CPU only",
            flush=True,
        )
    report = {
        "mode": mode,
        "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "cores": usable_cores(),
        "probe": seen,
        "forward": {},
        "fit": {},
        "select": {},
    }
    for config in configs:
        print(f"forward: {config} …", flush=True)
        report["forward"][config] = forward_step(config, args.quick, budget, timeouts)
    for config in ["cpu, all devices"] if args.quick else configs:
        print(f"fit: {config} …", flush=True)
        report["fit"][config] = fit_step(config, budget, timeouts)
    for config in ["cpu, all devices"] if args.quick else configs[:-1]:
        print(f"select: {config} …", flush=True)
        report["select"][config] = select_step(config, args.quick, budget, timeouts)
    report["wall_s"] = time.perf_counter() - t0
    print()
    print(table(report))
    print(f"\nwall {report['wall_s']:.0f} s (budget {BUDGET_S[mode]:.0f} s)")
    out_dir = Path(os.environ["OUT"]) if os.environ.get("OUT") else HERE / "results"
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / ("device_check.json" if mode == "full" else "device_check_quick.json")
    path.write_text(json.dumps(report, indent=1) + "\n")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

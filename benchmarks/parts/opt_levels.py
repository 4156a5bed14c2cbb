"""The difference XLA's optimisation level makes, per solve path (issue 34).

The tests compile at XLA's default optimisation (as users do); smoke tests compile with
``JAX_DISABLE_MOST_OPTIMIZATIONS=1``. This script computes the same outputs at both levels, each
in a fresh process with no compilation cache, and prints the largest absolute and relative
difference per path and output: the scalars (contact time, peak force, restitution) of the
quadrature, the phase-angle and the ODE paths (rigid floor, ball mode, a moving floor), the
sampled and the ODE force histories, their octave L_FE, gradients (``jax.grad`` of the contact
time in E, the README's un-jitted example, on each path; forward mode on the ODE) and a fit of
the bundled recordings (its parameters).

    python benchmarks/accuracy.py --only opt_levels   # both levels, the table (a few minutes)

``--quick``: the quadrature path, its sampled history and its gradient only (the ODE and phase-angle
programs take most of the minutes to compile, twice).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import numpy as np

from _common import write_json

HEIGHTS_M = [0.05, 0.2, 0.5, 1.0, 1.6]


def compute(quick: bool = False) -> dict[str, np.ndarray]:
    import jax
    import jax.numpy as jnp

    import rbjax
    from rbjax.data import examples_dir
    from rbjax.fit import fit

    ball = rbjax.JIS_RUBBER_BALL
    out: dict[str, np.ndarray] = {}

    def scalars(path, res):
        for k in ("contact_time_s", "peak_force_N", "restitution"):
            out[f"{path}|{k}"] = np.asarray(getattr(res, k))

    quad = rbjax.simulate(HEIGHTS_M, path="quadrature")
    scalars("quadrature", quad)
    out["sampled|force_N"] = np.asarray(quad.history(rate_Hz=44_100.0, duration_s=0.05).force_N)
    out["sampled|lfe_octave_dB"] = np.asarray(quad.lfe_octave_dB())

    def tc(E, **kw):
        return rbjax.simulate(1.0, ball.replace(youngs_Pa=E), **kw).contact_time_s

    out["quadrature|grad"] = np.asarray(jax.grad(tc)(1.6e6))  # the README's example, un-jitted
    if quick:
        return out
    zener = dict(damping=rbjax.Zener(0.3, 1e-3), blocked_force="momentum")
    hunt = dict(damping=rbjax.HuntCrossley(0.05), blocked_force="momentum")  # the angle path's
    scalars("angle", rbjax.simulate(HEIGHTS_M, path="angle", **hunt))
    ode = rbjax.simulate(HEIGHTS_M, path="ode", **zener)
    scalars("ode", ode)
    out["ode-sampled|force_N"] = np.asarray(ode.history(rate_Hz=44_100.0, duration_s=0.05).force_N)
    mode = rbjax.simulate(
        HEIGHTS_M, blocked_force="momentum", ball_mode=rbjax.BallMode(12.0, 450.0, 0.3)
    )
    scalars("ode-ball-mode", mode)
    floor = rbjax.simulate(HEIGHTS_M, floor=rbjax.InfinitePlate(0.015, 4.9e9, 600.0, 0.3))
    scalars("ode-floor", floor)
    out["ode-floor|force_N"] = np.asarray(floor.history(rate_Hz=44_100.0, duration_s=0.05).force_N)

    out["angle|grad"] = np.asarray(jax.grad(lambda E: tc(E, path="angle", **hunt))(1.6e6))
    fwd = rbjax.Solver(adjoint="forward")
    out["ode|grad (jacfwd)"] = np.asarray(
        jax.jacfwd(lambda E: tc(E, solver=fwd, **zener))(jnp.asarray(1.6e6))
    )
    res = fit(examples_dir(), "hunt-crossley", blocked_force="momentum", progress=False)
    for name, p in res.parameters.items():
        if not p.fixed:
            out[f"fit|{name}"] = np.asarray(p.value)
    out["fit|residual_rms_N"] = np.asarray(res.residual_rms_N)
    return out


def _run(level: str, path: str, quick: bool) -> None:
    env = dict(os.environ, JAX_DISABLE_MOST_OPTIMIZATIONS=level, RBJAX_CACHE_DIR="")
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    code = (
        f"import sys; sys.path[:0] = [{here!r}]; import numpy as np; "
        f"from parts.opt_levels import compute; np.savez({path!r}, **compute({quick!r}))"
    )
    subprocess.run([sys.executable, "-c", code], env=env, check=True)


def main(quick: bool = False) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        paths = {lv: os.path.join(tmp, f"level{lv}.npz") for lv in ("0", "1")}
        for level, path in paths.items():
            _run(level, path, quick)
        opt, low = (np.load(paths[lv]) for lv in ("0", "1"))
        rows = {}
        print(
            "| path | output | max abs difference | max rel. difference (histories: of the peak) |"
        )
        print("|---|---|---|---|")
        for key in opt.files:
            a, b = opt[key], low[key]
            assert np.array_equal(np.isnan(a), np.isnan(b)) and not np.any(np.isnan(a)), key
            diff = np.abs(a - b)
            if key.endswith("force_N"):  # histories: relative to each record's peak
                scale = np.max(np.abs(a), axis=-1, keepdims=True)
            else:
                scale = np.abs(a)
            rel = float(np.max(diff / np.where(scale > 0, scale, 1.0)))
            path, output = key.split("|")
            rows[key] = (float(np.max(diff)), rel)
            print(f"| {path} | {output} | {rows[key][0]:.2g} | {rel:.2g} |")
        name = "opt_levels" + ("_quick" if quick else "")
        print(f"wrote {write_json(name, {'max_abs_rel': rows})}")

"""Octave-band L_FE of a 1 s record (44.1 kHz) from its contact samples: the padded FFT (the
record zero-padded to 44 100 samples, ``lfe_octave_dB(padded, rate)``) against the short FFT and
band kernel (``lfe_octave_dB(contact, rate, n_record=44_100)``), which must give the same numbers.

Records: half-sine pulses of 4.0–5.8 ms (random duration and amplitude, fixed seed) in the first
256 samples, and, for the ball's ~20 ms contact, 20–23 ms pulses in the first 1024 samples.
Both paths are jitted; timings are warm medians, the first call (compile, and for the new path
the kernel build) is reported apart.

Prints a table and writes ``results/pulse_spectrum.json``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from rbjax.spectrum import lfe_octave_dB

from _common import finish_machine_info, machine_info, table, time_call, write_json

RATE_HZ = 44_100.0
N_RECORD = 44_100  # 1 s
CASES = [(256, 4.0e-3, 5.8e-3, 1000), (256, 4.0e-3, 5.8e-3, 10_000), (1024, 20e-3, 23e-3, 1000)]


def pulses(n: int, t_min_s: float, t_max_s: float, batch: int) -> np.ndarray:
    rng = np.random.default_rng(n + batch)
    duration = rng.uniform(t_min_s, t_max_s, (batch, 1))
    amplitude = rng.uniform(200.0, 2000.0, (batch, 1))
    t = np.arange(n) / RATE_HZ
    return np.where(
        t <= duration, amplitude * np.sin(np.pi * np.minimum(t, duration) / duration), 0.0
    )


def main(quick: bool = False) -> None:
    info = machine_info()
    padded_fn = jax.jit(
        lambda x: lfe_octave_dB(jnp.pad(x, ((0, 0), (0, N_RECORD - x.shape[-1]))), RATE_HZ)
    )
    short_fn = jax.jit(lambda x: lfe_octave_dB(x, RATE_HZ, n_record=N_RECORD))
    rows, out = [], {}
    for n, t_min, t_max, batch in [(256, 4.0e-3, 5.8e-3, 100)] if quick else CASES:
        x = jnp.asarray(pulses(n, t_min, t_max, batch))
        t_pad = time_call(lambda: padded_fn(x), max_repeats=5)
        t_short = time_call(lambda: short_fn(x))
        diff_dB = float(np.max(np.abs(np.asarray(t_short["out"]) - np.asarray(t_pad["out"]))))
        key = f"n{n}_batch{batch}"
        out[key] = {"n_contact": n, "batch": batch, "max_abs_diff_dB": diff_dB}
        for path, t in (("padded FFT (44 100)", t_pad), ("short FFT + band kernel", t_short)):
            per_s = batch / t["median_s"]
            out[key][path] = {
                "median_s": t["median_s"],
                "impacts_per_s": per_s,
                "first_call_s": t["first_s"],
            }
            rows.append(
                [
                    path,
                    n,
                    f"{batch:,}",
                    f"{1e3 * t['median_s']:.1f}",
                    f"{per_s:,.0f}",
                    f"{t['first_s']:.2f}",
                    f"{diff_dB:.1e}",
                ]
            )
            print(rows[-1], flush=True)
        out[key]["speedup"] = t_pad["median_s"] / t_short["median_s"]
    print(
        table(
            [
                "path",
                "contact samples",
                "batch",
                "ms/batch",
                "impacts/s",
                "first call (s)",
                "max |ΔL_FE| (dB)",
            ],
            rows,
        )
    )
    out["machine"] = finish_machine_info(info)
    m = out["machine"]
    print(
        f"machine: {m['date']}, {m['cpu_model']} ×{m['nproc']}, jax {m['jax']}, load "
        f"{m['loadavg_start']} → {m['loadavg_end']}"
    )
    print(f"wrote {write_json('pulse_spectrum' + ('_quick' if quick else ''), out)}")

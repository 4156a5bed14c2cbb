"""The force on several floors against the blocked force on the rigid one: histories, octave-band
L_FE and their difference, in three panels."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.levels import lfe_octave_dB
from .axes import colours, finish

__all__ = ["plot_floors"]


def plot_floors(results: Mapping[str, object], blocked=None, axes=None, *, title=None):
    """The force on several floors against the blocked force: force histories, octave-band
    L_FE and L_FE on the floor minus L_FE of the blocked force (three panels).

    ``results``: label → ``ImpactResult`` of one drop height on that floor (the first height of
    a batch is drawn); ``blocked``: the ``ImpactResult`` on the rigid floor (default: the entry
    of ``results`` whose floor is rigid), drawn in black. ``axes``: three axes (a new figure is
    made without them). Returns the figure.
    """

    if blocked is None:
        rigid = [r for r in results.values() if r.model.floor.rigid]  # type: ignore[attr-defined]
        if not rigid:
            raise ValueError(
                "plot_floors: no result on the rigid floor; pass blocked=rbjax.simulate(h) (the "
                "blocked force)"
            )
        blocked = rigid[0]
    if axes is None:
        # lazy: matplotlib.pyplot costs ~1 s at import
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, 3, figsize=(14.0, 4.2), layout="constrained")
    fig = axes[0].figure

    def first(result):
        traj = result.history()
        n = traj.force_N.shape[-1]
        force = np.asarray(traj.force_N, dtype=float).reshape(-1, n)[0]
        tc = float(np.asarray(result.contact_time_s, dtype=float).reshape(-1)[0])
        return (
            np.asarray(traj.time_s, dtype=float),
            force,
            tc,
            np.asarray(lfe_octave_dB(force, result.rate_Hz), dtype=float),
        )

    t, f0, tc0, lfe0 = first(blocked)
    curves = [(label, first(r)) for label, r in results.items() if r is not blocked]
    longest = max([tc0, *(c[1][2] for c in curves if np.isfinite(c[1][2]))])
    x = np.arange(len(OCTAVE_BANDS))
    ax_f, ax_l, ax_d = axes
    blocked_style = dict(color="k", ls="--", lw=1.4, label="blocked (rigid floor)")
    keep = t <= 1.1 * longest
    ax_f.plot(t[keep] * 1e3, f0[keep], **blocked_style)
    ax_l.plot(x, lfe0, marker="o", **blocked_style)
    for (label, (_, force, _, lfe)), c in zip(curves, colours(len(curves))):
        ax_f.plot(t[keep] * 1e3, force[keep], color=c, lw=1.2, label=label)
        ax_l.plot(x, lfe, marker="o", color=c, label=label)
        ax_d.plot(x, lfe - lfe0, marker="o", color=c, label=label)
    ax_f.set_xlim(0.0, 1.05e3 * longest)
    ax_f.set_ylim(bottom=0.0)
    ax_d.axhline(0.0, color="k", lw=0.8)
    for ax in (ax_l, ax_d):
        ax.set_xticks(x, list(OCTAVE_BANDS))
    h = float(np.asarray(blocked.height_m, dtype=float).reshape(-1)[0])
    finish(fig, ax_f, "time (ms)", "force on the floor (N)", f"drop height {h * 100:.0f} cm")
    finish(fig, ax_l, "octave band centre frequency (Hz)", "L_FE (dB re 1 N²s)", None)
    finish(fig, ax_d, "octave band centre frequency (Hz)", "L_FE − L_FE,blocked (dB)", None)
    if title:
        fig.suptitle(title)
    return fig

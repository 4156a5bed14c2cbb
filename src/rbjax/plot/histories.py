"""Force histories over the contact: the blocked force at several drop heights (an
``ImpactResult``'s own figure) and named force components against time (paper Fig. 3)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .axes import colours, figure_and_axes, finish

__all__ = ["plot_force_histories", "plot_histories", "plot_force_components"]


def _contact_window(t_ms, values, contact_time_s, margin=1.1):
    """Only the samples up to ``margin`` × the longest contact (the rest of a 1 s record is
    zeros)."""
    if contact_time_s is None or not np.any(np.isfinite(contact_time_s)):
        return t_ms, values
    keep = t_ms <= margin * 1e3 * float(np.nanmax(contact_time_s))
    return t_ms[keep], values[..., keep]


def plot_force_histories(time_s, force_N, heights_m, ax=None, *, contact_time_s=None, title=None):
    """Force (N) against time (ms), one line per drop height (rows of ``force_N``)."""
    fig, ax = figure_and_axes(ax)
    t_ms = np.asarray(time_s, dtype=float) * 1e3
    force = np.atleast_2d(np.asarray(force_N, dtype=float))
    heights = np.atleast_1d(np.asarray(heights_m, dtype=float)).reshape(-1)
    t_ms, force = _contact_window(t_ms, force, contact_time_s)
    for f, h, c in zip(force, heights, colours(len(heights))):
        ax.plot(t_ms, f, color=c, lw=1.2, label=f"{h * 100:.0f} cm")
    if contact_time_s is not None and np.any(np.isfinite(contact_time_s)):
        ax.set_xlim(0.0, 1.05e3 * float(np.nanmax(contact_time_s)))
    ax.set_ylim(bottom=0.0)
    where = (
        {"loc": "center left", "bbox_to_anchor": (1.01, 0.5)}
        if len(heights) > 6
        else {"loc": "upper right"}
    )
    return finish(
        fig, ax, "time (ms)", "blocked force (N)", title, legend={"title": "drop height", **where}
    )


def plot_histories(result, ax=None, rate_Hz=None):
    """Blocked-force histories of an ``ImpactResult`` over the contact, one line per height.

    Used by ``ImpactResult.plot()``. ``rate_Hz`` (default: the result's, 44.1 kHz as in §2.4)
    sets the sampling of the plotted histories.
    """
    traj = result.history(rate_Hz=rate_Hz)
    heights = np.asarray(result.height_m, dtype=float).reshape(-1)
    force = np.asarray(traj.force_N, dtype=float).reshape(heights.size, -1)
    tc = np.asarray(result.contact_time_s, dtype=float)
    return plot_force_histories(
        np.asarray(traj.time_s),
        force,
        heights,
        ax,
        contact_time_s=tc,
        title=f"rbjax: model {result.model.name}, gas {result.model.gas}",
    )


def plot_force_components(
    time_s,
    forces: Mapping[str, np.ndarray],
    ax=None,
    *,
    contact_time_s=None,
    title=None,
    styles=None,
):
    """Named force histories (e.g. F_T, F_B, F_G; paper Fig. 3) in N against time in ms."""
    fig, ax = figure_and_axes(ax)
    t_ms = np.asarray(time_s, dtype=float) * 1e3
    styles = styles or {}
    for name, f in forces.items():
        t, f = _contact_window(t_ms, np.asarray(f, dtype=float), contact_time_s)
        ax.plot(t, f, label=name, **styles.get(name, {}))
    if contact_time_s is not None:
        ax.set_xlim(0.0, 1.05e3 * float(contact_time_s))
    return finish(fig, ax, "time (ms)", "force (N)", title)

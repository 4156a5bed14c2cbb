"""Growth of L_FE per doubling of the drop height, per band (paper §4.2, Figs. 10–11).

The slope b of the least-squares line L_FE(h) = a + b·log2(h/h_ref), band by band, is the
increase of the force exposure level per doubling of the drop height, with its standard error
from the residual scatter. A linear source (fixed pulse shape, amplitude ∝ impact speed
√(2gh), Eq. 10) gives 10·log10 2 = 3.01 dB in every band; the paper finds about 3 dB for its
elastic model (5 dB at 63 Hz, where the contact resonance moves) and, for the measured ball,
about 3 dB at 31.5 Hz rising to almost 15 dB at 1 kHz: the real ball is not a linear source.

* :func:`growth_per_doubling_dB`: the fit, on any (heights, levels) table; several levels per
  height (repeated drops) are welcome and give the standard error its meaning.
* :func:`recording_growth`: the same for force-plate recordings (default: the bundled
  emulated recordings, one point per drop), L_FE read off the conditioned records exactly as
  :mod:`rbjax.fit` reads them (30 ms window from 3 ms before the onset, zero-padded to 1 s).
* :func:`model_growth`: the same for a model simulated at given heights (the 44.1 kHz × 1 s
  blocked-force records of the paper's §2.4).

A linear, height-independent filter (the 1250 Hz low-pass of a measuring chain) shifts every
height's level in a band by the same amount, so it leaves the slope unchanged; the slopes of
filtered recordings and of unfiltered model records are comparable.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from ..data import load_examples
from ..fit import prepare_data
from ..solve.inputs import PAPER_RATE_Hz, check_inputs
from ..solve.path import resolve_path
from ..solve.simulate import simulate, simulate_model
from ..solve.solver import Solver
from ..spectrum.bands import OCTAVE_BANDS
from ..spectrum.levels import lfe_octave_dB
from ..terms.ball import JIS_RUBBER_BALL, Ball

__all__ = [
    "LINEAR_SOURCE_dB",
    "GrowthError",
    "Growth",
    "growth_per_doubling_dB",
    "growth_table",
    "model_lfe_dB",
    "recording_lfe_dB",
    "recording_growth",
    "model_growth",
]

#: Growth per doubling of a linear source: 20·log10 √2 = 10·log10 2 dB.
LINEAR_SOURCE_dB = 10.0 * math.log10(2.0)


class GrowthError(ValueError):
    """The growth per doubling cannot be computed from these inputs (e.g. one height only)."""


@dataclasses.dataclass(frozen=True)
class Growth:
    """L_FE growth per doubling of the drop height, one value per band.

    Attributes:
        bands_Hz: nominal band labels (``"31.5"``, ``"63"``, …).
        slope_dB: least-squares slope of L_FE against log2(h/h_ref): dB per doubling.
        stderr_dB: its standard error, √(s²/Σ(u − ū)²), s² = RSS/(N − 2); NaN where N = 2.
        intercept_dB: the fitted L_FE at ``ref_height_m``.
        residual_rms_dB: rms of the residuals about the line.
        n_points: points used per band (NaN levels are left out).
        heights_m: the distinct heights of the fit.
        ref_height_m: reference height of the abscissa.
        label: what was fitted (for tables and legends).
    """

    bands_Hz: tuple[str, ...]
    slope_dB: np.ndarray
    stderr_dB: np.ndarray
    intercept_dB: np.ndarray
    residual_rms_dB: np.ndarray
    n_points: np.ndarray
    heights_m: np.ndarray
    ref_height_m: float = 1.0
    label: str = ""

    def slope(self, band: str) -> float:
        """Slope in one band (label as in ``bands_Hz``), dB per doubling."""
        try:
            return float(self.slope_dB[self.bands_Hz.index(band)])
        except ValueError:
            raise KeyError(f"band {band!r} not in {self.bands_Hz}") from None

    def to_dict(self) -> dict:
        """Plain-Python dict (JSON-ready; NaN stays NaN)."""
        return {
            "label": self.label,
            "bands_Hz": list(self.bands_Hz),
            "slope_dB_per_doubling": [float(x) for x in self.slope_dB],
            "stderr_dB": [float(x) for x in self.stderr_dB],
            "intercept_dB": [float(x) for x in self.intercept_dB],
            "residual_rms_dB": [float(x) for x in self.residual_rms_dB],
            "n_points": [int(x) for x in self.n_points],
            "heights_m": [float(x) for x in self.heights_m],
            "ref_height_m": self.ref_height_m,
        }


def growth_table(growths: Sequence[Growth], *, digits: int = 1) -> str:
    """A Markdown table: one row per :class:`Growth`, slope ± standard error per band.

    Args:
        growths: the :class:`Growth` results, all over the same bands (one row each, headed
            by its ``label``).
        digits: decimals of the slopes and standard errors.

    Returns:
        The table, a Markdown string ("—" for a band without a slope; the standard error left
        out where it is not finite and > 0).

    Raises:
        GrowthError: no growths, or growths over different bands.
    """
    if not growths:
        raise GrowthError("growth_table needs at least one Growth")
    bands = growths[0].bands_Hz
    lines = [
        "| dB per doubling | " + " | ".join(f"{b} Hz" for b in bands) + " |",
        "|---" * (len(bands) + 1) + "|",
    ]
    for g in growths:
        if g.bands_Hz != bands:
            raise GrowthError(f"growth_table: bands differ ({g.bands_Hz} vs {bands})")
        cells = []
        for s, e in zip(g.slope_dB, g.stderr_dB):
            if not np.isfinite(s):
                cells.append("—")
            elif np.isfinite(e) and e > 0:
                cells.append(f"{s:.{digits}f} ± {e:.{digits}f}")
            else:
                cells.append(f"{s:.{digits}f}")
        lines.append(f"| {g.label or '—'} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def growth_per_doubling_dB(
    heights_m,
    lfe_dB_by_band,
    bands_Hz: Sequence[str] | None = None,
    *,
    ref_height_m: float = 1.0,
    label: str = "",
) -> Growth:
    """Least-squares growth of L_FE per doubling of drop height, band by band.

    Args:
        heights_m: drop height of each point, shape (N,), m > 0; repeated heights (several
            drops) are allowed; at least two distinct heights per band.
        lfe_dB_by_band: levels, shape (N, n_bands) (or (N,) for one band), dB; NaN entries
            (failed solves) are left out of their band's fit.
        bands_Hz: band labels, length n_bands (default: rbjax.spectrum.bands.OCTAVE_BANDS when
            n_bands is 6, else ``"0"``, ``"1"``, …).
        ref_height_m: reference height of log2(h/h_ref) (sets the intercept only).
        label: carried into the result.

    Returns:
        The :class:`Growth`; NaN slopes in a band with fewer than two distinct heights of
        finite levels.

    Raises:
        GrowthError: fewer than two distinct heights, mismatched shapes (``heights_m`` not
            1-D, levels not (N, n_bands), a ``bands_Hz`` of another length), non-finite or
            non-positive heights, or a ``ref_height_m`` not finite and > 0 (a ``ValueError``).
    """

    h = np.asarray(heights_m, dtype=float)
    y = np.asarray(lfe_dB_by_band, dtype=float)
    if h.ndim != 1:
        raise GrowthError(f"heights_m must be 1-D; got shape {h.shape}")
    if y.ndim == 1:
        y = y[:, None]
    if y.ndim != 2 or y.shape[0] != h.shape[0]:
        raise GrowthError(
            f"lfe_dB_by_band has shape {y.shape}; expected ({h.shape[0]}, n_bands) to match "
            f"heights_m {h.shape}"
        )
    if not np.all(np.isfinite(h)) or np.any(h <= 0):
        raise GrowthError(f"heights_m={h.tolist()} must all be finite and > 0")
    if not (math.isfinite(ref_height_m) and ref_height_m > 0):
        raise GrowthError(f"ref_height_m={ref_height_m!r} must be finite and > 0")
    if np.unique(h).size < 2:
        raise GrowthError(
            f"heights_m={np.unique(h).tolist()}: the growth per doubling needs at least two "
            "distinct drop heights"
        )
    n_bands = y.shape[1]
    if bands_Hz is None:
        bands = (
            tuple(OCTAVE_BANDS)
            if n_bands == len(OCTAVE_BANDS)
            else tuple(str(i) for i in range(n_bands))
        )
    else:
        bands = tuple(str(b) for b in bands_Hz)
        if len(bands) != n_bands:
            raise GrowthError(f"bands_Hz has {len(bands)} labels for {n_bands} bands")
    u_all = np.log2(h / ref_height_m)
    out = {k: np.full(n_bands, np.nan) for k in ("slope", "se", "a", "rms")}
    count = np.zeros(n_bands, dtype=int)
    for j in range(n_bands):
        ok = np.isfinite(y[:, j])
        u, v = u_all[ok], y[ok, j]
        count[j] = u.size
        if np.unique(u).size < 2:
            continue  # this band has fewer than two usable heights: NaN
        ub, vb = u.mean(), v.mean()
        sxx = np.sum((u - ub) ** 2)
        b = np.sum((u - ub) * (v - vb)) / sxx
        a = vb - b * ub
        r = v - (a + b * u)
        out["slope"][j], out["a"][j] = b, a
        out["rms"][j] = math.sqrt(np.mean(r**2))
        out["se"][j] = math.sqrt(np.sum(r**2) / (u.size - 2) / sxx) if u.size > 2 else np.nan
    return Growth(
        bands_Hz=bands,
        slope_dB=out["slope"],
        stderr_dB=out["se"],
        intercept_dB=out["a"],
        residual_rms_dB=out["rms"],
        n_points=count,
        heights_m=np.unique(h),
        ref_height_m=float(ref_height_m),
        label=label,
    )


def recording_lfe_dB(
    recordings=None, *, window_s: float = 0.03, pre_onset_s: float = 0.003, average: bool = False
):
    """Octave-band L_FE of force-plate recordings: ``(heights_m, lfe_dB (N, 6))``.

    Each record is conditioned (``rbjax.data.condition`` through ``rbjax.fit.prepare_data``:
    baseline removed, onset aligned, ``window_s`` from ``pre_onset_s`` before the onset),
    zero-padded to 1 s and analysed by Eq. 11 in octave bands, as :mod:`rbjax.fit` does.
    ``recordings``: Recording objects, paths or a folder; default the bundled emulated
    recordings (``rbjax.data.load_examples()``). ``average=True``: one coherent average per
    height instead of one point per drop.
    """

    recs = load_examples() if recordings is None else recordings
    data = prepare_data(recs, average=average, window_s=window_s, pre_onset_s=pre_onset_s)
    n_pad = int(round(data.rate_Hz))
    x = np.asarray(data.force_N)
    padded = np.pad(x, ((0, 0), (0, max(0, n_pad - x.shape[1]))))
    return np.asarray(data.height_m, dtype=float), np.asarray(lfe_octave_dB(padded, data.rate_Hz))


def recording_growth(
    recordings=None, *, average: bool = False, ref_height_m: float = 1.0, label: str = "recordings"
) -> Growth:
    """Growth per doubling of recorded L_FE (default: the bundled emulated recordings, one
    point per drop, so the standard error includes the drop-to-drop scatter).

    Args:
        recordings: Recording objects, paths or a folder (:func:`recording_lfe_dB`); ``None``:
            the bundled emulated recordings.
        average: one coherent average per height instead of one point per drop.
        ref_height_m: reference height of log2(h/h_ref), m (sets the intercept only).
        label: carried into the result.

    Returns:
        The :class:`Growth` over the octave bands 31.5 Hz–1 kHz.

    Raises:
        GrowthError: fewer than two distinct heights among the recordings, or a bad
            ``ref_height_m`` (:func:`growth_per_doubling_dB`).
        rbjax.data.DataError: recordings that cannot be read or conditioned
            (:func:`rbjax.fit.prepare_data`).
    """

    h, lfe = recording_lfe_dB(recordings, average=average)
    return growth_per_doubling_dB(h, lfe, OCTAVE_BANDS, ref_height_m=ref_height_m, label=label)


def model_lfe_dB(
    heights_m, ball: Ball = JIS_RUBBER_BALL, model=None, **simulate_kwargs
) -> np.ndarray:
    """Octave-band L_FE (n_heights, 6) of a model's 44.1 kHz × 1 s blocked-force records.

    ``model``: an ``rbjax.Model`` (e.g. a fit's ``FitResult.model``, with ``ball`` its
    ``FitResult.ball``), or None for ``rbjax.simulate(heights, ball, **simulate_kwargs)``.
    Failed solves give NaN rows.
    """

    if model is None:
        res = simulate(np.asarray(heights_m, dtype=float), ball, **simulate_kwargs)
    else:
        if simulate_kwargs:
            raise ValueError(
                "model_lfe_dB: pass either model or simulate options, not both "
                f"({sorted(simulate_kwargs)})"
            )

        h = np.asarray(heights_m, dtype=float)
        check_inputs(h, ball, PAPER_RATE_Hz, 1.0)
        res = simulate_model(
            h, ball, model, Solver(), path=resolve_path("auto", model, None), fallback=True
        )
    force = np.asarray(res.history().force_N)
    lfe = np.array(lfe_octave_dB(force, PAPER_RATE_Hz))
    lfe[np.asarray(res.status).reshape(-1) != 0] = np.nan
    return lfe


def model_growth(
    heights_m,
    ball: Ball = JIS_RUBBER_BALL,
    model=None,
    *,
    ref_height_m: float = 1.0,
    label: str = "model",
    **simulate_kwargs,
) -> Growth:
    """Growth per doubling of a model's octave-band L_FE, simulated at ``heights_m``.

    E.g. ``model_growth(h)`` (the paper's elastic model), ``model_growth(h, gas="none")``, or
    ``model_growth(h, fit.ball, fit.model)`` for a fitted model.

    Args:
        heights_m: the drop heights, m (at least two distinct ones).
        ball: the ball (default: ``JIS_RUBBER_BALL``).
        model: an ``rbjax.Model`` (e.g. a fit's ``FitResult.model``), or ``None`` for
            ``rbjax.simulate(heights, ball, **simulate_kwargs)`` (:func:`model_lfe_dB`).
        ref_height_m: reference height of log2(h/h_ref), m (sets the intercept only).
        label: carried into the result.
        simulate_kwargs: options of ``rbjax.simulate`` where ``model`` is ``None``.

    Returns:
        The :class:`Growth` over the octave bands 31.5 Hz–1 kHz (a failed solve's levels are
        NaN and left out of its bands' fits).

    Raises:
        GrowthError: fewer than two distinct heights, or a bad ``ref_height_m``.
        ValueError: both ``model`` and ``simulate_kwargs`` given, or inputs ``rbjax.simulate``
            rejects.
    """

    h = np.asarray(heights_m, dtype=float).reshape(-1)
    if np.unique(h).size < 2:
        raise GrowthError(
            f"heights_m={np.unique(h).tolist()}: the growth per doubling needs at least two "
            "distinct drop heights"
        )
    return growth_per_doubling_dB(
        h,
        model_lfe_dB(h, ball, model, **simulate_kwargs),
        OCTAVE_BANDS,
        ref_height_m=ref_height_m,
        label=label,
    )

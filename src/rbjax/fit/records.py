"""The records a fit compares with: conditioned, stacked on one time grid, and the features
(contact start and end, peak, octave-band L_FE) read off data and predictions alike."""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import reprlib
from collections.abc import Iterable, Sequence
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from .. import data
from ..data import Recording, describe_conditioning
from ..spectrum.filters import butter_lowpass_sos
from ..spectrum.levels import lfe_octave_dB

#: Level (fraction of the peak) at which contact start and end are read from a history:
#: the same estimator is applied to measured and predicted (filtered) histories.
FEATURE_FRACTION = 0.05


@dataclasses.dataclass(frozen=True, eq=False)
class FitData:
    """Conditioned records ready for fitting: one row per record, all on one time grid.

    Attributes:
        sources: the file(s) behind each record (several for a per-height average).
        height_m: nominal drop height of each record, m.
        force_N: (n_records, n_samples) baseline-free force, onset at ``onset_s``.
        rate_Hz: sampling rate.
        onset_s: onset (5 % of the peak on the rising edge) of each record, s.
        noise_rms_N: noise rms of each record (of the average: per-drop rms / √n_drops).
        n_drops: drops behind each record.
        lowpass_Hz: cutoff of the causal 4th-order Butterworth measuring chain the records
            went through (applied to the predictions too), or None (no filter).
        conditioning: one dict per recording read (before averaging): ``source``,
            ``height_m``, ``rate_Hz`` and what conditioning did to it (``Recording.conditioning``:
            polarity, drift, hum, offset, the impact kept and the others cut, the window).
        excluded: one dict per recording left out (``source``, ``height_m``, ``reason``),
            e.g. a clipped file loaded with ``strict=False``.
    """

    sources: tuple
    height_m: np.ndarray
    force_N: np.ndarray
    rate_Hz: float
    onset_s: np.ndarray
    noise_rms_N: np.ndarray
    n_drops: np.ndarray
    lowpass_Hz: float | None
    conditioning: tuple = ()
    excluded: tuple = ()

    @property
    def n_records(self) -> int:
        return int(self.force_N.shape[0])

    @property
    def n_samples(self) -> int:
        return int(self.force_N.shape[1])

    @property
    def time_s(self) -> np.ndarray:
        return np.arange(self.n_samples) / self.rate_Hz

    @property
    def heights_m(self) -> np.ndarray:
        """The distinct drop heights, ascending."""
        return np.unique(self.height_m)

    # The two below are computed once and kept with the data (``functools.cached_property``),
    # so that every fit of these records reuses them, and a worker process that receives the
    # data after they were computed receives them too (a selection computes them before it
    # hands out its tasks). Each worker computed them again before: 0.3 s for the octave-band
    # kernel of the features, 0.8 s for importing scipy.signal to design the filter.

    @functools.cached_property
    def measured_features(self) -> dict:
        """:func:`record_features` of the records (read-only arrays)."""
        out = record_features(self.force_N, self.rate_Hz)
        for value in out.values():
            value.flags.writeable = False
        return out

    @functools.cached_property
    def lowpass_sos(self) -> np.ndarray:
        """The measuring chain's filter (``lowpass_Hz``) as second-order sections
        (:func:`rbjax.spectrum.filters.butter_lowpass_sos`, order 4; read-only), or one
        section of zeros where there is none (the fit then applies no filter)."""
        if self.lowpass_Hz is None:
            sos = np.zeros((1, 6))
        else:
            sos = butter_lowpass_sos(4, self.lowpass_Hz, self.rate_Hz)
        sos.flags.writeable = False
        return sos

    def replace(self, **changes) -> FitData:
        return dataclasses.replace(self, **changes)

    def conditioning_report(self) -> str:
        """What conditioning did to each recording, and the ones left out (text, a line each)."""

        lines = [
            f"  {c['source']} ({c['height_m']:g} m): {describe_conditioning(c)}"
            for c in self.conditioning
        ]
        lines += [f"  {e['source']}: EXCLUDED: {e['reason']}" for e in self.excluded]
        return "\n".join(["conditioning:"] + lines)


def load_data(paths_or_dir, *, lowpass_Hz="auto", strict: bool = False, **load_kwargs):
    """Read recordings with ``rbjax.data.load``; resolve the measuring chain's low-pass.

    Args:
        paths_or_dir: a file or directory (``str`` or any ``os.PathLike``), or an iterable
            of them.
        lowpass_Hz: the measuring chain's cutoff, Hz. ``"auto"``: the cutoff the recordings
            declare (all equal), else, for the shipped emulated recordings
            (``rbjax.data.examples_dir()``), their documented 1250 Hz; else none. A number or
            None overrides.
        strict: False (the default): a clipped file is returned as ``rbjax.data.Excluded``
            with its reason (:func:`prepare_data` leaves it out and reports it); True: it is
            refused (``rbjax.data.ClippedRecordError``).
        **load_kwargs: further keywords of ``rbjax.data.load`` (``height_m``, ``manifest``,
            ``rate_Hz``, ``calibration_N_per_FS``, ``channel``).

    Returns:
        A list of ``rbjax.data.Recording`` in file order, their ``lowpass_Hz`` resolved as
        above, with an ``rbjax.data.Excluded`` in place of each clipped file (``strict=False``).

    Raises:
        DataError: a file cannot be read or its height known, and the other errors of
            ``rbjax.data.load``.
        ClippedRecordError: a clipped file, with ``strict=True``.
    """

    items = [paths_or_dir] if isinstance(paths_or_dir, (str, os.PathLike)) else list(paths_or_dir)
    recs = data.load(items, strict=strict, **load_kwargs)
    if lowpass_Hz == "auto":
        declared = {r.lowpass_Hz for r in recs if isinstance(r, data.Recording)}
        if declared == {None}:
            examples = data.examples_dir().resolve()
            files = [Path(p).resolve() for p in items]
            inside = all(p == examples or examples in p.parents for p in files)
            if inside:
                return _with_lowpass(recs, data.EXAMPLES_LOWPASS_HZ)
        return recs
    return _with_lowpass(recs, lowpass_Hz)


def _with_lowpass(recs, lowpass_Hz):
    """The recordings with the chain's cutoff set (excluded entries as they are)."""

    cutoff = None if lowpass_Hz is None else float(lowpass_Hz)
    return [r.replace(lowpass_Hz=cutoff) if isinstance(r, Recording) else r for r in recs]


def prepare_data(
    recordings,
    *,
    average: bool = True,
    window_s: float = 0.03,
    pre_onset_s: float = 0.003,
    lowpass_Hz="auto",
) -> FitData:
    """Condition recordings for fitting (``rbjax.data.condition``) and stack them.

    Each record is first mended (``rbjax.data.clean``: inverted sign, drift, mains hum),
    then keeps ``window_s`` seconds starting ``pre_onset_s`` before its first impact's
    onset (baseline removed, sub-sample onset alignment; a rebound is cut and reported);
    what was done to each is in ``FitData.conditioning``. ``rbjax.data.Excluded`` entries
    (clipped files read with ``strict=False``) are left out and listed in
    ``FitData.excluded``. With ``average=True`` the drops of one
    height are averaged coherently in the frequency domain (``rbjax.data.average``, the
    paper's §3 averaging), one record per height; else every drop is a record.

    Args:
        recordings: Recording objects (``rbjax.data.Excluded`` entries among them are left
            out), or a file or directory (``str`` or any ``os.PathLike``), or paths (read by
            :func:`load_data`); any iterable of either (a generator too) is read into a list
            first. A :class:`FitData` is returned as it is (the other arguments are then not
            used).
        average: average the drops of each height into one record (True) or keep every
            drop a record (False).
        window_s: length of the window kept of each record, s.
        pre_onset_s: how long before the first impact's onset the window starts, s.
        lowpass_Hz: the measuring chain's cutoff: ``"auto"`` (as declared by the
            recordings), a cutoff in Hz, or None (no filter).

    Returns:
        The :class:`FitData`, its records in ascending height (one per height with
        ``average=True``), all cut to the length of the shortest.

    Raises:
        DataError: no recording is left (every one excluded, or none given), a recording's
            drop height is unknown, the recordings declare different low-pass cutoffs, or a
            record cannot be conditioned (e.g. ``rbjax.data.NoImpactError``,
            ``rbjax.data.RecordCutOffError``) or read (:func:`load_data`).
        ValueError: ``window_s`` or ``pre_onset_s`` is not a positive finite number.
        TypeError: ``recordings`` is none of these (not iterable, or an item that is
            neither a ``Recording`` nor a path among recordings).
    """

    if isinstance(recordings, FitData):
        return recordings
    if not isinstance(recordings, (str, os.PathLike, Sequence)):
        if not isinstance(recordings, Iterable):
            raise TypeError(
                f"recordings={reprlib.repr(recordings)} (of type {type(recordings).__name__}): "
                "expected Recording objects, a file or directory, paths, or a FitData"
            )
        recordings = list(recordings)  # a generator or other iterable: looked at once, here
    if isinstance(recordings, (str, os.PathLike)) or (
        recordings and isinstance(recordings[0], (str, os.PathLike))
    ):
        recs = load_data(recordings, lowpass_Hz=lowpass_Hz)
    else:
        recs = list(recordings)
        other = [
            (k, r) for k, r in enumerate(recs) if not isinstance(r, (Recording, data.Excluded))
        ]
        if other:
            k, item = other[0]
            raise TypeError(
                f"recordings[{k}]={reprlib.repr(item)} (of type {type(item).__name__}) is not a "
                "Recording: give Recording objects (rbjax.data.load) or else paths"
            )
        if lowpass_Hz != "auto":
            recs = _with_lowpass(recs, lowpass_Hz)
    excluded = tuple(r.to_dict() for r in recs if isinstance(r, data.Excluded))
    recs = [r for r in recs if not isinstance(r, data.Excluded)]
    if not recs:
        left_out = "; ".join(f"{e['source']}: {e['reason']}" for e in excluded)
        raise data.DataError(
            "no recordings to fit" + (f": every one was excluded ({left_out})" if excluded else "")
        )
    _check_positive("window_s", window_s)
    _check_positive("pre_onset_s", pre_onset_s)
    for r in recs:
        if r.height_m is None:
            raise data.DataError(
                f"{r.source}: unknown drop height; name the file hNNN_... or pass height_m"
            )
    cutoffs = {r.lowpass_Hz for r in recs}
    if len(cutoffs) > 1:
        listing = ", ".join(f"{r.source}: {r.lowpass_Hz}" for r in recs)
        raise data.DataError(f"recordings declare different measuring-chain low-passes ({listing})")
    cutoff = cutoffs.pop()
    cleaned = [data.clean(r) for r in recs]
    conditioned = [
        (data.condition(r, window_s=window_s, pre_onset_s=pre_onset_s), r.noise_rms_N)
        for r in cleaned
    ]
    log = tuple(
        {"source": rec.source, "height_m": rec.height_m, "rate_Hz": rec.rate_Hz, **rec.conditioning}
        for rec, _ in conditioned
    )
    rows = []
    if average:
        groups: dict[float, list] = {}
        for rec, sigma in conditioned:
            assert rec.height_m is not None  # every record's height was checked above
            groups.setdefault(round(rec.height_m, 3), []).append((rec, sigma))
        for h in sorted(groups):
            members = groups[h]
            avg = data.average([m[0] for m in members]) if len(members) > 1 else members[0][0]
            sigma = math.sqrt(np.mean([m[1] ** 2 for m in members]) / len(members))
            rows.append((tuple(m[0].source for m in members), h, avg, sigma, len(members)))
    else:
        for rec, sigma in sorted(conditioned, key=lambda m: (m[0].height_m, m[0].source)):
            assert rec.height_m is not None  # every record's height was checked above
            rows.append(((rec.source,), rec.height_m, rec, sigma, 1))
    n = min(r[2].n_samples for r in rows)
    return FitData(
        sources=tuple(r[0] for r in rows),
        height_m=np.array([r[1] for r in rows], dtype=float),
        force_N=np.stack([r[2].force_N[:n] for r in rows]),
        rate_Hz=float(rows[0][2].rate_Hz),
        onset_s=np.array([r[2].onset_s for r in rows], dtype=float),
        noise_rms_N=np.array([r[3] for r in rows], dtype=float),
        n_drops=np.array([r[4] for r in rows], dtype=int),
        lowpass_Hz=cutoff,
        conditioning=log,
        excluded=excluded,
    )


def _check_positive(name, value):
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(
            f"{name}={value!r} must be a positive finite number (valid range: (0, inf))"
        )


# ----------------------------------------------------------------------------------------------
# features measured the same way on data and predictions


def pulse_features(force_N, rate_Hz: float, n_pad: int, fraction: float = FEATURE_FRACTION):
    """(t_rise, t_fall, peak, L_FE × 6 octave bands) of histories (..., n), differentiable.

    t_rise/t_fall: where the force crosses ``fraction`` × peak on the rising edge (last
    sample below the level before the peak) and the falling edge (first sample below it
    after the peak), by linear interpolation (NaN where the record has no such sample); the
    contact time is t_fall − t_rise. L_FE:
    paper Eq. 11 in octave bands (``rbjax.spectrum.levels.lfe_octave_dB``) of the record
    zero-padded to ``n_pad`` samples (1 s, as in the paper's §2.4).
    """

    x = jnp.asarray(force_N)
    n = x.shape[-1]
    idx = jnp.arange(n)
    ip = jnp.argmax(x, axis=-1)[..., None]
    peak = jnp.max(x, axis=-1)
    level = fraction * peak[..., None]
    take = lambda i: jnp.take_along_axis(x, i, axis=-1)  # noqa: E731
    before = (idx < ip) & (x < level)
    i = jnp.clip(n - 1 - jnp.argmax(before[..., ::-1], axis=-1)[..., None], 0, n - 2)
    xi, xi1 = take(i), take(i + 1)
    t_rise = (i + (level - xi) / (xi1 - xi))[..., 0] / rate_Hz
    after = (idx > ip) & (x < level)
    j = jnp.clip(jnp.argmax(after, axis=-1)[..., None], 1, n - 1)
    xj, xj1 = take(j), take(j - 1)
    t_fall = (j - 1 + (xj1 - level) / (xj1 - xj))[..., 0] / rate_Hz
    # no crossing inside the record (pulse cut off at either end): NaN, not a clipped index
    t_rise = jnp.where(jnp.any(before, axis=-1), t_rise, jnp.nan)
    t_fall = jnp.where(jnp.any(after, axis=-1), t_fall, jnp.nan)
    # L_FE of the record zero-padded to n_pad samples, from its own samples (the padded FFT's
    # numbers to round-off, ~10× faster: see ``lfe_octave_dB``'s ``n_record``)
    lfe = lfe_octave_dB(x, rate_Hz, n_record=max(n, n_pad))
    return jnp.concatenate([t_rise[..., None], t_fall[..., None], peak[..., None], lfe], axis=-1)


@functools.lru_cache(maxsize=8)
def _features_jit(rate_Hz: float, n_pad: int):
    return jax.jit(lambda x: pulse_features(x, rate_Hz, n_pad))


def _n_pad(rate_Hz: float) -> int:
    return int(round(rate_Hz * 1.0))


def record_features(force_N, rate_Hz: float) -> dict:
    """Contact time, peak force and octave-band L_FE of histories (..., n) as measured.

    The estimator of :func:`fit` (5 % of the peak, linear interpolation; L_FE of the record
    zero-padded to 1 s).

    Args:
        force_N: force histories, N, shape (..., n): time along the last axis.
        rate_Hz: their sampling rate, Hz.

    Returns:
        A dict of NumPy arrays: ``onset_s`` (...), the contact start from the first sample,
        s; ``contact_time_s`` (...), s; ``peak_force_N`` (...), N; ``lfe_octave_dB``
        (..., 6), dB per octave band. Contact start and time are NaN where the history
        does not cross 5 % of its peak before or after it.
    """
    f = np.asarray(
        _features_jit(float(rate_Hz), _n_pad(rate_Hz))(jnp.asarray(force_N, dtype=jnp.float64))
    )
    return {
        "onset_s": f[..., 0],
        "contact_time_s": f[..., 1] - f[..., 0],
        "peak_force_N": f[..., 2],
        "lfe_octave_dB": f[..., 3:],
    }

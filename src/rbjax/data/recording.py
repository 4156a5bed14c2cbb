"""The :class:`Recording` type (one force record of one drop) and the checks on its data."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .crossings import estimate_noise_rms_N, rising_crossing, solve_crossing
from .errors import ClippedRecordError, DataError
from .shift import fractional_shift
from .sources import height_from_name

__all__ = ["Recording", "MIN_SAMPLES"]

MIN_SAMPLES = 100
"""Fewer samples than this in a file is treated as a truncated file."""


def _frozen_array(x) -> np.ndarray:
    a = np.array(x, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


@dataclasses.dataclass(frozen=True, eq=False)
class Recording:
    """One force record of one drop, sampled uniformly.

    Attributes:
        source: file name the record came from (or a description, e.g. for averages).
        height_m: drop height in metres, or ``None`` when unknown.
        rate_Hz: sampling rate in Hz.
        force_N: force samples in newtons, 1-D float64, read-only; sample ``i`` is at
            ``i / rate_Hz`` seconds from the first sample.
        onset_s: sub-sample time of the impact onset (see :func:`locate_onset`), seconds
            from the first sample of ``force_N``; ``None`` until :func:`condition` sets it.
        calibration_N_per_FS: calibration used to scale integer/normalised samples to
            newtons (N per full scale), or ``None``.
        lowpass_Hz: cutoff of the causal low-pass the record went through (measuring chain
            or :func:`condition`), Hz, if known/declared; ``None`` if unknown.
        notes: human-readable warnings and processing notes, oldest first.
        log: what conditioning did to the record, as ``(step, value)`` pairs in the order
            done (:func:`~rbjax.data.clean`, :func:`~rbjax.data.condition`): ``polarity``,
            ``drift_N_per_s``, ``hum``, ``offset_N``, ``impact_s``, ``further_impacts``...;
            ``conditioning`` gives them as a dict.

    Raises:
        DataError: ``rate_Hz`` is not positive and finite; ``force_N`` is not a non-empty
            1-D array or holds NaN or inf; ``height_m`` is given but not positive and
            finite; ``onset_s``, ``calibration_N_per_FS`` or ``lowpass_Hz`` is given but
            not finite.
    """

    source: str
    height_m: float | None
    rate_Hz: float
    force_N: np.ndarray
    onset_s: float | None = None
    calibration_N_per_FS: float | None = None
    lowpass_Hz: float | None = None
    notes: tuple[str, ...] = ()
    log: tuple[tuple[str, object], ...] = ()

    def __post_init__(self):
        rate = float(self.rate_Hz)
        if not (math.isfinite(rate) and rate > 0):
            raise DataError(f"{self.source}: rate_Hz={self.rate_Hz!r} must be positive and finite")
        object.__setattr__(self, "rate_Hz", rate)
        f = _frozen_array(self.force_N)
        if f.ndim != 1 or f.size == 0:
            raise DataError(
                f"{self.source}: force_N must be a non-empty 1-D array; got shape {f.shape}"
            )
        if not np.all(np.isfinite(f)):
            raise DataError(f"{self.source}: force_N contains NaN or inf")
        object.__setattr__(self, "force_N", f)
        if self.height_m is not None:
            h = float(self.height_m)
            if not (math.isfinite(h) and h > 0):
                raise DataError(
                    f"{self.source}: height_m={self.height_m!r} must be positive and finite"
                )
            object.__setattr__(self, "height_m", h)
        for name in ("onset_s", "calibration_N_per_FS", "lowpass_Hz"):
            v = getattr(self, name)
            if v is not None:
                v = float(v)
                if not math.isfinite(v):
                    raise DataError(f"{self.source}: {name}={v!r} must be finite")
                object.__setattr__(self, name, v)
        object.__setattr__(self, "notes", tuple(str(n) for n in self.notes))
        object.__setattr__(self, "log", tuple((str(k), v) for k, v in self.log))

    # ----- derived quantities --------------------------------------------------------
    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.force_N.size)

    @property
    def duration_s(self) -> float:
        """Length of the record, ``n_samples / rate_Hz`` seconds."""
        return self.n_samples / self.rate_Hz

    @property
    def time_s(self) -> np.ndarray:
        """Sample times in seconds from the first sample, ``arange(n) / rate_Hz``."""
        return np.arange(self.n_samples) / self.rate_Hz

    @property
    def peak_N(self) -> float:
        """Largest force sample, N."""
        return float(self.force_N.max())

    @property
    def noise_rms_N(self) -> float:
        """Robust rms of the noise, N (see :func:`estimate_noise_rms_N`)."""
        return estimate_noise_rms_N(self.force_N)

    @property
    def conditioning(self) -> dict:
        """The log as a dict: step -> what was done (JSON-ready values)."""
        return dict(self.log)

    def replace(self, **changes) -> Recording:
        """A copy with the given fields changed (``dataclasses.replace``)."""
        return dataclasses.replace(self, **changes)

    def contact_window(self, *, fraction: float = 0.05) -> tuple[float, float]:
        """``(start_s, end_s)``: times the force crosses ``fraction * peak`` up, then down.

        Times in seconds from the first sample, interpolated to a fraction of a sample
        (rising edge exactly as :func:`locate_onset`; falling edge by cubic
        interpolation too). ``end_s - start_s`` is a contact time at that level. Assumes
        the baseline has been removed (a conditioned record).

        Args:
            fraction: the level as a fraction of the peak force.

        Returns:
            ``(start_s, end_s)``, seconds from the first sample.

        Raises:
            DataError: the force does not fall below the level after the peak.
            RecordCutOffError: the force is already above the level at the first sample.
        """
        x = self.force_N
        ip = int(np.argmax(x))
        level = fraction * x[ip]
        start = rising_crossing(x, ip, level, self.source)
        # falling edge: first sample after the peak below the level
        below = np.flatnonzero(x[ip:] < level)
        if below.size == 0:
            raise DataError(
                f"{self.source}: the force does not fall below {level:.4g} N after the peak"
            )
        j = ip + int(below[0])  # x[j-1] >= level > x[j]
        u = solve_crossing(x, j, -level, sign=-1.0)
        return start / self.rate_Hz, (j - 1 + u) / self.rate_Hz

    def aligned(self, onset_s: float, *, interpolation: str = "fourier") -> Recording:
        """The record shifted in time so that its onset lands at ``onset_s`` (same length).

        Sub-sample shift by :func:`fractional_shift` (``"fourier"``: band-limited,
        ``"linear"`` or ``"cubic"`` interpolation); samples shifted in from outside the
        record are zero (meaningful for a baseline-subtracted record).

        Args:
            onset_s: where the onset is to land, seconds from the first sample.
            interpolation: ``"fourier"``, ``"linear"`` or ``"cubic"``.

        Returns:
            A copy of the :class:`Recording` with the shifted ``force_N`` and ``onset_s``.

        Raises:
            DataError: the record has no ``onset_s`` (not conditioned).
            ValueError: an unknown ``interpolation`` (when the shift is not zero).
        """
        if self.onset_s is None:
            raise DataError(f"{self.source}: no onset_s; condition() the recording first")
        shift = (float(onset_s) - self.onset_s) * self.rate_Hz
        y = fractional_shift(self.force_N, shift, interpolation=interpolation)
        return self.replace(force_N=y, onset_s=float(onset_s))


# --------------------------------------------------------------------------------------
# checks of the samples a reader found, and of a set of recordings
# --------------------------------------------------------------------------------------


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    """(length, start) of the longest run of True in a 1-D boolean array."""
    if not mask.any():
        return 0, -1
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1)
    k = int(np.argmax(ends - starts))
    return int(ends[k] - starts[k]), int(starts[k])


def check_force(force: np.ndarray, source: str, *, flat_top: bool = True) -> None:
    """Length, finiteness, constant signal and (for float data) flat-top clipping."""
    n = force.size
    if n == 0:
        raise DataError(f"{source}: no samples (empty file?)")
    if n < MIN_SAMPLES:
        raise DataError(
            f"{source}: only {n} samples (at least {MIN_SAMPLES} needed); truncated file?"
        )
    bad = ~np.isfinite(force)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"{source}: {int(bad.sum())} sample(s) are NaN or inf (first at sample {i}: "
            f"{force[i]!r})"
        )
    if np.ptp(force) == 0:
        raise DataError(f"{source}: all {n} samples equal {force[0]!r}: no signal")
    if flat_top:
        amax = float(np.abs(force).max())
        mask = np.abs(force) >= amax * (1 - 1e-9)
        run, start = _longest_run(mask)
        if run >= 3:
            raise ClippedRecordError(
                f"{source}: clipped: {run} consecutive samples (from sample {start}) sit at the "
                f"maximum |force| {amax:.6g} (a flat top); the peak force is not known"
            )


def check_height(height_m, source):
    if height_m is None:
        return None
    h = float(height_m)
    if not (math.isfinite(h) and h > 0):
        raise DataError(f"{source}: drop height {height_m!r} m must be positive and finite")
    return h


def file_recording(
    source: str,
    force_N,
    rate_Hz: float,
    height_m: float | None,
    *,
    calibration_N_per_FS: float | None = None,
    lowpass_Hz: float | None = None,
    notes=(),
) -> Recording:
    """The Recording a reader returns for a file: the drop height, when not given, from the
    file name (``hNNN``), checked."""
    if height_m is None:
        height_m = height_from_name(source)
    return Recording(
        source=source,
        height_m=check_height(height_m, source),
        rate_Hz=float(rate_Hz),
        force_N=force_N,
        calibration_N_per_FS=calibration_N_per_FS,
        lowpass_Hz=lowpass_Hz,
        notes=tuple(notes),
    )


def require_same_rate(recs) -> None:
    rates = {r.rate_Hz for r in recs}
    if len(rates) > 1:
        listing = ", ".join(f"{r.source}: {r.rate_Hz:g} Hz" for r in recs)
        raise DataError(f"recordings have different sample rates ({listing}); resample them first")

"""Force-plate recordings in: reading, checking, conditioning and averaging (NumPy).

This is the data edge of rbjax. Everything here is plain NumPy/SciPy and returns
frozen dataclasses holding read-only NumPy arrays; the JAX model code takes
``force_N`` / ``rate_Hz`` / ``onset_s`` from a :class:`Recording`.

Modules (every public name is also importable from ``rbjax.data``):

``errors``
    :class:`DataError` (a ``ValueError`` naming the file and the problem) and
    :class:`DataWarning`; nothing is silently repaired.
``recording``
    :class:`Recording`, one force record of one drop, and the checks on its samples
    (length ``MIN_SAMPLES``, NaN/inf, constant signal, clipping).
``readers``
    :func:`read_csv`, :func:`read_wav`, :func:`read_npy` read one file each;
    :func:`load` reads many files (or a directory) and resolves each drop height from
    an argument, a manifest CSV or the file name (:func:`height_from_name`:
    ``h100_d1.csv`` -> 1.00 m).
``conditioning``
    :func:`find_impacts` lists every impact of a raw record; :func:`condition` keeps
    one, subtracts the pre-trigger baseline, optionally low-passes, locates the onset
    to a fraction of a sample (:func:`locate_onset`) and cuts a window that starts a
    fixed ``pre_onset_s`` before the onset, so that records of one height line up.
``shift``
    :func:`fractional_shift`, a sub-sample delay (band-limited or interpolated).
``averaging``
    :func:`average` averages repeated drops coherently, in the frequency domain (as in
    the paper's section 3) or in the time domain, after sub-sample onset alignment.
``examples``
    The example recordings shipped with the package: :func:`examples_dir`,
    :func:`load_examples`.
"""

from __future__ import annotations

from .averaging import average
from .conditioning import Impact, condition, find_impacts, locate_onset
from .crossings import estimate_noise_rms_N
from .errors import DataError, DataWarning
from .examples import EXAMPLES_LOWPASS_HZ, examples_dir, load_examples
from .readers import load, read_csv, read_npy
from .recording import MIN_SAMPLES, Recording
from .shift import fractional_shift
from .sources import height_from_name
from .wav import read_wav

__all__ = [
    "DataError",
    "DataWarning",
    "Recording",
    "Impact",
    "MIN_SAMPLES",
    "EXAMPLES_LOWPASS_HZ",
    "examples_dir",
    "load_examples",
    "height_from_name",
    "read_csv",
    "read_wav",
    "read_npy",
    "load",
    "estimate_noise_rms_N",
    "find_impacts",
    "locate_onset",
    "condition",
    "fractional_shift",
    "average",
]

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
``readers``, ``wav``, ``matlab``, ``uff``, ``tdms``
    :func:`read_csv`, :func:`read_npy`, :func:`read_wav`, :func:`read_mat` (MATLAB,
    v7.3 by h5py), :func:`read_uff` (Universal File Format dataset 58, pyuff),
    :func:`read_tdms` (NI TDMS, npTDMS) read one file each; the last three share
    ``channels`` (a channel by name or number, units, calibration, integer full scale).
    pyuff, npTDMS and h5py are the optional extra ``rbjax[formats]``.
``loading``
    :func:`read_file` reads one file of any of them (by its suffix); :func:`load` reads
    many files (or a directory) and resolves each drop height from an argument, a
    manifest CSV or the file name (:func:`height_from_name`: ``h100_d1.csv`` -> 1.00 m);
    with ``strict=False`` a clipped file comes back as :class:`Excluded`.
``faults``
    :func:`clean` mends what a real record holds before conditioning: an inverted sign,
    a slow drift of the baseline, mains hum; and logs it.
``logbook``
    :func:`describe_conditioning`: the log of a record in words.
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
from .errors import (
    ClippedRecordError,
    DataError,
    DataWarning,
    MissingFormatError,
    NoImpactError,
    RecordCutOffError,
)
from .examples import EXAMPLES_LOWPASS_HZ, examples_dir, load_examples
from .faults import clean
from .loading import Excluded, load, read_file
from .logbook import describe_conditioning
from .matlab import read_mat
from .readers import read_csv, read_npy
from .recording import MIN_SAMPLES, Recording
from .shift import fractional_shift
from .sources import height_from_name
from .tdms import read_tdms
from .uff import read_uff
from .wav import read_wav

__all__ = [
    "DataError",
    "DataWarning",
    "ClippedRecordError",
    "NoImpactError",
    "RecordCutOffError",
    "MissingFormatError",
    "Excluded",
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
    "read_mat",
    "read_uff",
    "read_tdms",
    "read_file",
    "load",
    "clean",
    "describe_conditioning",
    "estimate_noise_rms_N",
    "find_impacts",
    "locate_onset",
    "condition",
    "fractional_shift",
    "average",
]

"""Many recordings at once: :func:`load` reads files and directories of every format rbjax
reads (:func:`read_file` picks the reader by the file's suffix) and resolves each drop
height from an argument, a manifest CSV or the file name (``h100_d1.csv`` -> 1.00 m).

A clipped file among good ones is refused (``strict=True``, the default) or, with
``strict=False``, returned as an :class:`Excluded` entry that says why, so that a fit can
use the others and report it.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Literal, overload

from .errors import ClippedRecordError, DataError
from .matlab import read_mat
from .readers import read_csv, read_npy
from .recording import Recording, require_same_rate
from .sources import as_source, existing_file, height_from_name
from .tdms import read_tdms
from .uff import read_uff
from .wav import read_wav

__all__ = ["Excluded", "SUFFIXES", "read_file", "load"]

_ONE_CHANNEL = (".csv", ".npy")  # newtons in one channel: no channel, no calibration
#: The formats whose channels have names, units and a time base of their own.
_CHANNEL_READERS = {".mat": read_mat, ".uff": read_uff, ".unv": read_uff, ".tdms": read_tdms}
#: The file suffixes :func:`read_file` and :func:`load` read.
SUFFIXES = (*_ONE_CHANNEL, ".wav", *_CHANNEL_READERS)
_KNOWN = ", ".join(f"*{s}" for s in SUFFIXES)


@dataclasses.dataclass(frozen=True)
class Excluded:
    """A file :func:`load` read but left out (``strict=False``): its name, height and why.

    Attributes:
        source: the file's name.
        height_m: its drop height in metres (as :func:`load` resolved it), or ``None``.
        reason: why it was left out (the :class:`ClippedRecordError` message).
    """

    source: str
    height_m: float | None
    reason: str

    def to_dict(self) -> dict:
        return {"source": self.source, "height_m": self.height_m, "reason": self.reason}


def read_file(
    path,
    *,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
    channel: int | str | None = None,
) -> Recording:
    """Read one recording of any known format, chosen by the file's suffix (:data:`SUFFIXES`).

    The arguments a format has no use for are refused, not ignored: a ``.csv`` or ``.npy``
    has one channel in newtons (no ``channel``, no calibration); a ``.wav``'s rate is in
    its header (``rate_Hz``, if given, must agree).

    Args:
        path: the file; its suffix (any case) picks the reader.
        rate_Hz: sampling rate, Hz: required for ``.npy``, for a ``.csv`` without a time
            column and for a channel whose file gives no rate; checked against the file's
            own rate otherwise.
        calibration_N_per_FS: newtons per full scale (or per unit) for integer or
            non-newton samples; refused for ``.csv`` and ``.npy``.
        height_m: drop height, m; default from the file name (``hNNN``), else ``None``.
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).
        channel: the channel to read (a number, or a name for MAT, UFF and TDMS files);
            refused for ``.csv`` and ``.npy`` (except ``0``).

    Returns:
        The file's :class:`Recording`, as the format's reader returns it.

    Raises:
        DataError: an unknown suffix; ``channel`` or ``calibration_N_per_FS`` given for a
            ``.csv`` or ``.npy``; a ``.npy`` without ``rate_Hz``; a ``rate_Hz`` that
            disagrees with a WAV header; anything the format's reader refuses (see
            :func:`read_csv`, :func:`read_npy`, :func:`read_wav`, :func:`read_mat`,
            :func:`read_uff`, :func:`read_tdms`), :class:`ClippedRecordError` included.
        MissingFormatError: the format's optional reader (pyuff, npTDMS, h5py for MATLAB
            v7.3) is not installed.
    """
    p = Path(path)
    suf = p.suffix.lower()
    if suf not in SUFFIXES:
        raise DataError(
            f"{p.name}: unknown file type {p.suffix!r}: none of the known formats ({_KNOWN})"
        )
    if suf in _ONE_CHANNEL:
        if channel not in (None, 0):
            raise DataError(
                f"{p.name}: a {suf} file has one force channel: channel={channel!r} does not apply"
            )
        if calibration_N_per_FS is not None:
            raise DataError(
                f"{p.name}: a {suf} file holds newtons: calibration_N_per_FS does not apply"
            )
        if suf == ".csv":
            return read_csv(p, rate_Hz=rate_Hz, height_m=height_m, lowpass_Hz=lowpass_Hz)
        if rate_Hz is None:
            raise DataError(
                f"{p.name}: a .npy file has no time base: pass rate_Hz= or a manifest rate_Hz"
            )
        return read_npy(p, rate_Hz=rate_Hz, height_m=height_m, lowpass_Hz=lowpass_Hz)
    if suf == ".wav":
        rec = read_wav(
            p,
            calibration_N_per_FS=calibration_N_per_FS,
            height_m=height_m,
            channel=channel,
            lowpass_Hz=lowpass_Hz,
        )
        if rate_Hz is not None and abs(float(rate_Hz) - rec.rate_Hz) > 1e-4 * rec.rate_Hz:
            raise DataError(
                f"{p.name}: rate_Hz={rate_Hz!r} disagrees with the WAV header ({rec.rate_Hz:g} Hz)"
            )
        return rec
    return _CHANNEL_READERS[suf](
        p,
        channel=channel,
        rate_Hz=rate_Hz,
        calibration_N_per_FS=calibration_N_per_FS,
        height_m=height_m,
        lowpass_Hz=lowpass_Hz,
    )


def _read_manifest(manifest) -> dict[str, dict]:
    if isinstance(manifest, Mapping):
        out = {}
        for k, v in manifest.items():
            out[Path(k).name] = dict(v) if isinstance(v, Mapping) else {"height_m": v}
        return out
    src = as_source(manifest)
    text = existing_file(manifest, "manifest ").read_text(encoding="utf-8-sig")
    rows = [r for r in csv.reader(io.StringIO(text)) if any(c.strip() for c in r)]
    if not rows:
        raise DataError(f"manifest {src}: empty file")
    header = [h.strip().lower() for h in rows[0]]
    if "file" not in header or "height_m" not in header:
        raise DataError(f"manifest {src}: needs columns file,height_m (found {rows[0]})")
    known = {"file", "height_m", "calibration_n_per_fs", "rate_hz", "lowpass_hz", "channel"}
    out = {}
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise DataError(f"manifest {src}: line {k} has {len(r)} fields, expected {len(header)}")
        entry: dict[str, object] = {}
        for h, v in zip(header, r):
            if h == "file" or h not in known:
                continue
            v = v.strip()
            if v == "":
                continue
            if h == "channel":  # a number, or a name (MAT, UFF, TDMS)
                entry["channel"] = int(v) if v.isdigit() else v
                continue
            try:
                entry[
                    {
                        "calibration_n_per_fs": "calibration_N_per_FS",
                        "rate_hz": "rate_Hz",
                        "lowpass_hz": "lowpass_Hz",
                    }.get(h, h)
                ] = float(v)
            except ValueError:
                raise DataError(f"manifest {src}: line {k}: {h}={v!r} is not a number") from None
        out[Path(r[header.index("file")].strip()).name] = entry
    return out


@overload
def load(
    paths_or_dir,
    *,
    height_m=...,
    manifest=...,
    rate_Hz=...,
    calibration_N_per_FS=...,
    lowpass_Hz=...,
    channel=...,
    strict: Literal[True] = ...,
) -> list[Recording]: ...
@overload
def load(
    paths_or_dir,
    *,
    height_m=...,
    manifest=...,
    rate_Hz=...,
    calibration_N_per_FS=...,
    lowpass_Hz=...,
    channel=...,
    strict: bool,
) -> list[Recording | Excluded]: ...
def load(
    paths_or_dir,
    *,
    height_m: float | None = None,
    manifest=None,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    lowpass_Hz: float | None = None,
    channel: int | str | None = None,
    strict: bool = True,
):
    """Read many recordings: files and/or directories (``*.csv``, ``*.wav``, ``*.npy``, ``*.mat``,
    ``*.uff``/``*.unv``, ``*.tdms``).

    A directory expands to its files of these types, sorted by name (a ``manifest.csv``
    inside it is used as the manifest, not read as a recording).

    Drop height of each file, first found: the ``height_m`` argument (all files), the
    manifest (a CSV with columns ``file,height_m`` and optionally
    ``calibration_N_per_FS``, ``rate_Hz``, ``lowpass_Hz``, ``channel`` (a number, or a
    name for MAT/UFF/TDMS files), matched on the file name; or a mapping ``{file name:
    height_m}`` or ``{file name: {column: value}}``), the file name (``h100_d1.csv`` ->
    1.00 m: ``hNNN`` in centimetres). The manifest's other values (``calibration_N_per_FS``,
    ``rate_Hz``, ``lowpass_Hz``, ``channel``) override the arguments for that file; its height
    does not override a ``height_m`` argument.

    Args:
        paths_or_dir: a file or directory (``str`` or path), or an iterable of them.
        height_m: drop height in metres of every file (overrides the manifest and the
            names).
        manifest: a manifest CSV file, or a mapping ``{file name: height_m}`` or
            ``{file name: {column: value}}``; default: a ``manifest.csv`` in a directory
            given.
        rate_Hz: sampling rate, Hz, for the files that need one (see :func:`read_file`).
        calibration_N_per_FS: newtons per full scale (or per unit), passed to the files
            other than ``.csv`` and ``.npy``.
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).
        channel: the channel to read, passed to the files other than ``.csv`` and ``.npy``.
        strict: a clipped file (:class:`ClippedRecordError`) is refused (True, the
            default) or returned as an :class:`Excluded` entry with the reason (False), in
            its place among the recordings.

    Returns:
        A list of :class:`Recording` in file order (each directory's files sorted by
            name), with an :class:`Excluded` in place of each clipped file when
            ``strict=False``.

    Raises:
        DataError: a file cannot be read (see the readers), a path is neither a file nor
            a directory, a directory holds no recording, a height cannot be known, no file
            at the ``manifest`` path, the manifest is empty, lacks the ``file`` and
            ``height_m`` columns, has a line of the wrong length or a non-numeric value, the
            files have different sample rates, nothing to read.
        ClippedRecordError: a clipped file, with ``strict=True``.
        MissingFormatError: a file's optional reader is not installed.
    """
    if isinstance(paths_or_dir, (str, os.PathLike)):
        items = [paths_or_dir]
    else:
        items = list(paths_or_dir)
    files: list[Path] = []
    for it in items:
        p = Path(it)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file() and q.suffix.lower() in SUFFIXES)
            mf = p / "manifest.csv"
            if mf.is_file():
                found = [q for q in found if q.name != "manifest.csv"]
                if manifest is None:
                    manifest = mf
            if not found:
                raise DataError(f"{p}: no recording ({_KNOWN}) in this directory")
            files += found
        elif p.is_file():
            files.append(p)
        else:
            raise DataError(f"{p}: no such file or directory")
    if not files:
        raise DataError("load(): nothing to read")
    table = _read_manifest(manifest) if manifest is not None else {}
    if manifest is not None and not isinstance(manifest, Mapping):
        files = [f for f in files if f.resolve() != Path(manifest).resolve()]

    recs: list[Recording | Excluded] = []
    for f in files:
        entry = table.get(f.name, {})
        h = height_m if height_m is not None else entry.get("height_m")
        if h is None:
            h = height_from_name(f.name)
        if h is None:
            raise DataError(
                f"cannot know the drop height of {f.name}: pass height_m=, a manifest, "
                "or name it hNNN_... (NNN in centimetres)"
            )
        kwargs: dict = {"rate_Hz": rate_Hz, "lowpass_Hz": lowpass_Hz}
        if f.suffix.lower() not in _ONE_CHANNEL:  # the arguments apply to the files that take them
            kwargs.update(calibration_N_per_FS=calibration_N_per_FS, channel=channel)
        kwargs.update({k: v for k, v in entry.items() if k != "height_m"})
        try:
            recs.append(read_file(f, height_m=h, **kwargs))
        except ClippedRecordError as err:
            if strict:
                raise
            recs.append(Excluded(f.name, h, str(err)))
    require_same_rate([r for r in recs if isinstance(r, Recording)])
    return recs

"""Readers of force-plate recordings written as text or NumPy: :func:`read_csv`, :func:`read_npy`.

The other formats have a module each (:mod:`.wav`, :mod:`.matlab`, :mod:`.uff`,
:mod:`.tdms`); :func:`rbjax.data.load` (:mod:`.loading`) reads many files of any of them.

Bad data raise :class:`DataError` (a ``ValueError``) naming the file, or warn with
:class:`DataWarning`; nothing is silently repaired. Checked: empty or truncated files,
missing/unknown columns, non-numeric values, NaN/inf, fewer than ``MIN_SAMPLES``
samples, a non-uniform time column, clipping.
"""

from __future__ import annotations

import csv
import io
import os

import numpy as np

from .columns import decimal_places, infer_rate, parse_column
from .errors import DataError
from .recording import Recording, check_force, check_height, file_recording
from .sources import as_source, existing_file, height_from_name

__all__ = ["read_csv", "read_npy"]


# --------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------


def read_csv(
    path,
    *,
    rate_Hz: float | None = None,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
) -> Recording:
    """Read a force record from a CSV file.

    Columns: a time column (``time_s``, ``time``, ``t``; units ``s`` or ``ms`` in the
    name, e.g. ``time [ms]``) and a force column (``force_N``, ``force``, ``F``; units
    ``N`` or ``kN``), names case-insensitive; or a single force column (with or without
    header), then ``rate_Hz`` is required. A header-less file with two numeric columns is
    read as (time in s, force in N). Delimiter ``,``, ``;`` or tab; lines starting with
    ``#`` are skipped.

    The sampling rate is inferred from the time column, which must be uniform to 1 %
    of a sample beyond its printed resolution; a rate within that tolerance of a whole
    number of Hz is rounded to it (``44100.01`` -> ``44100``). If ``rate_Hz`` is also
    given it must agree with the column to 1e-4.

    Args:
        path: CSV file.
        rate_Hz: sampling rate in Hz, needed without a time column.
        height_m: drop height in metres; default: from the file name (``hNNN``), else None.
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).

    Returns:
        The :class:`Recording` (``source`` the file's name), with a note for a time column
            that does not start at 0 or is written coarsely.

    Raises:
        DataError: no file at ``path``; an empty, truncated or non-text file,
            missing/unknown/ambiguous columns, non-numeric or non-finite values, fewer than
            ``MIN_SAMPLES`` rows, a constant signal, non-uniform time, no ``rate_Hz``
            without a time column or one that disagrees with it, a drop height that is not
            positive; clipping (:class:`ClippedRecordError`).
    """
    source = as_source(path)
    try:
        text = existing_file(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise DataError(f"{source}: not a text CSV file ({e})") from None
    lines = [
        (k + 1, ln)
        for k, ln in enumerate(text.splitlines())
        if ln.strip() and not ln.lstrip().startswith("#")
    ]
    if not lines:
        raise DataError(f"{source}: empty file")
    first = lines[0][1]
    delim = max([",", ";", "\t"], key=first.count)
    if first.count(delim) == 0:
        delim = ","
    rows = list(csv.reader(io.StringIO("\n".join(ln for _, ln in lines)), delimiter=delim))
    linenos = [k for k, _ in lines]

    def _isnum(s):
        try:
            float(s)
            return True
        except ValueError:
            return False

    header = rows[0]
    has_header = not all(_isnum(f) for f in header)
    t_col = f_col = None
    t_scale = f_scale = 1.0
    if has_header:
        kinds = [parse_column(h) for h in header]
        for k, (kind, val) in enumerate(kinds):
            if kind in ("time?", "force?"):
                raise DataError(
                    f"{source}: column {header[k]!r}: unknown unit {val!r} "
                    f"({'s, ms' if kind == 'time?' else 'N, kN'} understood)"
                )
        t_cols = [k for k, (kind, _) in enumerate(kinds) if kind == "time"]
        f_cols = [k for k, (kind, _) in enumerate(kinds) if kind == "force"]
        if len(t_cols) > 1 or len(f_cols) > 1:
            raise DataError(
                f"{source}: ambiguous columns {header}: more than one time or force column"
            )
        if not f_cols:
            if len(header) == 1 and not t_cols:
                raise DataError(
                    f"{source}: column {header[0]!r} is not a force column (expected force_N, "
                    "force or F)"
                )
            raise DataError(
                f"{source}: no force column among {header} (expected force_N, force or F, "
                "case-insensitive, optionally with a unit N or kN)"
            )
        f_col, f_scale = f_cols[0], kinds[f_cols[0]][1]
        if t_cols:
            t_col, t_scale = t_cols[0], kinds[t_cols[0]][1]
        data_rows, data_lines = rows[1:], linenos[1:]
        n_fields = len(header)
    else:
        n_fields = len(header)
        if n_fields == 1:
            f_col = 0
        elif n_fields == 2:
            t_col, f_col = 0, 1
        else:
            raise DataError(
                f"{source}: {n_fields} columns without a header; name them (time_s, force_N)"
            )
        data_rows, data_lines = rows, linenos
    if not data_rows:
        raise DataError(f"{source}: no data rows after the header (empty or truncated file)")

    t_txt, f_txt = [], []
    for row, ln in zip(data_rows, data_lines):
        if len(row) != n_fields or any(not c.strip() for c in row):
            raise DataError(
                f"{source}: line {ln} has {sum(bool(c.strip()) for c in row)} of {n_fields} fields "
                f"({delim.join(row)!r}); truncated file?"
            )
        f_txt.append(row[f_col])
        if t_col is not None:
            t_txt.append(row[t_col])
    try:
        force = np.array(f_txt, dtype=np.float64) * f_scale
        t = np.array(t_txt, dtype=np.float64) * t_scale if t_col is not None else None
    except ValueError:
        cols = [(f_col, f_txt)] + ([(t_col, t_txt)] if t_col is not None else [])
        for col, vals in cols:
            for k, v in enumerate(vals):
                if not _isnum(v):
                    raise DataError(
                        f"{source}: line {data_lines[k]}: non-numeric value {v.strip()!r} in "
                        f"column {col + 1}"
                    ) from None
        raise  # pragma: no cover
    if t is not None:
        bad = ~np.isfinite(t)
        if bad.any():
            k = int(np.argmax(bad))
            raise DataError(
                f"{source}: line {data_lines[k]}: time {t_txt[k].strip()!r} is not finite"
            )
    check_force(force, source)

    notes = []
    if t is not None:
        dec = [decimal_places(s) for s in t_txt[: min(len(t_txt), 1000)]]
        known = [d for d in dec if d is not None]
        quantum = 0.0 if len(known) < len(dec) else 10.0 ** (-max(known)) * t_scale
        rate_t, t0, more = infer_rate(t, quantum, source)
        notes += more
        if t0 != 0 and abs(t0) > 0.5 / rate_t:
            notes.append(
                f"time column starts at {t0:.9g} s; times here count from the first sample"
            )
        if rate_Hz is not None:
            if abs(float(rate_Hz) - rate_t) > 1e-4 * rate_t:
                raise DataError(
                    f"{source}: rate_Hz={rate_Hz!r} disagrees with the time column ({rate_t:.8g} "
                    "Hz)"
                )
            rate_t = float(rate_Hz)
        rate = rate_t
    else:
        if rate_Hz is None:
            raise DataError(f"{source}: no time column: pass rate_Hz=")
        rate = float(rate_Hz)
    return file_recording(source, force, rate, height_m, lowpass_Hz=lowpass_Hz, notes=notes)


# --------------------------------------------------------------------------------------
# NPY
# --------------------------------------------------------------------------------------


def read_npy(
    path_or_array,
    *,
    rate_Hz: float,
    height_m: float | None = None,
    lowpass_Hz: float | None = None,
    source: str | None = None,
) -> Recording:
    """A force record (newtons) from a ``.npy`` file or an array, sampled at ``rate_Hz``.

    The array must be 1-D (or ``(n, 1)`` / ``(1, n)``). ``source`` names an array in
    messages (default ``"<array>"``); for a file, its name is used and the drop height
    defaults to the one in the name.

    Args:
        path_or_array: a ``.npy`` file (``str`` or path) or an array-like of forces, N.
        rate_Hz: sampling rate, Hz.
        height_m: drop height, m; default for a file: from its name (``hNNN``), else None.
        lowpass_Hz: declared cutoff of the measuring chain, Hz (stored, not applied).
        source: name of an array in messages and in the result (ignored for a file).

    Returns:
        The :class:`Recording` (``source`` the file's name, or ``source`` for an array).

    Raises:
        DataError: no file at the path given, an empty or unreadable file, a ``.npz``
            archive, a non-numeric array or one that is not 1-D, no ``rate_Hz``, NaN or
            inf, fewer than ``MIN_SAMPLES`` samples, a constant signal, a drop height that
            is not positive; a flat top (:class:`ClippedRecordError`).
    """
    if isinstance(path_or_array, (str, os.PathLike)):
        src = as_source(path_or_array)
        p = existing_file(path_or_array)
        if p.stat().st_size == 0:
            raise DataError(f"{src}: empty file")
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError, EOFError) as e:
            raise DataError(f"{src}: cannot read as .npy ({e}); truncated file?") from None
        if isinstance(arr, np.lib.npyio.NpzFile):
            raise DataError(f"{src}: .npz archives are not supported; save one array with np.save")
        if height_m is None:
            height_m = height_from_name(src)
    else:
        src = source or "<array>"
        arr = path_or_array
    try:
        a = np.asarray(arr, dtype=np.float64)
    except (TypeError, ValueError):
        raise DataError(f"{src}: not a numeric array") from None
    if a.ndim == 2 and 1 in a.shape:
        a = a.reshape(-1)
    if a.ndim != 1:
        raise DataError(f"{src}: expected a 1-D force array, got shape {a.shape}")
    if rate_Hz is None:
        raise DataError(f"{src}: pass rate_Hz= (a bare array has no time base)")
    check_force(a, src)
    return Recording(
        source=src,
        height_m=check_height(height_m, src),
        rate_Hz=float(rate_Hz),
        force_N=a,
        lowpass_Hz=lowpass_Hz,
    )

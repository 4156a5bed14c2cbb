"""Readers of force-plate recordings: CSV, WAV, NPY, and many files at once.

:func:`read_csv`, :func:`read_wav` (``scipy.io.wavfile``), :func:`read_npy` read one
file each; :func:`load` reads many files (or a directory) and resolves each drop
height from an argument, a manifest CSV or the file name (``h100_d1.csv`` -> 1.00 m).

Bad data raise :class:`DataError` (a ``ValueError``) naming the file, or warn with
:class:`DataWarning`; nothing is silently repaired. Checked: empty or truncated files,
missing/unknown columns, non-numeric values, NaN/inf, fewer than ``MIN_SAMPLES``
samples, a non-uniform time column, clipping, mixed sample rates, an unknown drop height.
"""

from __future__ import annotations

import csv
import io
import os
import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .errors import DataError
from .recording import Recording, _check_force, _check_height, _require_same_rate
from .sources import _as_source, height_from_name
from .wav import read_wav

__all__ = ["height_from_name", "read_csv", "read_wav", "read_npy", "load"]


# --------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------

_TIME_NAMES = {"time": 1.0, "t": 1.0}
_FORCE_NAMES = {"force": 1.0, "f": 1.0}
_TIME_UNITS = {None: 1.0, "s": 1.0, "sec": 1.0, "ms": 1e-3}
_FORCE_UNITS = {None: 1.0, "n": 1.0, "kn": 1e3}
_COL_RE = re.compile(r"^\s*([a-z]+)\s*(?:[_\s]\s*([a-z]+)|[\[(]\s*([a-z]+)\s*[\])])?\s*$")


def _parse_column(name: str):
    """('time'|'force'|None, scale) for a header field such as ``time_s``, ``F [kN]``."""
    m = _COL_RE.match(name.strip().lower())
    if not m:
        return None, None
    base, unit = m.group(1), m.group(2) or m.group(3)
    if base in _TIME_NAMES:
        if unit not in _TIME_UNITS:
            return "time?", unit
        return "time", _TIME_UNITS[unit]
    if base in _FORCE_NAMES:
        if unit not in _FORCE_UNITS:
            return "force?", unit
        return "force", _FORCE_UNITS[unit]
    return None, None


def _decimals(s: str) -> int | None:
    s = s.strip()
    if "e" in s.lower():
        return None
    if "." not in s:
        return 0
    return len(s.split(".", 1)[1])


def _infer_rate(t: np.ndarray, quantum_s: float, source: str) -> tuple[float, float, list[str]]:
    """Uniform-sampling check of a time column; returns (rate_Hz, t0_s, notes)."""
    dt_steps = np.diff(t)
    if np.any(dt_steps <= 0):
        k = int(np.argmax(dt_steps <= 0))
        raise DataError(
            f"{source}: time column is not strictly increasing (sample {k + 1}: "
            f"{t[k + 1]!r} s after {t[k]!r} s)"
        )
    n = t.size
    i = np.arange(n, dtype=np.float64)
    dt, t0 = np.polyfit(i, t, 1)
    resid = t - (t0 + dt * i)
    tol = 0.5 * quantum_s * 1.01 + 0.01 * dt
    worst = float(np.abs(resid).max())
    if worst > tol:
        k = int(np.argmax(np.abs(resid)))
        raise DataError(
            f"{source}: non-uniform time column: sample {k} is {resid[k] / dt:+.3f} samples off a "
            f"uniform grid of {1 / dt:.6g} Hz (tolerance {tol / dt:.3f} samples); resample first"
        )
    notes = []
    if quantum_s > 0.1 * dt:
        notes.append(
            f"time column resolution {quantum_s:g} s is coarse for {1 / dt:.6g} Hz sampling; "
            "the rate comes from a fit over the whole column"
        )
    rate = 1.0 / dt
    cand = float(round(rate))
    if cand > 0:
        t0c = float(np.mean(t - i / cand))
        if np.abs(t - (t0c + i / cand)).max() <= tol:
            rate, t0 = cand, t0c
    return float(rate), float(t0), notes


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

    Raises:
      DataError: empty or truncated file, missing/unknown columns, non-numeric or
        non-finite values, fewer than ``MIN_SAMPLES`` rows, non-uniform time, clipping.
    """
    source = _as_source(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise DataError(f"{source}: not a text CSV file ({e})") from None
    lines = [(k + 1, ln) for k, ln in enumerate(text.splitlines()) if ln.strip() and not ln.lstrip().startswith("#")]
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
        kinds = [_parse_column(h) for h in header]
        for k, (kind, val) in enumerate(kinds):
            if kind in ("time?", "force?"):
                raise DataError(
                    f"{source}: column {header[k]!r}: unknown unit {val!r} "
                    f"({'s, ms' if kind == 'time?' else 'N, kN'} understood)"
                )
        t_cols = [k for k, (kind, _) in enumerate(kinds) if kind == "time"]
        f_cols = [k for k, (kind, _) in enumerate(kinds) if kind == "force"]
        if len(t_cols) > 1 or len(f_cols) > 1:
            raise DataError(f"{source}: ambiguous columns {header}: more than one time or force column")
        if not f_cols:
            if len(header) == 1 and not t_cols:
                raise DataError(
                    f"{source}: column {header[0]!r} is not a force column (expected force_N, force or F)"
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
                        f"{source}: line {data_lines[k]}: non-numeric value {v.strip()!r} in column {col + 1}"
                    ) from None
        raise  # pragma: no cover
    if t is not None:
        bad = ~np.isfinite(t)
        if bad.any():
            k = int(np.argmax(bad))
            raise DataError(f"{source}: line {data_lines[k]}: time {t_txt[k].strip()!r} is not finite")
    _check_force(force, source)

    notes = []
    if t is not None:
        dec = [_decimals(s) for s in t_txt[: min(len(t_txt), 1000)]]
        known = [d for d in dec if d is not None]
        quantum = 0.0 if len(known) < len(dec) else 10.0 ** (-max(known)) * t_scale
        rate_t, t0, more = _infer_rate(t, quantum, source)
        notes += more
        if t0 != 0 and abs(t0) > 0.5 / rate_t:
            notes.append(f"time column starts at {t0:.9g} s; times here count from the first sample")
        if rate_Hz is not None:
            if abs(float(rate_Hz) - rate_t) > 1e-4 * rate_t:
                raise DataError(
                    f"{source}: rate_Hz={rate_Hz!r} disagrees with the time column ({rate_t:.8g} Hz)"
                )
            rate_t = float(rate_Hz)
        rate = rate_t
    else:
        if rate_Hz is None:
            raise DataError(f"{source}: no time column: pass rate_Hz=")
        rate = float(rate_Hz)
    if height_m is None:
        height_m = height_from_name(source)
    return Recording(
        source=source,
        height_m=_check_height(height_m, source),
        rate_Hz=rate,
        force_N=force,
        lowpass_Hz=lowpass_Hz,
        notes=tuple(notes),
    )


# --------------------------------------------------------------------------------------
# WAV
# --------------------------------------------------------------------------------------


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
    """
    if isinstance(path_or_array, (str, os.PathLike)):
        src = _as_source(path_or_array)
        p = Path(path_or_array)
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
    _check_force(a, src)
    return Recording(
        source=src,
        height_m=_check_height(height_m, src),
        rate_Hz=float(rate_Hz),
        force_N=a,
        lowpass_Hz=lowpass_Hz,
    )


# --------------------------------------------------------------------------------------
# many files
# --------------------------------------------------------------------------------------

_SUFFIXES = (".csv", ".wav", ".npy")


def _read_manifest(manifest) -> dict[str, dict]:
    if isinstance(manifest, Mapping):
        out = {}
        for k, v in manifest.items():
            out[Path(k).name] = dict(v) if isinstance(v, Mapping) else {"height_m": v}
        return out
    src = _as_source(manifest)
    text = Path(manifest).read_text(encoding="utf-8-sig")
    rows = [r for r in csv.reader(io.StringIO(text)) if any(c.strip() for c in r)]
    if not rows:
        raise DataError(f"manifest {src}: empty file")
    header = [h.strip().lower() for h in rows[0]]
    if "file" not in header or "height_m" not in header:
        raise DataError(f"manifest {src}: needs columns file,height_m (found {rows[0]})")
    known = {"file", "height_m", "calibration_n_per_fs", "rate_hz", "lowpass_hz"}
    out = {}
    for k, r in enumerate(rows[1:], start=2):
        if len(r) != len(header):
            raise DataError(f"manifest {src}: line {k} has {len(r)} fields, expected {len(header)}")
        entry = {}
        for h, v in zip(header, r):
            if h == "file" or h not in known:
                continue
            v = v.strip()
            if v == "":
                continue
            try:
                entry[{"calibration_n_per_fs": "calibration_N_per_FS", "rate_hz": "rate_Hz",
                       "lowpass_hz": "lowpass_Hz"}.get(h, h)] = float(v)
            except ValueError:
                raise DataError(f"manifest {src}: line {k}: {h}={v!r} is not a number") from None
        out[Path(r[header.index("file")].strip()).name] = entry
    return out


def load(
    paths_or_dir,
    *,
    height_m: float | None = None,
    manifest=None,
    rate_Hz: float | None = None,
    calibration_N_per_FS: float | None = None,
    lowpass_Hz: float | None = None,
    channel: int | None = None,
) -> list[Recording]:
    """Read many recordings: files and/or directories (``*.csv``, ``*.wav``, ``*.npy``).

    A directory expands to its ``*.csv``/``*.wav``/``*.npy`` files, sorted by name (a
    ``manifest.csv`` inside it is used as the manifest, not read as a recording).

    Drop height of each file, first found: the ``height_m`` argument (all files), the
    manifest (a CSV with columns ``file,height_m`` and optionally
    ``calibration_N_per_FS``, ``rate_Hz``, ``lowpass_Hz``, matched on the file name; or
    a mapping ``{file name: height_m}``), the file name (``h100_d1.csv`` -> 1.00 m:
    ``hNNN`` in centimetres). Manifest values of calibration/rate/lowpass override the
    arguments for that file.

    Raises:
      DataError: a file cannot be read (see the readers), a height cannot be known,
        the files have different sample rates, nothing to read.
    """
    if isinstance(paths_or_dir, (str, os.PathLike)):
        items = [paths_or_dir]
    else:
        items = list(paths_or_dir)
    files: list[Path] = []
    for it in items:
        p = Path(it)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file() and q.suffix.lower() in _SUFFIXES)
            mf = p / "manifest.csv"
            if mf.is_file():
                found = [q for q in found if q.name != "manifest.csv"]
                if manifest is None:
                    manifest = mf
            if not found:
                raise DataError(f"{p}: no *.csv, *.wav or *.npy recording in this directory")
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

    recs = []
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
        rate = entry.get("rate_Hz", rate_Hz)
        cal = entry.get("calibration_N_per_FS", calibration_N_per_FS)
        lp = entry.get("lowpass_Hz", lowpass_Hz)
        suf = f.suffix.lower()
        if suf == ".csv":
            r = read_csv(f, rate_Hz=rate, height_m=h, lowpass_Hz=lp)
        elif suf == ".wav":
            r = read_wav(f, calibration_N_per_FS=cal, height_m=h, channel=channel, lowpass_Hz=lp)
        elif suf == ".npy":
            if rate is None:
                raise DataError(f"{f.name}: a .npy file has no time base: pass rate_Hz= or a manifest rate_Hz")
            r = read_npy(f, rate_Hz=rate, height_m=h, lowpass_Hz=lp)
        else:
            raise DataError(f"{f.name}: unknown file type {f.suffix!r} (csv, wav, npy)")
        recs.append(r)
    _require_same_rate(recs)
    return recs

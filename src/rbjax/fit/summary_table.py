"""Summary figures of a ball, per drop height: what a calibration certificate or a paper gives.

A table has one row per drop height and any of these figures (an empty cell: not measured):

* ``contact_time_s``, ``peak_force_N``, ``restitution``;
* ``lfe_<band>_dB``: the octave-band force exposure level L_FE (Eq. 11) of a 1 s record,
  bands by their nominal centre ``31.5`` … ``1000`` (``rbjax.spectrum.bands.OCTAVE_BANDS``);
* ``lfe_third_<band>_dB``: the same in one-third-octave bands ``25`` … ``1250``.

Each may have an uncertainty (one standard deviation) in a column of the same name with ``_sd``
appended (``contact_time_s_sd``). Where none is given the default of :data:`DEFAULT_SD` is used
(the noise level the paper reports, §4.1: < 0.1 ms; 1 % of a force; 0.2 dB), and the table
says so in :attr:`SummaryTable.notes`.

Files: CSV (a header row of column names; lines starting with ``#`` are comments, e.g. where the
figures are quoted from) or TOML (``[[height]]`` tables with the same keys). Every problem is a
:class:`SummaryTableError` naming the file, the row (CSV: the line; TOML: the ``[[height]]``
table, from 1) and the column.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..data.errors import DataError
from ..spectrum.bands import OCTAVE_BANDS, THIRD_OCTAVE_BANDS

HEIGHT_COLUMN = "height_m"
SCALAR_FIGURES = ("contact_time_s", "peak_force_N", "restitution")
OCTAVE_FIGURES = tuple(f"lfe_{b}_dB" for b in OCTAVE_BANDS)
THIRD_OCTAVE_FIGURES = tuple(f"lfe_third_{b}_dB" for b in THIRD_OCTAVE_BANDS)
#: Every figure a table may hold, in the order of a fit's residual vector.
FIGURES = SCALAR_FIGURES + OCTAVE_FIGURES + THIRD_OCTAVE_FIGURES
SD_SUFFIX = "_sd"


def default_sd(figure: str, value: float) -> float:
    """The uncertainty of a figure given without one (the paper's noise level, §4.1):
    0.1 ms for a contact time, 1 % of a peak force, 0.01 for a restitution, 0.2 dB for an L_FE."""
    if figure == "contact_time_s":
        return 1e-4
    if figure == "peak_force_N":
        return 0.01 * abs(value)
    if figure == "restitution":
        return 0.01
    return 0.2


#: The defaults of :func:`default_sd`, as the notes state them.
DEFAULT_SD = {
    "contact_time_s": "0.1 ms",
    "peak_force_N": "1 % of the value",
    "restitution": "0.01",
    "lfe_*_dB": "0.2 dB",
}


class SummaryTableError(DataError):
    """A summary table cannot be used as it is; the message names the file, row and column."""


@dataclasses.dataclass(frozen=True, eq=False)
class SummaryTable:
    """Figures per drop height (build one with :func:`summary_table` or
    :func:`read_summary`, which check it).

    Args:
        heights_m: the drop heights, m.
        values: figure → array over ``heights_m`` (NaN where not measured).
        sd: figure → the figure's standard deviation over ``heights_m``.
        source: the file the table came from (or ``"<table>"``).
        rows: the row label of each height in it.
        notes: what was assumed (default uncertainties).
    """

    heights_m: np.ndarray
    values: Mapping[str, np.ndarray]
    sd: Mapping[str, np.ndarray]
    source: str = "<table>"
    rows: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()

    @property
    def figures(self) -> tuple[str, ...]:
        """The figures the table holds (at least one height), in :data:`FIGURES` order."""
        return tuple(f for f in FIGURES if f in self.values)

    def entries(self) -> list[tuple[int, str]]:
        """(height index, figure) of every measured figure, height by height."""
        return [
            (i, f)
            for i in range(self.heights_m.size)
            for f in self.figures
            if np.isfinite(self.values[f][i])
        ]

    @property
    def n_figures(self) -> int:
        return len(self.entries())

    def to_dict(self) -> dict:
        return {
            "source": self.source,
            "heights_m": self.heights_m.tolist(),
            "figures": {
                f: {"value": _nulls(self.values[f]), "sd": _nulls(self.sd[f])} for f in self.figures
            },
            "notes": list(self.notes),
        }


def _nulls(arr) -> list:
    return [None if not np.isfinite(x) else float(x) for x in arr]


def summary_table(
    rows: list[Mapping], source: str = "<table>", row_labels: list[str] | None = None
) -> SummaryTable:
    """A :class:`SummaryTable` from rows, checked.

    Args:
        rows: one mapping per drop height, column → number or None: ``height_m`` and any of
            the figures (contact time, peak force, restitution, L_FE per band), each optionally
            with its standard deviation (the figure + ``_sd``; a default where absent).
        source: what the rows came from, for the messages.
        row_labels: each row's label in the messages (default ``row 1``, ``row 2``, …).

    Returns:
        The :class:`SummaryTable`.

    Raises:
        SummaryTableError: no rows, an unknown column, a cell that is not a finite number, or
            a height given twice (the message names the source, row and column).
    """
    labels = row_labels or [f"row {k + 1}" for k in range(len(rows))]
    where = lambda k, col: f"{source}, {labels[k]}, column {col!r}"  # noqa: E731
    valid = (HEIGHT_COLUMN,) + FIGURES + tuple(f + SD_SUFFIX for f in FIGURES)
    if not rows:
        raise SummaryTableError(
            f"{source}: no rows; give one row per drop height with {HEIGHT_COLUMN} and any of "
            f"{', '.join(FIGURES[:4])} …"
        )
    heights: list[float] = []
    values: dict[str, list[float]] = {f: [] for f in FIGURES}
    sds: dict[str, list[float]] = {f: [] for f in FIGURES}
    defaulted: set[str] = set()
    for k, row in enumerate(rows):
        for col in row:
            if col not in valid:
                raise SummaryTableError(
                    f"{where(k, col)}: unknown column; valid: {HEIGHT_COLUMN}, "
                    f"{', '.join(FIGURES)}, and any of them + {SD_SUFFIX!r}"
                )
        cells = {col: _number(row[col], where(k, col)) for col in row}
        h = cells.get(HEIGHT_COLUMN)
        if h is None or not h > 0:
            raise SummaryTableError(
                f"{where(k, HEIGHT_COLUMN)}: a drop height > 0 m is required (got "
                f"{row.get(HEIGHT_COLUMN)!r}; valid range (0, inf))"
            )
        if any(math.isclose(h, other, abs_tol=5e-4) for other in heights):
            raise SummaryTableError(
                f"{where(k, HEIGHT_COLUMN)}: height {h:g} m occurs twice; give one row per drop "
                "height"
            )
        heights.append(h)
        measured = 0
        for f in FIGURES:
            v, s = cells.get(f), cells.get(f + SD_SUFFIX)
            if v is None:
                if s is not None:
                    raise SummaryTableError(
                        f"{where(k, f + SD_SUFFIX)}: an uncertainty without a value in column {f!r}"
                    )
                values[f].append(np.nan)
                sds[f].append(np.nan)
                continue
            measured += 1
            if s is None:
                s = default_sd(f, v)
                defaulted.add(f)
            if not s > 0:
                raise SummaryTableError(
                    f"{where(k, f + SD_SUFFIX)}: uncertainty {s!r} must be positive (valid range "
                    "(0, inf))"
                )
            if f in SCALAR_FIGURES and not v > 0:
                raise SummaryTableError(
                    f"{where(k, f)}: {v!r} must be positive (valid range (0, inf))"
                )
            if f == "restitution" and not v <= 1:
                raise SummaryTableError(
                    f"{where(k, f)}: {v!r} must be at most 1 (valid range (0, 1])"
                )
            values[f].append(v)
            sds[f].append(s)
        if measured == 0:
            raise SummaryTableError(
                f"{source}, {labels[k]}: height {h:g} m has no figure; give at least one of "
                f"{', '.join(FIGURES[:4])} …"
            )
    order = np.argsort(heights)
    keep = [f for f in FIGURES if np.any(np.isfinite(values[f]))]
    notes = []
    if defaulted:
        names = ", ".join(f for f in FIGURES if f in defaulted)
        notes.append(
            f"No uncertainty given for {names}: the default used is "
            + "; ".join(
                f"{k} {v}" for k, v in DEFAULT_SD.items() if any(_matches(k, f) for f in defaulted)
            )
            + " (the paper's noise level, §4.1)."
        )
    return SummaryTable(
        heights_m=np.asarray(heights, dtype=float)[order],
        values={f: np.asarray(values[f], dtype=float)[order] for f in keep},
        sd={f: np.asarray(sds[f], dtype=float)[order] for f in keep},
        source=source,
        rows=tuple(labels[i] for i in order),
        notes=tuple(notes),
    )


def _matches(pattern: str, figure: str) -> bool:
    return figure.startswith("lfe_") if pattern == "lfe_*_dB" else pattern == figure


def _number(cell, where: str) -> float | None:
    if cell is None or (isinstance(cell, str) and not cell.strip()):
        return None
    try:
        x = float(cell)
    except (TypeError, ValueError):
        raise SummaryTableError(f"{where}: {cell!r} is not a number") from None
    if not math.isfinite(x):
        raise SummaryTableError(f"{where}: {cell!r} is not a finite number")
    return x


def read_summary(path) -> SummaryTable:
    """Read a summary table from a ``.csv`` or ``.toml`` file (see the module docstring).

    Args:
        path: the file.

    Returns:
        The :class:`SummaryTable`, checked as :func:`summary_table` checks rows.

    Raises:
        SummaryTableError: no such file, an unknown format, or a table that cannot be used
            (the message names the file, row and column).
    """
    path = Path(path)
    if not path.is_file():
        raise SummaryTableError(f"{path}: no such file (a summary table: .csv or .toml)")
    if path.suffix.lower() == ".toml":
        try:
            doc = tomllib.loads(path.read_text())
        except tomllib.TOMLDecodeError as err:
            raise SummaryTableError(f"{path}: not valid TOML: {err}") from None
        unknown = sorted(set(doc) - {"height", "source", "note"})
        if unknown or not isinstance(doc.get("height"), list):
            raise SummaryTableError(
                f"{path}: expected [[height]] tables (and optional 'source', 'note'); found keys "
                f"{sorted(doc)}"
            )
        rows = doc["height"]
        return summary_table(rows, str(path), [f"[[height]] {k + 1}" for k in range(len(rows))])
    if path.suffix.lower() != ".csv":
        raise SummaryTableError(f"{path}: unknown format {path.suffix!r}; valid: .csv, .toml")
    lines = [
        (n, line)
        for n, line in enumerate(path.read_text().splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise SummaryTableError(f"{path}: no header row")
    reader = list(csv.reader([line for _, line in lines]))
    header = [c.strip() for c in reader[0]]
    rows, labels = [], []
    for (n, _), cells in zip(lines[1:], reader[1:]):
        if len(cells) > len(header):
            raise SummaryTableError(
                f"{path}, line {n}: {len(cells)} cells but {len(header)} columns in the header"
            )
        rows.append(dict(zip(header, cells)))
        labels.append(f"line {n}")
    if HEIGHT_COLUMN not in header:
        raise SummaryTableError(
            f"{path}, line {lines[0][0]}, column {HEIGHT_COLUMN!r}: missing; the header needs "
            f"{HEIGHT_COLUMN} and figure columns"
        )
    for col in header:
        if col and col not in (HEIGHT_COLUMN,) + FIGURES + tuple(f + SD_SUFFIX for f in FIGURES):
            raise SummaryTableError(
                f"{path}, line {lines[0][0]}, column {col!r}: unknown column; valid: "
                f"{HEIGHT_COLUMN}, {', '.join(FIGURES)}, and any of them + {SD_SUFFIX!r}"
            )
    return summary_table(rows, str(path), labels)

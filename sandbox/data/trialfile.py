"""One trial file: its columns, read as floats within the loader's limits, and checked.

:func:`read_trial_table` reads the chosen columns of a CSV trial file row by
row, never holding more than the chosen cells, and refuses a file beyond the
limits of :mod:`sandbox.data.limits` (bytes per file, line and field, rows per
file) or malformed CSV with a :class:`TrialError`. :func:`check_plausible`
refuses a trial whose times, robot joints or values are implausible (a span
over a minute or in another time unit, a joint outside Baxter's URDF limits, a
huge value). :mod:`sandbox.data.recorded` turns a file into a demonstration.
"""

from __future__ import annotations

import csv
import difflib
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.limits import (
    JOINT_LIMIT_TOL_RAD,
    MAX_ABS_VALUE,
    MAX_FIELD_BYTES,
    MAX_FILE_BYTES,
    MAX_LINE_BYTES,
    MAX_ROWS_PER_FILE,
    check_duration,
    joint_limits,
)
from sandbox.data.spec import HAND, ROBOT_COLUMNS, TIME_COLUMN, DataSpec
from sandbox.validation import FloatArray

HUMAN_COLUMNS = HAND.dims


class TrialError(ValueError):
    """A trial file that cannot be used; the message says why."""



@dataclass(frozen=True)
class Columns:
    """Which CSV columns to read (the physical columns; see :meth:`from_spec`).

    As a loader argument it is shorthand for a spec whose ``hand`` modality is
    ``human`` (:meth:`~sandbox.data.spec.DataSpec.with_columns`).

    Parameters
    ----------
    human : sequence of str
        Human dims (m), e.g. the left hand x, y, z.
    robot : sequence of str
        Robot dims (rad), e.g. Baxter's seven left-arm joints.
    time : str
        Time column (s).
    """

    human: tuple[str, ...] = HUMAN_COLUMNS
    robot: tuple[str, ...] = ROBOT_COLUMNS
    time: str = TIME_COLUMN

    def __post_init__(self) -> None:
        if not isinstance(self.time, str) or not self.time:
            raise ValueError(f"time column: expected a non-empty name, got {self.time!r}")
        for name in ("human", "robot"):
            given = getattr(self, name)
            if isinstance(given, (str, bytes)) or not isinstance(given, Sequence):
                raise ValueError(f"{name} columns: expected a sequence of names such as "
                                 f"('x', 'y', 'z'), got {given!r}")
            cols = tuple(given)
            if not cols or not all(isinstance(c, str) and c for c in cols):
                raise ValueError(f"{name} columns: expected non-empty names, got {cols!r}")
            object.__setattr__(self, name, cols)
        wanted = (self.time, *self.human, *self.robot)
        twice = sorted({c for c in wanted if wanted.count(c) > 1})
        if twice:
            raise ValueError(f"columns: each column may be used once, got {twice} more than once")

    @property
    def all(self) -> tuple[str, ...]:
        """Every column read: the time, the human columns, then the robot columns."""
        return (self.time, *self.human, *self.robot)

    @classmethod
    def from_spec(cls, spec: DataSpec, modalities: Sequence[Modality]) -> Columns:
        """The columns to read for these modalities of a spec."""
        return cls(tuple(c for m in modalities for c in m.dims), spec.robot, spec.time)

    def as_spec(self) -> DataSpec:
        """The hand-only spec these columns stand for."""
        return DataSpec().with_columns(human=self.human, robot=self.robot, time=self.time)


def _clean_name(name: str) -> str:
    return name.replace("\ufeff", "").strip().strip("\"'").strip()


def _column_index(header: list[str], wanted: Sequence[str], fix: Callable[[str], str]
                  ) -> list[int]:
    names = [_clean_name(h) for h in header]
    index = []
    for col in wanted:
        hits = [i for i, n in enumerate(names) if n == col]
        if len(hits) > 1:
            raise TrialError(f"column {col!r} appears {len(hits)} times (columns {hits})")
        if not hits:
            lower = {n.lower(): n for n in names}
            close = [lower[c] for c in difflib.get_close_matches(col.lower(), list(lower), n=2,
                                                                 cutoff=0.75)]
            hint = f" (did you mean {' or '.join(map(repr, close))}?)" if close else ""
            raise TrialError(f"missing column {col!r}{hint}{fix(col)}")
        index.append(hits[0])
    return index


def _fix(col: str, columns: Columns, owners: dict | None) -> str:
    """What fixes a missing column: the option that names it."""
    owner = (owners or {}).get(col)
    if owner is not None:
        return (f"; it is a column of modality {owner!r}: name the file's columns in a spec "
                f"(--spec FILE) or leave {owner!r} out of --observe")
    if col == columns.time:
        return ("; name the time column in a spec (--spec FILE, key 'time'), or give rate_hz "
                "for files without one")
    if col in columns.robot:
        return "; name the robot columns with --robot-columns or a spec (--spec FILE, key 'robot')"
    return "; name the human columns with --human-columns or a spec (--spec FILE)"


def _to_float(cells: list[list[str]], names: Sequence[str], first_row: int) -> FloatArray:
    """Parse a table of strings; '' and 'nan' become NaN, other text is an error."""
    table = np.array(cells, dtype=object)
    out = np.empty(table.shape)
    for (r, c), cell in np.ndenumerate(table):
        text = cell.strip()
        try:
            out[r, c] = float(text) if text else np.nan
        except ValueError:
            raise TrialError(
                f"row {first_row + r}: non-numeric value {cell!r} in column {names[c]!r}"
            ) from None
    out[~np.isfinite(out)] = np.nan
    return out


def read_trial_table(path: str | Path, columns: Columns = Columns(),
                     owners: dict | None = None) -> tuple[FloatArray, dict]:
    """Read the time, human and robot columns of one trial file as floats.

    As :func:`read_columns` with ``columns.all``; ``owners`` maps human
    columns to their modality's name, for the message of a missing column.
    """
    return read_columns(path, columns.all, lambda col: _fix(col, columns, owners))


def read_columns(path: str | Path, names: Sequence[str],
                 fix: Callable[[str], str] = lambda col: "") -> tuple[FloatArray, dict]:
    """Read the chosen columns of one trial file as floats.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    names : sequence of str
        The columns to read, in the order of the table.
    fix : callable, optional
        ``fix(column)``: what the message of a missing column adds (the option
        that names it).

    Returns
    -------
    table : ndarray, shape (n_rows, len(names))
        The columns in that order; NaN for empty cells.
    notes : dict
        ``{"truncated_last_row": bool}``.

    Raises
    ------
    TrialError
        Empty file, no data rows, missing or duplicated columns, a row with the
        wrong number of fields (other than a truncated last row), non-numeric
        text, malformed CSV, a file, row count or field beyond the limits of
        :mod:`sandbox.data.limits`, a file that cannot be read.
    """
    path = Path(path)
    if not path.is_file():
        raise TrialError("not a regular file (a folder, FIFO, device or dangling link)"
                         if path.exists() or path.is_symlink() else f"no such file: {path}")
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise TrialError(f"file of {size} bytes, expected at most {MAX_FILE_BYTES} "
                             f"(sandbox.data.limits.MAX_FILE_BYTES)")
        with path.open(newline="", encoding="utf-8", errors="replace") as fh:
            body, truncated = _read_rows(_rows(csv.reader(_lines(fh))), tuple(names), fix)
    except csv.Error as error:
        raise TrialError(f"malformed CSV ({error}; a stray quote?)") from None
    except OSError as error:
        raise TrialError(f"cannot read the file ({type(error).__name__}: {error})") from None
    table = _to_float(body, names, 2) if body else np.empty((0, len(names)))
    return table, {"truncated_last_row": truncated}


def _read_rows(rows: Iterator[list[str]], names: tuple[str, ...], fix: Callable[[str], str]
               ) -> tuple[list[list[str]], bool]:
    """The chosen cells of every data row, and whether a short last row was left out.

    Only the chosen cells are kept, so a file is never held in memory whole;
    the row limit is checked as rows arrive.
    """
    header = next(rows, None)
    if header is None:
        raise TrialError("empty file")
    index = _column_index(header, names, fix)
    body: list[list[str]] = []
    short: list[str] | None = None
    for n, row in enumerate(rows, start=2):
        if short is not None or len(row) > len(header):
            bad, k = (short, n - 1) if short is not None else (row, n)
            raise TrialError(f"row {k} has {len(bad)} fields, the header has {len(header)}")
        if len(row) < len(header):
            short = row  # allowed as the last row only (a recording cut off mid-row)
            continue
        if len(body) >= MAX_ROWS_PER_FILE:
            raise TrialError(f"more than {MAX_ROWS_PER_FILE} data rows "
                             "(sandbox.data.limits.MAX_ROWS_PER_FILE)")
        body.append([row[i] for i in index])
    if not body and short is None:
        raise TrialError("no data rows (only a header)")
    return body, short is not None


def _rows(reader: Iterator[list[str]]) -> Iterator[list[str]]:
    """The non-blank rows of a CSV reader, each field checked against the size limit."""
    for row in reader:
        long = max(map(len, row), default=0)
        if long > MAX_FIELD_BYTES:
            raise TrialError(f"line {reader.line_num}: a field of {long} characters, expected "
                             f"at most {MAX_FIELD_BYTES} (sandbox.data.limits.MAX_FIELD_BYTES;"
                             " a stray quote?)")
        if any(c.strip() for c in row):
            yield row


def _lines(fh) -> Iterator[str]:
    """The lines of a text file, refusing one longer than :data:`MAX_LINE_BYTES`."""
    for n, line in enumerate(iter(lambda: fh.readline(MAX_LINE_BYTES + 1), ""), start=1):
        if len(line) > MAX_LINE_BYTES:
            raise TrialError(f"line {n} is longer than {MAX_LINE_BYTES} characters "
                             "(sandbox.data.limits.MAX_LINE_BYTES)")
        yield line


def check_plausible(times: FloatArray, human: FloatArray, robot: FloatArray, columns: Columns,
                     max_duration: float) -> None:
    """Refuse a trial whose times, robot joints or values are implausible (issue 13).

    Parameters
    ----------
    times : ndarray, shape (T,)
        The distinct time stamps (s), increasing.
    human, robot : ndarray, shape (n, P) and (n, Q)
        The kept rows' human and robot values (NaN where missing).
    columns : Columns
        Their column names.
    max_duration : float
        Longest span accepted (s).

    Raises
    ------
    TrialError
        Naming the column, the value and the limit.
    """
    try:
        check_duration(times, f"time column {columns.time!r}", max_duration)
    except ValueError as error:
        raise TrialError(str(error).replace("raise max_duration=", "pass max_duration=")
                         ) from None
    lower, upper = joint_limits(columns.robot)
    outside = (robot < lower - JOINT_LIMIT_TOL_RAD) | (robot > upper + JOINT_LIMIT_TOL_RAD)
    if outside.any():
        r, c = np.argwhere(outside)[0]
        raise TrialError(
            f"robot column {columns.robot[c]!r} = {robot[r, c]:g} rad at data row {r + 1}, "
            f"outside its URDF limits [{lower[c]:g}, {upper[c]:g}] rad (+/- "
            f"{JOINT_LIMIT_TOL_RAD:g} rad, sandbox.data.limits.JOINT_LIMIT_TOL_RAD); "
            f"{int(outside[:, c].sum())} value(s) outside")
    for name, values, names in (("robot", robot, columns.robot), ("human", human, columns.human)):
        huge = np.abs(np.nan_to_num(values)) > MAX_ABS_VALUE
        if huge.any():
            r, c = np.argwhere(huge)[0]
            raise TrialError(f"{name} column {names[c]!r} = {values[r, c]:g} at data row {r + 1}, "
                             f"expected a magnitude of at most {MAX_ABS_VALUE:g} "
                             "(sandbox.data.limits.MAX_ABS_VALUE)")

"""Write a trial file in the recorded CSV layout ``<root>/<task>/<trial>.csv``.

The inverse of :mod:`sandbox.data.trialfile` for the built-in layout: the
header has every column of the shared recordings (:data:`RECORDED_COLUMNS`,
in their order), one row per sample. A column the caller does not give is
written as empty cells, which the loader reads as missing values (NaN): a
hand-only trial loads with ``observe="hand"``, and a modality whose columns are
all empty is skipped by the loader with the reason ("fewer than 2 valid
samples of 'arm'", "modality 'emg' is constant or missing"), never taken as
zeros.

Examples
--------
>>> import numpy as np, tempfile
>>> from pathlib import Path
>>> from sandbox.data.recorded import load_trial
>>> root = Path(tempfile.mkdtemp())
>>> t = np.linspace(0.0, 2.0, 101)
>>> cols = {**{f"human_left_hand_{a}": t * k for a, k in zip("xyz", (0.1, 0.2, 0.3))},
...         **{name: np.full(101, 0.5) for name in ROBOT_COLUMNS}}
>>> path = write_trial(next_trial_path(root / "up"), t, cols)
>>> path.name, load_trial(path, preprocess="none").human.shape
('001.csv', (101, 3))
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from sandbox.data.spec import ROBOT_COLUMNS, TIME_COLUMN
from sandbox.validation import check_times

_FRAMES = ("head", "neck", "torso", "left_shoulder", "left_elbow", "left_hand",
           "right_shoulder", "right_elbow", "right_hand")
#: Baxter's right-arm joint columns (rad).
RIGHT_ARM_COLUMNS = tuple(name.replace("left_", "right_") for name in ROBOT_COLUMNS)
#: Every column of the shared recordings (``birl-handover-20180329``), in their order.
RECORDED_COLUMNS: tuple[str, ...] = (
    TIME_COLUMN,
    *(f"human_{frame}_{axis}" for frame in _FRAMES for axis in "xyz"),
    *(f"baxter_{side}_hand_{axis}" for side in ("left", "right") for axis in "xyz"),
    *ROBOT_COLUMNS,
    *RIGHT_ARM_COLUMNS,
    *(f"emg{i}" for i in range(8)),
)
_NUMBERED = re.compile(r"^(\d+)\.csv$")


def next_trial_path(folder: str | Path) -> Path:
    """``folder/NNN.csv``, one more than the highest numbered trial there (``001.csv`` first).

    The folder is created if needed; names sort in recording order.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    numbers = [int(m.group(1)) for p in folder.iterdir() if (m := _NUMBERED.match(p.name))]
    return folder / f"{max(numbers, default=0) + 1:03d}.csv"


def write_trial(path: str | Path, times: ArrayLike, columns: Mapping[str, ArrayLike]) -> Path:
    """Write one trial: a header of :data:`RECORDED_COLUMNS`, then one row per time.

    Parameters
    ----------
    path : str or Path
        The new file (an existing one is never replaced).
    times : array_like, shape (T,)
        Sample times (s), strictly increasing; written as the ``t`` column.
    columns : mapping of str to array_like, each shape (T,) or a scalar
        Values of other columns of :data:`RECORDED_COLUMNS` (m, rad or raw, as
        in the recordings); a scalar fills its column. NaN and the columns not
        given are written as empty cells.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        Unknown column names, a column of the wrong length, times not strictly
        increasing, or ``path`` already exists.
    """
    times = check_times(times, "times")
    unknown = sorted(set(columns) - set(RECORDED_COLUMNS[1:]))
    if unknown:
        raise ValueError(f"columns: expected names among the recorded layout's "
                         f"(sandbox.data.writer.RECORDED_COLUMNS, without 't'), got {unknown}")
    table = np.full((times.size, len(RECORDED_COLUMNS)), np.nan)
    table[:, 0] = times
    for name, values in columns.items():
        values = np.asarray(values, dtype=float)
        if values.ndim > 1 or (values.ndim == 1 and values.size != times.size):
            raise ValueError(f"columns[{name!r}]: expected a scalar or shape ({times.size},), "
                             f"got shape {values.shape}")
        table[:, RECORDED_COLUMNS.index(name)] = values
    lines = [",".join(RECORDED_COLUMNS)]
    lines += [",".join(_cell(v) for v in row) for row in table]
    path = Path(path)
    try:
        with path.open("x", encoding="utf-8", newline="") as file:
            file.write("\n".join(lines) + "\n")
    except FileExistsError:
        raise ValueError(f"path: expected a new file, got existing {str(path)!r}") from None
    return path


def _cell(value: float) -> str:
    """Six decimals (1 um, 1 urad, 1 us); empty for NaN."""
    return f"{value:.6f}" if np.isfinite(value) else ""

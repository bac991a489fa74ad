"""Recorded handovers in the per-trial CSV layout ``<root>/<task>/<trial>.csv``.

One file per demonstration, one row per sample, a header row naming the
columns (see ``data/README.md`` of the shared recordings). The user chooses the
time, human and robot columns; the defaults are the paper's: the human left
hand ``human_left_hand_x/y/z`` (m) and Baxter's seven left-arm joints (rad).

What the loader does with a trial (everything it does is counted in
``demo.meta["report"]``, see :func:`load_trial`):

1. Rows without a time or with a missing robot value are dropped, rows whose
   time goes backwards are dropped. Missing human values stay NaN.
2. Rows that share their time stamp with the previous row (about 40 % of the
   recorded rows) are collapsed to the last row of each time stamp, so times
   are strictly increasing. The first and last time stamps are kept: the
   ground-truth duration is the recorded span.
3. Human samples are classified (:func:`sandbox.data.glitches.find_glitches`): (0, 0, 0) rows
   (tracker lost the person), stale rows (a frame received before, sent again:
   the tracker runs at about 30 Hz, rows at about 100 Hz), frozen stretches (no
   new frame for longer than ``freeze_s``), jumps between consecutive frames.
4. ``preprocess`` decides what the human array holds:

   ``"none"``
       the recorded values at the kept rows, untouched (stale and zero rows included).
   ``"causal"``
       the output of the gated Kalman filter (:mod:`sandbox.data.filtering`)
       at rows where a new frame was accepted, NaN elsewhere (stale, zero,
       missing and gated-out rows are marked, not invented). Each value only
       depends on earlier rows: use it for test streams.
   ``"smooth"`` (default)
       first, frames farther than ``excursion_m`` from the running median of the
       frames within +/- 0.25 s are set aside (the tracker's occlusion jumps,
       :func:`sandbox.data.glitches.excursions`; this looks at later frames);
       then the gated filter and the RTS smoother run on the remaining frames,
       and the smoothed track is given at every row that lies in a gap of at
       most ``max_fill_s`` (default 1 s) between accepted frames or at most
       0.1 s after the last one, NaN elsewhere. For training demos: a long
       gap left NaN makes a basis-function fit of the demo ill-posed there
       (weights of metres), a bridged one does not.

``demo.meta["human_measured"]`` (bool, shape (T,)) marks the rows that carry a
new, accepted tracker frame.
"""

from __future__ import annotations

import csv
import difflib
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.core.validation import FloatArray, check_choice, check_positive
from sandbox.data.demonstration import Demonstration
from sandbox.data.filtering import FilterConfig, filter_track, smooth_track
from sandbox.data.glitches import excursions, find_glitches

HUMAN_COLUMNS = ("human_left_hand_x", "human_left_hand_y", "human_left_hand_z")
ROBOT_COLUMNS = ("left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2")
TIME_COLUMN = "t"
PREPROCESS = ("none", "causal", "smooth")
#: Width (s) of the running-median window used to find excursions ("smooth").
EXCURSION_WINDOW_S = 0.5
#: "smooth" extrapolates past the last accepted frame by at most this (s).
MAX_EXTRAPOLATE_S = 0.1


class TrialError(ValueError):
    """A trial file that cannot be used; the message says why."""


class SkippedTrialWarning(UserWarning):
    """Issued for each trial :func:`load_recorded` skips."""


@dataclass(frozen=True)
class Columns:
    """Which CSV columns to read.

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
        for name in ("human", "robot"):
            cols = tuple(getattr(self, name))
            if not cols or not all(isinstance(c, str) and c for c in cols):
                raise ValueError(f"{name} columns: expected non-empty names, got {cols!r}")
            object.__setattr__(self, name, cols)
        wanted = (self.time, *self.human, *self.robot)
        twice = sorted({c for c in wanted if wanted.count(c) > 1})
        if twice:
            raise ValueError(f"columns: each column may be used once, got {twice} more than once")

    @property
    def all(self) -> tuple[str, ...]:
        return (self.time, *self.human, *self.robot)


def _clean_name(name: str) -> str:
    return name.replace("\ufeff", "").strip().strip("\"'").strip()


def _column_index(header: list[str], columns: Columns) -> list[int]:
    names = [_clean_name(h) for h in header]
    index = []
    for col in columns.all:
        hits = [i for i, n in enumerate(names) if n == col]
        if len(hits) > 1:
            raise TrialError(f"column {col!r} appears {len(hits)} times (columns {hits})")
        if not hits:
            lower = {n.lower(): n for n in names}
            close = [lower[c] for c in difflib.get_close_matches(col.lower(), list(lower), n=2,
                                                                 cutoff=0.75)]
            hint = f" (did you mean {' or '.join(map(repr, close))}?)" if close else ""
            raise TrialError(f"missing column {col!r}{hint}")
        index.append(hits[0])
    return index


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


def read_trial_table(path: str | Path, columns: Columns = Columns()) -> tuple[FloatArray, dict]:
    """Read the chosen columns of one trial file as floats.

    Returns
    -------
    table : ndarray, shape (n_rows, 1 + P + Q)
        Time, human and robot columns in that order; NaN for empty cells.
    notes : dict
        ``{"truncated_last_row": bool}``.

    Raises
    ------
    TrialError
        Empty file, no data rows, missing or duplicated columns, a row with the
        wrong number of fields (other than a truncated last row), non-numeric text.
    """
    path = Path(path)
    if not path.is_file():
        raise TrialError(f"no such file: {path}")
    with path.open(newline="", encoding="utf-8", errors="replace") as fh:
        rows = [r for r in csv.reader(fh) if r and any(c.strip() for c in r)]
    if not rows:
        raise TrialError("empty file")
    header, body = rows[0], rows[1:]
    index = _column_index(header, columns)
    if not body:
        raise TrialError("no data rows (only a header)")
    truncated = len(body[-1]) < len(header)
    if truncated:
        body = body[:-1]
    for n, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise TrialError(f"row {n} has {len(row)} fields, the header has {len(header)}")
    cells = [[row[i] for i in index] for row in body]
    table = _to_float(cells, columns.all, 2) if cells else np.empty((0, len(index)))
    return table, {"truncated_last_row": truncated}


def _usable_rows(table: FloatArray, n_human: int) -> tuple[np.ndarray, dict[str, int]]:
    """Mask of rows to keep and the number of rows dropped per reason."""
    t, robot = table[:, 0], table[:, 1 + n_human :]
    no_time = np.isnan(t)
    no_robot = ~no_time & np.isnan(robot).any(axis=1)
    keep = ~no_time & ~no_robot
    running = np.maximum.accumulate(np.where(keep, t, -np.inf))
    backwards = keep & (t < np.r_[-np.inf, running[:-1]])
    keep &= ~backwards
    dropped = {"time missing": int(no_time.sum()), "robot value missing": int(no_robot.sum()),
               "time going backwards": int(backwards.sum())}
    return keep, {k: v for k, v in dropped.items() if v}


def _human_track(
    times: FloatArray, values: FloatArray, preprocess: str, config: Any, max_fill_s: float
) -> tuple[FloatArray, np.ndarray, dict[str, int]]:
    """Per-row human output, the rows whose frame was used, and filter counts."""
    run = filter_track(times, values, config)
    used = run.used
    counts = run.counts()
    stats = {"gate_rejected": counts["rejected"], "filter_resets": counts["reset"]}
    if preprocess == "causal":
        return run.filtered, used, stats
    smoothed = smooth_track(run)
    t_used = times[used]
    if t_used.size == 0:
        return smoothed, used, stats
    k = np.searchsorted(t_used, times, side="right")  # next used frame index
    prev = t_used[np.maximum(k - 1, 0)]
    inside = (k > 0) & (k < t_used.size)
    nxt = t_used[np.minimum(k, t_used.size - 1)]
    fill = inside & (nxt - prev <= max_fill_s)  # a gap bridged by the smoother
    fill |= (k == t_used.size) & (times - prev <= min(max_fill_s, MAX_EXTRAPOLATE_S))
    fill |= used
    return np.where(fill[:, None], smoothed, np.nan), used, stats


def preprocess_rows(
    times: FloatArray,
    human: FloatArray,
    preprocess: str,
    *,
    config: FilterConfig | None = None,
    freeze_s: float = 0.25,
    max_fill_s: float = 1.0,
    jump_m: float = 0.05,
    excursion_m: float = 0.04,
) -> tuple[FloatArray, np.ndarray, dict[str, int | float]]:
    """Classify and preprocess human rows, then keep one row per time stamp.

    Parameters
    ----------
    times : ndarray, shape (T,)
        Row times (s), non-decreasing; rows sharing a time stamp are collapsed
        to the last of them.
    human : ndarray, shape (T, P)
        Human values (m), NaN where missing.
    preprocess, config, freeze_s, max_fill_s, jump_m, excursion_m
        As in :func:`load_trial`.

    Returns
    -------
    human : ndarray, shape (T', P)
        One row per distinct time stamp (see the module docstring for each mode).
    measured : ndarray of bool, shape (T',)
        Time stamps at which a new tracker frame was received (and, when
        filtering, accepted by the gate).
    counts : dict
        Glitch and filter counts (JSON-ready).
    """
    _check_options(preprocess, config=config, freeze_s=freeze_s, max_fill_s=max_fill_s,
                   jump_m=jump_m, excursion_m=excursion_m)
    glitches = find_glitches(times, human, freeze_s=freeze_s, jump_m=jump_m)
    measurement = np.where(glitches.fresh[:, None], human, np.nan)
    away = np.zeros(times.size, dtype=bool)
    if excursion_m > 0:
        away = excursions(times, measurement, window_s=EXCURSION_WINDOW_S, threshold_m=excursion_m)
    stats = {"excursions": int(away.sum()), "gate_rejected": 0, "filter_resets": 0}
    if preprocess == "none":
        out_rows, used = human, glitches.fresh
    else:
        if preprocess == "smooth":
            measurement[away] = np.nan  # set aside: offline only (the median sees ahead)
        out_rows, used, counts = _human_track(times, measurement, preprocess, config, max_fill_s)
        stats.update(counts)
    last = np.flatnonzero(np.r_[np.diff(times) > 0, True])
    group = np.cumsum(np.r_[True, np.diff(times) > 0]) - 1
    measured = np.bincount(group, weights=used.astype(float), minlength=last.size) > 0
    out = out_rows[last]
    if preprocess == "causal":
        out = np.where(measured[:, None], out, np.nan)
    unfilled = int(np.isnan(out).any(axis=1).sum())
    return out, measured, {**glitches.counts(), **stats, "unfilled_samples": unfilled}


def preprocess_demonstration(
    demo: Demonstration, preprocess: str = "smooth", **options: Any
) -> Demonstration:
    """Apply the loader's human preprocessing to any demonstration (e.g. synthetic).

    ``options`` are those of :func:`load_trial` (``config``, ``freeze_s``,
    ``max_fill_s``, ``jump_m``, ``excursion_m``). The robot and the times are unchanged;
    ``meta["report"]`` gets the glitch and filter counts and
    ``meta["human_measured"]`` the rows with an accepted new sample.
    ``preprocess="none"`` returns ``demo`` itself.
    """
    check_choice(preprocess, "preprocess", PREPROCESS)
    if preprocess == "none":
        return demo
    human, measured, counts = preprocess_rows(demo.times, demo.human, preprocess, **options)
    measured.setflags(write=False)
    report = {**dict(demo.meta.get("report", {})), "preprocess": preprocess, **counts}
    meta = {**demo.meta, "report": report, "human_measured": measured}
    return demo.replace(human=human, meta=meta)


def load_trial(
    path: str | Path,
    *,
    task: str | None = None,
    columns: Columns = Columns(),
    preprocess: str = "smooth",
    config: FilterConfig | None = None,
    freeze_s: float = 0.25,
    max_fill_s: float = 1.0,
    jump_m: float = 0.05,
    excursion_m: float = 0.04,
) -> Demonstration:
    """Load one trial file as a :class:`Demonstration`.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    task : str, optional
        Task label; defaults to the name of the file's folder.
    columns : Columns
        Time, human and robot columns to read.
    preprocess : {"none", "causal", "smooth"}
        What to do with the human samples (see the module docstring).
    config : FilterConfig, optional
        Filter settings for "causal" and "smooth".
    freeze_s : float
        A stretch without a new tracker frame longer than this (s) is a frozen skeleton.
    max_fill_s : float
        "smooth" bridges gaps between accepted frames up to this long (s);
        longer ones stay NaN. ``meta["human_measured"]`` tells bridged rows apart.
    jump_m : float
        A step between consecutive tracker frames of at least this (m) counts as a jump.
    excursion_m : float
        "smooth" sets aside frames farther than this (m) from their running
        median (0 disables). On the recorded handovers 4 cm sets aside 4.9 % of
        the frames; on synthetic tracks with known truth it finds 67 % of the
        frames more than 3 cm off, with 96 % precision.

    Returns
    -------
    Demonstration
        ``source`` is the file path; ``meta["report"]`` is a JSON-ready dict of
        what was found and done; ``meta["human_measured"]`` marks the rows
        carrying an accepted new frame.

    Raises
    ------
    ValueError
        (:class:`TrialError`) the file cannot be used; the message says why.
    """
    options = {"config": config, "freeze_s": freeze_s, "max_fill_s": max_fill_s,
               "jump_m": jump_m, "excursion_m": excursion_m}
    _check_options(preprocess, **options)
    path = Path(path)
    try:
        return _load_trial(path, task or path.parent.name, columns, preprocess, options)
    except TrialError as error:
        raise TrialError(f"{path}: {error}") from None


def _check_options(
    preprocess: str,
    *,
    config: Any,
    freeze_s: float,
    max_fill_s: float,
    jump_m: float,
    excursion_m: float,
) -> None:
    check_choice(preprocess, "preprocess", PREPROCESS)
    check_positive(freeze_s, "freeze_s")
    check_positive(max_fill_s, "max_fill_s", allow_zero=True)
    check_positive(jump_m, "jump_m")
    check_positive(excursion_m, "excursion_m", allow_zero=True)
    if config is not None and not isinstance(config, FilterConfig):
        raise ValueError(f"config: expected a FilterConfig, got {type(config).__name__}")


def _load_trial(
    path: Path, task: str, columns: Columns, preprocess: str, options: dict[str, Any]
) -> Demonstration:
    table, notes = read_trial_table(path, columns)
    n_rows = table.shape[0]
    p = len(columns.human)
    keep, dropped = _usable_rows(table, p)
    if notes["truncated_last_row"]:
        dropped["truncated last row"] = 1
    table = table[keep]
    times, human, robot = table[:, 0], table[:, 1 : 1 + p], table[:, 1 + p :]
    last = np.flatnonzero(np.r_[np.diff(times) > 0, True]) if times.size else times.astype(int)
    if last.size < 2:
        why = "; ".join(f"{v} dropped ({k})" for k, v in dropped.items())
        raise TrialError(
            f"only {last.size} usable time stamp(s) out of {n_rows} rows, need at least 2"
            + (f" ({why})" if why else "")
        )
    out, measured, counts = preprocess_rows(times, human, preprocess, **options)
    if counts["new_frames"] < 2:
        raise TrialError(
            f"fewer than 2 valid human samples ({counts['missing_rows']} rows missing, "
            f"{counts['zero_rows']} rows (0, 0, 0), {counts['stale_rows']} repeated)"
        )
    report = {
        "file": str(path), "task": task, "preprocess": preprocess, "rows": n_rows,
        "rows_dropped": dropped, "repeated_timestamps": int(times.size - last.size),
        "samples": int(last.size), "duration_s": float(times[-1] - times[0]), **counts,
    }
    measured.setflags(write=False)
    return Demonstration(
        times=times[last], human=out, robot=robot[last], task=task,
        human_names=columns.human, robot_names=columns.robot, source=str(path),
        meta={"report": report, "human_measured": measured},
    )


def find_trials(root: str | Path, tasks: Sequence[str] | None = None) -> list[tuple[str, Path]]:
    """List ``(task, file)`` of ``<root>/<task>/<trial>.csv``, sorted by task then file.

    Raises ``ValueError`` if ``root`` is not a folder in that layout or a requested
    task is not there (the message lists the tasks that are).
    """
    root = Path(root)
    if not root.is_dir():
        raise ValueError(f"data: expected a folder <root>/<task>/<trial>.csv, got {str(root)!r}")
    found = {d.name: sorted(d.glob("*.csv")) for d in sorted(root.iterdir()) if d.is_dir()}
    found = {k: v for k, v in found.items() if v}
    if not found:
        raise ValueError(f"data: no <task>/<trial>.csv files under {str(root)!r}")
    if tasks is not None:
        tasks = list(tasks)
        unknown = [t for t in tasks if t not in found]
        if unknown:
            raise ValueError(f"tasks: expected some of {sorted(found)}, got unknown {unknown}")
        found = {t: found[t] for t in dict.fromkeys(tasks)}
    return [(task, f) for task, files in found.items() for f in files]


def load_recorded(
    root: str | Path,
    *,
    tasks: Sequence[str] | None = None,
    columns: Columns = Columns(),
    preprocess: str = "smooth",
    config: FilterConfig | None = None,
    **options: float,
) -> tuple[list[Demonstration], list[tuple[str, str]]]:
    """Load every trial of ``<root>/<task>/<trial>.csv`` (optionally only ``tasks``).

    Parameters
    ----------
    root : str or Path
        The dataset folder.
    tasks : sequence of str, optional
        Tasks to load (folder names); default all.
    columns, preprocess, config, **options
        As in :func:`load_trial` (``freeze_s``, ``max_fill_s``, ``jump_m``,
        ``excursion_m``).

    Returns
    -------
    demos : list of Demonstration
        In task then file order.
    skipped : list of (str, str)
        ``(file, reason)`` of every trial that could not be used; each also
        raises a :class:`SkippedTrialWarning`.
    """
    check_choice(preprocess, "preprocess", PREPROCESS)
    demos, skipped = [], []
    for task, path in find_trials(root, tasks):
        try:
            demos.append(load_trial(path, task=task, columns=columns, preprocess=preprocess,
                                    config=config, **options))
        except TrialError as error:
            reason = str(error).removeprefix(f"{path}: ")
            skipped.append((str(path), reason))
            warnings.warn(f"skipped {path}: {reason}", SkippedTrialWarning, stacklevel=2)
    return demos, skipped

"""Reading a trial as its spec declares it: which files, which rows, in which units and frame.

:func:`find_trials` lists the trials of the built-in layout
``<root>/<task>/<trial>.csv``, :func:`find_spec_trials` those of a spec's
``files`` and ``labels`` (:mod:`sandbox.data.spec_layout`); :func:`read_spec_table` reads one
trial's columns (one CSV, or one per part of a trial folder, joined row by
row) with the time in seconds (the time column, or ``i / rate_hz``) and every
position in metres in the robot's base frame (``units``, ``frame``).
:func:`cut_rows` applies ``segment`` and ``resample_hz``
(:mod:`sandbox.data.segment`). :mod:`sandbox.data.recorded` does the rest.
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Iterable, Sequence
from functools import partial
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.limits import MAX_FILE_BYTES
from sandbox.data.segment import bounds, thin
from sandbox.data.spec import DataSpec
from sandbox.data.spec_layout import LENGTH_UNITS
from sandbox.data.trialfile import TrialError, read_columns
from sandbox.validation import FloatArray


def _points(values: FloatArray, scale: float, frame) -> FloatArray:
    """Columns (n, k) in metres and, with a frame, in the base frame (k a multiple of 3)."""
    out = values * scale
    if frame is not None:
        for j in range(0, out.shape[1], 3):
            out[:, j:j + 3] = frame.apply(out[:, j:j + 3])
    return out


def _part_file(folder: Path, pattern: str, part: str) -> Path:
    """The one file of a trial folder matching ``files.<part>``."""
    hits = sorted(p for p in folder.glob(pattern) if p.is_file())
    if len(hits) != 1:
        found = "no file" if not hits else f"{len(hits)} files"
        raise TrialError(f"{found} matching {pattern!r} (files.{part}) in {folder}")
    return hits[0]


def part_files(folder: Path, spec: DataSpec) -> list[Path] | None:
    """The files of a trial folder, one per part of the spec's ``files`` (in its order),
    or None if ``folder`` is no folder or a part matches no file or several (the loader
    refuses such a trial with its reason; the trial cache keys a trial by these files)."""
    if not folder.is_dir():
        return None
    out = []
    for pattern in spec.layout.files.values():
        hits = sorted(p for p in folder.glob(pattern) if p.is_file())
        if len(hits) != 1:
            return None
        out.append(hits[0])
    return out


def _part_fix(part: str, fix: Callable[[str], str], column: str) -> str:
    """What the message of a missing column of ``files.<part>`` adds."""
    return f" in files.{part}{fix(f'{part}.{column}')}"


def _read_names(path: Path, spec: DataSpec, names: list[str], fix) -> tuple[FloatArray, dict]:
    """The columns ``names`` of a trial (a file, or a folder of parts), rows joined."""
    files = spec.layout.files
    if not files:
        return read_columns(path, names, fix)
    if not path.is_dir():
        raise TrialError("expected a trial folder holding the spec's 'files'")
    parts: dict[str, list[str]] = {}
    for name in names:
        part, _, column = name.partition(".")
        if part not in files:
            raise TrialError(f"column {name!r} names no part of 'files' (expected part.column "
                             f"with part one of {list(files)})")
        parts.setdefault(part, []).append(column)
    tables, notes = {}, {"truncated_last_row": False}
    for part, columns in parts.items():
        file = _part_file(path, files[part], part)
        table, note = read_columns(file, list(dict.fromkeys(columns)),
                                   partial(_part_fix, part, fix))
        tables[part] = dict(zip(dict.fromkeys(columns), table.T, strict=True))
        notes["truncated_last_row"] |= note["truncated_last_row"]
    lengths = {p: next(iter(t.values())).size for p, t in tables.items()}
    n = min(lengths.values())
    notes["unequal_files"] = sum(lengths.values()) - n * len(lengths)
    out = np.column_stack([tables[name.partition(".")[0]][name.partition(".")[2]][:n]
                           for name in names]) if n else np.empty((0, len(names)))
    return out, notes


def read_spec_table(path: Path, spec: DataSpec, modalities: Sequence[Modality], fix
                    ) -> tuple[FloatArray, FloatArray, dict]:
    """One trial's columns as the spec declares them.

    Returns
    -------
    table : ndarray, shape (n, 1 + P + Q)
        Time (s; NaN where missing), the modalities' columns (positions in m,
        base frame) and the robot columns.
    extra : ndarray, shape (n, 3 + E)
        For ``segment``: its modality (m, base frame), then the columns its
        bounds name; shape (n, 0) without a segment.
    notes : dict
        ``truncated_last_row`` (bool) and ``unequal_files`` (rows cut to join
        the parts of a trial).
    """
    layout, segment = spec.layout, spec.layout.segment
    human = [c for m in modalities for c in m.dims]
    extra = [] if segment is None else [*spec.modalities[segment.modality].dims,
                                        *segment.columns]
    time = [] if layout.rate_hz is not None else [spec.time]
    names = [*time, *human, *spec.robot, *extra]
    raw, notes = _read_names(path, spec, names, fix)
    n = raw.shape[0]
    times = np.arange(n) / layout.rate_hz if layout.rate_hz is not None \
        else raw[:, 0] * spec.time_scale
    values = raw[:, len(time):]
    start, blocks = 0, []
    for m in modalities:
        cols = values[:, start:start + m.size]
        start += m.size
        blocks.append(_points(cols, layout.length_scale(m.name), layout.frame_of(m.name))
                      if m.kind == "position" else cols)
    robot = values[:, start:start + len(spec.robot)]
    if spec.robot_space == "task":        # a position: the spec's units and frame apply too
        robot = _task_points(robot, layout)
    rest = values[:, start + len(spec.robot):]
    if segment is not None:
        rest = rest.copy()
        rest[:, :3] = _points(rest[:, :3], layout.length_scale(segment.modality),
                              layout.frame_of(segment.modality))
    table = np.column_stack([times, *blocks, robot]) if n else np.empty((0, 1 + len(human)
                                                                          + len(spec.robot)))
    return table, rest, notes


def _task_points(robot: FloatArray, layout) -> FloatArray:
    """A task-space robot part (n, k) in metres and, with a global frame, the base frame."""
    if layout.frame is not None and robot.shape[1] % 3:
        raise TrialError(f"robot: a frame moves x, y, z columns; got {robot.shape[1]} "
                         f"task-space robot columns")
    return _points(robot, LENGTH_UNITS[layout.units], layout.frame)


def robot_points(robot: FloatArray, space: str = "joint") -> FloatArray:
    """Baxter's gripper tip (n, 3) m, base frame, for the robot columns (n, 7) rad; a
    task-space part of x, y, z (m, base frame) as it is."""
    if space == "task" and robot.shape[1] == 3:
        return robot
    if robot.shape[1] != 7:
        raise TrialError(f"segment.end: rule approach needs the robot part's position, the "
                         f"forward kinematics of Baxter's 7 joints; got {robot.shape[1]} robot "
                         f"columns")
    from sandbox.data.synthetic.robot import kinematics
    from sandbox.robot import TIP_LINK

    return kinematics().fk(robot, link=TIP_LINK)


def cut_rows(spec: DataSpec, table: FloatArray, extra: FloatArray, n_human: int
             ) -> tuple[FloatArray, dict]:
    """``segment`` and ``resample_hz`` applied to usable rows; times restart at 0 if cut.

    ``table`` (n, 1 + P + Q) and ``extra`` (n, 3 + E) as :func:`read_spec_table`
    returns them (rows already usable: times non-decreasing). Returns the kept
    rows of ``table`` and a report (``segment``: the bounds found, s;
    ``resampled_rows``: rows thinned out).
    """
    layout, segment = spec.layout, spec.layout.segment
    report: dict[str, Any] = {}
    if segment is not None and table.shape[0] > 1:
        robot = (robot_points(table[:, 1 + n_human:], spec.robot_space) if segment.needs_robot
                 else None)
        columns = dict(zip(segment.columns, extra[:, 3:].T, strict=True))
        try:
            first, last, found = bounds(segment, table[:, 0], extra[:, :3], robot, columns)
        except ValueError as error:
            raise TrialError(str(error)) from None
        table = table[first:last + 1].copy()
        table[:, 0] -= table[0, 0]
        if layout.rate_hz is not None:          # row i - first at exactly (i - first) / rate
            table[:, 0] = np.round(table[:, 0] * layout.rate_hz) / layout.rate_hz
        report["segment"] = found
    if layout.resample_hz is not None and table.shape[0] > 1:
        rows = thin(table[:, 0], layout.resample_hz)
        report["resampled_rows"] = int(table.shape[0] - rows.size)
        table = table[rows]
    return table, report


def _labels(root: Path, spec: DataSpec) -> dict[str, str]:
    """Trial name -> task, from the spec's label file."""
    labels = spec.layout.labels
    assert labels is not None
    path = root / labels.file
    if not path.is_file():
        raise ValueError(f"labels.file: expected a CSV file in the data folder, got no file "
                         f"{str(path)!r}")
    if path.stat().st_size > MAX_FILE_BYTES:
        raise ValueError(f"labels.file: expected at most {MAX_FILE_BYTES} bytes "
                         f"(sandbox.data.limits.MAX_FILE_BYTES), got {path.stat().st_size}")
    with path.open(newline="", encoding="utf-8", errors="replace") as fh:
        rows = csv.DictReader(fh)
        fields = [f.strip() for f in rows.fieldnames or []]
        for key in ("trial", "task"):
            if getattr(labels, key) not in fields:
                raise ValueError(f"labels.{key}: expected a column of {path.name} (one of "
                                 f"{fields}), got {getattr(labels, key)!r}")
        out = {}
        for row in rows:
            row = {k.strip(): (v or "").strip() for k, v in row.items() if k}
            if row.get(labels.trial) and row.get(labels.task):
                out[row[labels.trial].removesuffix(".csv")] = row[labels.task]
    return out


def find_spec_trials(root: Path, spec: DataSpec, tasks: list[str] | None
                     ) -> tuple[list[tuple[str, Path]], list[tuple[str, str]]]:
    """``(task, trial)`` of a set laid out as the spec says, and ``(trial, reason)`` left out.

    Without ``labels``: ``<root>/<task>/<trial>.csv``, or ``<root>/<task>/<trial>/`` with
    ``files``. With ``labels``: the trials directly under ``root``, each given its task by
    the label file; a trial it does not list, or one it lists that is not there, is left out
    with the reason. Raises ``ValueError`` (naming the tasks found) for an unknown task.
    """
    files = bool(spec.layout.files)
    if spec.layout.labels is None:
        found = {d.name: sorted(p for p in d.iterdir() if (p.is_dir() if files else
                                                          p.suffix == ".csv"))
                 for d in sorted(root.iterdir()) if d.is_dir()}
        trials, left_out = [(t, p) for t, ps in found.items() for p in ps], []
    else:
        labels = _labels(root, spec)
        entries = sorted(p for p in root.iterdir()
                         if (p.is_dir() if files else p.suffix == ".csv")
                         and p.name != Path(spec.layout.labels.file).name)
        names = {p.name.removesuffix(".csv"): p for p in entries}
        trials = sorted(((labels[n], p) for n, p in names.items() if n in labels),
                        key=lambda tp: (tp[0], tp[1].name))
        left_out = [(str(p), f"no task for {n!r} in {spec.layout.labels.file}")
                    for n, p in names.items() if n not in labels]
        left_out += [(str(root / n), f"{spec.layout.labels.file} lists {n!r}, not found")
                     for n in labels if n not in names]
    if not trials:
        raise ValueError(f"data: no trials under {str(root)!r} in the spec's layout")
    available = list(dict.fromkeys(t for t, _ in trials))
    if tasks is not None:
        unknown = [t for t in tasks if t not in available]
        if unknown:
            raise ValueError(f"tasks: expected some of {available}, got unknown {unknown}")
        trials = [tp for t in dict.fromkeys(tasks) for tp in trials if tp[0] == t]
    return trials, left_out


def find_trials(root: str | Path, tasks: Sequence[str] | None = None) -> list[tuple[str, Path]]:
    """List ``(task, file)`` of ``<root>/<task>/<trial>.csv``, sorted by task then file.

    Raises ``ValueError`` if ``root`` is not a folder in that layout or a requested
    task is not there (the message lists the tasks that are).
    """
    root = _folder(root)
    if tasks is not None:
        if isinstance(tasks, (str, bytes)) or not isinstance(tasks, Iterable):
            raise ValueError(f"tasks: expected a list of task names, got {tasks!r}")
        tasks = list(tasks)
        if not all(isinstance(t, str) for t in tasks):
            raise ValueError(f"tasks: expected a list of task names, got {tasks!r}")
    if not root.is_dir():
        raise ValueError(f"data: expected a folder <root>/<task>/<trial>.csv, got {str(root)!r}")
    found = {d.name: sorted(d.glob("*.csv")) for d in sorted(root.iterdir()) if d.is_dir()}
    found = {k: v for k, v in found.items() if v}
    if not found:
        raise ValueError(f"data: no <task>/<trial>.csv files under {str(root)!r}")
    if tasks is not None:
        unknown = [t for t in tasks if t not in found]
        if unknown:
            raise ValueError(f"tasks: expected some of {sorted(found)}, got unknown {unknown}")
        found = {t: found[t] for t in dict.fromkeys(tasks)}
    return [(task, f) for task, files in found.items() for f in files]


def layout_trials(root, tasks, spec: DataSpec
                  ) -> tuple[list[tuple[str, Path]], list[tuple[str, str]]]:
    """The trials of ``root`` in the spec's layout, and those left out with the reason
    (:func:`find_trials` without ``files`` or ``labels``, :func:`find_spec_trials` with)."""
    if not spec.layout.files and spec.layout.labels is None:
        return find_trials(root, tasks), []
    root = _folder(root)
    if not root.is_dir():
        raise ValueError(f"data: expected a folder, got {str(root)!r}")
    if tasks is not None and (isinstance(tasks, (str, bytes)) or not isinstance(tasks, Iterable)):
        raise ValueError(f"tasks: expected a list of task names, got {tasks!r}")
    return find_spec_trials(root, spec, None if tasks is None else list(tasks))


def trial_list(root, tasks, spec: DataSpec | None = None) -> list[tuple[str, Path]]:
    """``(task, trial)`` of ``root`` in the spec's layout (:func:`find_trials` without
    ``files`` or ``labels``)."""
    return layout_trials(root, tasks, spec or DataSpec())[0]


def count_trials(root, tasks, spec: DataSpec | None = None) -> int | None:
    """How many trials ``root`` holds in the spec's layout (None if it cannot be listed)."""
    try:
        return len(trial_list(root, tasks, spec))
    except (ValueError, OSError):
        return None


def _folder(root: Any) -> Path:
    if not isinstance(root, (str, PathLike)):
        raise ValueError(f"data: expected a path, got {root!r}")
    return Path(root)

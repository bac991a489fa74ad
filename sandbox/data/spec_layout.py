"""How a recorded set is laid out on disk: the spec keys beyond the column names.

:class:`Layout` holds what :class:`~sandbox.data.spec.DataSpec` reads from
the keys ``time``/``rate_hz``, ``units``, ``frame``, ``files``, ``labels``,
``segment`` and ``resample_hz`` of a spec file, and per modality ``units``,
``frame`` and ``preprocess``. Every value is checked here; a mistake is a
one-line ``ValueError`` naming the key, what came and the valid choices.

``files``
    A mapping ``name: file`` of the files inside each trial folder (a trial is
    then a folder, one file per modality or body segment); ``file`` may be a
    pattern (``*_RHand_pose.csv``) that must match exactly one file of the
    folder. Every column is then written ``name.column``. The files of a trial
    are joined row by row (a longer file is cut to the shortest, and the rows
    cut are reported).
``labels``
    A CSV file (path relative to the data folder) mapping each trial (its file
    name, or its folder with ``files``; with or without ``.csv``) to its task,
    instead of one folder per task: ``labels: labels.csv`` (columns ``trial``
    and ``task``) or ``labels: {file: F, trial: COLUMN, task: COLUMN}``.
``units`` (and ``modalities.NAME.units``)
    ``m``, ``cm`` or ``mm``: the unit of the position columns; they are
    converted to metres as they are read. Signal modalities keep any units
    text (a label).
``preprocess`` (``modalities.NAME.preprocess``, signals only)
    ``envelope`` (default, what EMG needs: rectified, then low-pass filtered at
    ``signal_cutoff_hz``), ``lowpass`` (filtered, not rectified: keeps the sign
    of a force or a torque) or ``none`` (the values as they come).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from sandbox.data.segment import Segment, parse_segment
from sandbox.data.spec_frame import Frame, parse_frame
from sandbox.validation import check_positive

#: Units a position column may be in, and their length in metres.
LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
#: What a signal modality's ``preprocess`` may be (the first is the default).
SIGNAL_FILTERS = ("envelope", "lowpass", "none")
#: Highest ``rate_hz`` / ``resample_hz`` accepted (Hz).
MAX_LAYOUT_HZ = 10_000.0
_LABEL_KEYS = ("file", "trial", "task")


@dataclass(frozen=True)
class Labels:
    """A label file: which column names the trial and which its task.

    Parameters
    ----------
    file : str
        The CSV file, relative to the data folder.
    trial, task : str
        Its columns naming the trial (a folder or file name, ``.csv`` optional) and its task.
    """

    file: str
    trial: str = "trial"
    task: str = "task"


@dataclass(frozen=True)
class Layout:
    """The spec keys beyond the column names (see the module docstring).

    Parameters
    ----------
    rate_hz : float or None
        Sample rate (Hz) of files without a time column: row ``i`` is at ``i / rate_hz`` s.
    units : {"m", "cm", "mm"}
        Unit of the position columns (default m).
    frame : Frame or None
        Transform of every position modality to the robot base frame.
    files : mapping of str to str
        File name (or pattern) of each part of a trial folder; empty: one CSV per trial.
    labels : Labels or None
        The label file, instead of one folder per task.
    segment : Segment or None
        Where each recording is cut.
    resample_hz : float or None
        Thin the rows to at most this rate (Hz).
    modality_units, modality_frames, signal_filters : mapping
        Per modality name: its own units, frame, and a signal's preprocessing.
    """

    rate_hz: float | None = None
    units: str = "m"
    frame: Frame | None = None
    files: Mapping[str, str] = field(default_factory=dict)
    labels: Labels | None = None
    segment: Segment | None = None
    resample_hz: float | None = None
    modality_units: Mapping[str, str] = field(default_factory=dict)
    modality_frames: Mapping[str, Frame] = field(default_factory=dict)
    signal_filters: Mapping[str, str] = field(default_factory=dict)

    def length_scale(self, name: str) -> float:
        """Metres per unit of position modality ``name``'s columns."""
        return LENGTH_UNITS[self.modality_units.get(name, self.units)]

    def frame_of(self, name: str) -> Frame | None:
        """The frame of position modality ``name`` (its own, else the global one)."""
        return self.modality_frames.get(name, self.frame)

    def signal_filter(self, name: str) -> str:
        """Preprocessing of signal modality ``name`` (default ``envelope``)."""
        return self.signal_filters.get(name, SIGNAL_FILTERS[0])

    def to_dict(self) -> dict:
        """JSON-ready form of the keys that differ from the defaults."""
        out: dict[str, Any] = {"units": self.units}
        for key in ("rate_hz", "resample_hz"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        if self.frame is not None:
            out["frame"] = self.frame.to_dict()
        if self.files:
            out["files"] = dict(self.files)
        if self.labels is not None:
            out["labels"] = {"file": self.labels.file, "trial": self.labels.trial,
                             "task": self.labels.task}
        if self.segment is not None:
            out["segment"] = self.segment.to_dict()
        return out


def check_rate(value: Any, key: str) -> float:
    """A rate (Hz) in (0, :data:`MAX_LAYOUT_HZ`]."""
    return check_positive(value, f"{key} (Hz)", high=MAX_LAYOUT_HZ)


def check_units(value: Any, key: str) -> str:
    """``m``, ``cm`` or ``mm``; anything else is a ``ValueError`` naming ``key``."""
    if not isinstance(value, str) or value.strip() not in LENGTH_UNITS:
        raise ValueError(f"{key}: expected one of {list(LENGTH_UNITS)} (positions are converted "
                         f"to metres), got {value!r}")
    return value.strip()


def _text(value: Any, key: str, what: str) -> str:
    if not isinstance(value, str) or not value.strip() or not value.isprintable():
        raise ValueError(f"{key}: expected {what}, got {value!r}")
    return value.strip()


def parse_files(value: Any) -> dict[str, str]:
    """``files:``: a mapping of part names (no dots) to file names or patterns."""
    if not isinstance(value, Mapping) or not value:
        raise ValueError(f"files: expected a mapping name -> file name inside each trial folder "
                         f"(e.g. {{hand: giver_RHand_pose.csv}}), got {value!r}")
    out = {}
    for name, file in value.items():
        name = _text(name, "files", "part names that are printable text")
        if "." in name:
            raise ValueError(f"files: expected part names without dots (columns are written "
                             f"name.column), got {name!r}")
        file = _text(file, f"files.{name}", "a file name or pattern such as *_pose.csv")
        if "/" in file or "\\" in file or file.startswith(".."):
            raise ValueError(f"files.{name}: expected a file name inside the trial folder, "
                             f"got {file!r}")
        out[name] = file
    return out


def parse_labels(value: Any) -> Labels:
    """``labels:``: a file name, or ``{file, trial, task}``."""
    if isinstance(value, str):
        value = {"file": value}
    if not isinstance(value, Mapping):
        raise ValueError(f"labels: expected a CSV file name or {{file, trial, task}}, "
                         f"got {value!r}")
    unknown = sorted(set(value) - set(_LABEL_KEYS))
    if unknown:
        raise ValueError(f"labels: unknown keys {unknown}; expected some of {list(_LABEL_KEYS)}")
    if "file" not in value:
        raise ValueError("labels: 'file' is missing (the CSV mapping each trial to its task)")
    file = _text(value["file"], "labels.file", "a CSV file inside the data folder")
    if file.startswith("/") or ".." in file.split("/"):
        raise ValueError(f"labels.file: expected a path inside the data folder, got {file!r}")
    return Labels(file, *(_text(value.get(k, k), f"labels.{k}", "a column name")
                          for k in ("trial", "task")))


def parse_time(data: Mapping[str, Any]) -> tuple[str | None, str | None, float | None]:
    """The time column, its unit and ``rate_hz`` from the ``time``, ``time_unit`` and
    ``rate_hz`` keys (``time: NAME`` or ``time: {column, unit}``; ``rate_hz`` without a time
    column)."""
    time, unit = data.get("time"), data.get("time_unit")
    if isinstance(time, Mapping):
        unknown = sorted(set(time) - {"column", "unit"})
        if unknown:
            raise ValueError(f"time: unknown keys {unknown}; expected some of ['column', 'unit']")
        if unit is not None and "unit" in time:
            raise ValueError("time_unit: expected either time.unit or time_unit, got both")
        unit = time.get("unit", unit)
        if "column" not in time:
            raise ValueError("time.column: missing (or leave time out and give rate_hz)")
        time = time["column"]
    rate = data.get("rate_hz")
    if rate is not None:
        rate = check_rate(rate, "rate_hz")
        if time is not None:
            raise ValueError("rate_hz: expected either rate_hz (files without a time column) or "
                             "a time column, got both")
    return time, unit, rate


def parse_layout(data: Mapping[str, Any], modalities: Mapping[str, Any]) -> Layout:
    """A :class:`Layout` from a parsed spec file (``modalities``: its raw modality entries)."""
    units = check_units(data.get("units", "m"), "units")
    per_units, per_frames, filters = {}, {}, {}
    for name, entry in modalities.items():
        kind = entry.get("kind", "position")
        if kind == "position" and entry.get("units") not in (None, ""):
            own = check_units(entry["units"], f"modalities.{name}.units")
            if own != units:                     # kept only where it differs from the global
                per_units[name] = own
        if "frame" in entry:
            if kind != "position":
                raise ValueError(f"modalities.{name}.frame: only position modalities have a "
                                 f"frame, got kind {kind!r}")
            per_frames[name] = parse_frame(entry["frame"], f"modalities.{name}.frame")
        if "preprocess" in entry:
            if kind != "signal" or entry["preprocess"] not in SIGNAL_FILTERS:
                raise ValueError(f"modalities.{name}.preprocess: expected one of "
                                 f"{list(SIGNAL_FILTERS)} for a signal modality, got "
                                 f"{entry['preprocess']!r} (kind {kind!r})")
            filters[name] = entry["preprocess"]
    return Layout(
        rate_hz=parse_time(data)[2], units=units,
        frame=None if data.get("frame") is None else parse_frame(data["frame"]),
        files={} if data.get("files") is None else parse_files(data["files"]),
        labels=None if data.get("labels") is None else parse_labels(data["labels"]),
        segment=None if data.get("segment") is None else parse_segment(data["segment"]),
        resample_hz=None if data.get("resample_hz") is None
        else check_rate(data["resample_hz"], "resample_hz"),
        modality_units=per_units, modality_frames=per_frames, signal_filters=filters)


def check_columns(layout: Layout, columns: dict[str, tuple[str, ...]]) -> None:
    """With ``files``, every column named (``{key: names}``) must read ``part.column``."""
    if not layout.files:
        return
    for key, names in columns.items():
        for name in names:
            part = name.split(".", 1)[0]
            if "." not in name or part not in layout.files:
                raise ValueError(f"{key}: expected columns written part.column with part one "
                                 f"of {list(layout.files)} (the files key), got {name!r}")

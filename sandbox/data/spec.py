"""What the columns of a recorded set are: time, robot, and the observation modalities.

A :class:`DataSpec` names the time column, the robot columns and every
modality a set offers (:class:`~sandbox.core.modality.Modality`: columns, kind,
units); ``observe`` chooses which modalities a model sees. The built-in
modalities are those of the recorded Baxter handovers (the paper's lab):

======  ==============================================================  ========  =====
name    columns                                                         kind      units
======  ==============================================================  ========  =====
hand    ``human_left_hand_x/y/z``                                       position  m
arm     ``human_left_elbow_x/y/z``, ``human_left_shoulder_x/y/z``       position  m
emg     ``emg0`` ... ``emg7`` (Myo armband)                             signal    raw
======  ==============================================================  ========  =====

``hand`` is the default everywhere (the paper's setup). A user describes their
own layout once in a spec file, YAML or JSON (``--spec FILE`` on every
command)::

    time: {column: stamp, unit: ms}  # optional, default t in s (or: time: stamp, time_unit: ms)
    rate_hz: 120                     # instead of a time column: row i is at i / 120 s
    units: mm                        # m (default), cm or mm: positions converted to metres
    robot: [j1, j2, j3, j4, j5, j6, j7]   # optional, default left_s0 ... left_w2
    # or, with the space the robot part is in (default joint: Baxter's 7 arm joints, rad):
    # robot: {columns: [rx, ry, rz], space: task}   # task: positions (m) in the base frame
    observe: [wrist, grip]           # optional default choice, default [hand]
    modalities:                      # added to (or replacing) the built-ins
      wrist: {columns: [wx, wy, wz], kind: position, units: m}
      grip:  {columns: [f1, f2], kind: signal, preprocess: lowpass}
    frame: {translation: [0.9, 0.2, -0.1], yaw: 180, up: z}   # world -> robot base
    files: {giver: giver_RHand_pose.csv}   # one file per part in each trial folder
    labels: labels.csv               # trial -> task, instead of one folder per task
    segment: {start: {rule: onset, speed: 0.15}, end: {rule: approach, hold_s: 0.3}}
    resample_hz: 60                  # thin fast recordings

Every key is checked; a mistake is a ``ValueError`` naming the file, the key,
what came and what was expected. ``time_unit`` converts the time column to
seconds as it is read (``--time-unit`` on the commands does the same without a
spec). The keys after ``modalities`` are described in
:mod:`sandbox.data.spec_layout` (``files``, ``labels``, ``units``, a signal's
``preprocess``), :mod:`sandbox.data.spec_frame` (``frame``, also per modality)
and :mod:`sandbox.data.segment` (``segment``, ``resample_hz``). A position
modality's ``units`` is the unit of its columns; once loaded it is in metres
(``Modality.units == "m"``).
``robot.space`` says what the robot columns are: ``joint`` (default; joint
angles, rad, checked against Baxter's 7-joint arm by the commands) or ``task``
(a position in the robot's base frame, m, any size, e.g. the receiving hand's
x, y, z): a model fitted on it predicts that position directly, e_p is measured
on it without forward kinematics and e_q does not apply.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from os import PathLike
from pathlib import Path
from typing import Any

from sandbox.core.modality import Modality, check_modalities, select
from sandbox.data.spec_layout import Layout, check_columns, parse_layout, parse_time

TIME_COLUMN = "t"
ROBOT_COLUMNS = ("left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2")
#: The tracked left hand (the paper's observation).
HAND = Modality("hand", ("human_left_hand_x", "human_left_hand_y", "human_left_hand_z"),
                "position", "m")
#: The same side's tracked elbow and shoulder.
ARM = Modality("arm", tuple(f"human_left_{joint}_{axis}" for joint in ("elbow", "shoulder")
                            for axis in "xyz"), "position", "m")
#: The Myo armband's 8 EMG channels.
EMG = Modality("emg", tuple(f"emg{i}" for i in range(8)), "signal", "raw")
#: The built-in modalities, by name.
BUILT_IN: dict[str, Modality] = {m.name: m for m in (HAND, ARM, EMG)}
_KEYS = {"time", "time_unit", "robot", "observe", "modalities", "rate_hz", "units", "frame",
         "files", "labels", "segment", "resample_hz"}
#: Spaces a robot part may be in (``robot: {columns, space}``).
ROBOT_SPACES = ("joint", "task")
_ROBOT_KEYS = {"columns", "space"}
#: Units a time column may be in, and their length in seconds.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}
_MODALITY_KEYS = {"columns", "kind", "units", "frame", "preprocess"}


@dataclass(frozen=True)
class DataSpec:
    """The columns of a recorded set and the modalities it offers.

    Parameters
    ----------
    time : str
        Time column.
    robot : sequence of str
        Robot columns (rad), e.g. Baxter's seven left-arm joints.
    modalities : mapping of str to Modality
        Every modality the set offers, by name (default: the built-ins).
    observe : sequence of str
        The modalities observed when a command or function is not told
        otherwise (default ``("hand",)``).
    time_unit : {"s", "ms", "us", "ns"}
        Unit of the time column (default seconds); the loaders convert it to
        seconds (:attr:`time_scale`).
    layout : Layout
        Everything else a spec file declares (:mod:`sandbox.data.spec_layout`):
        ``rate_hz``, units, frames, files, labels, segmentation, resampling.
    robot_space : {"joint", "task"}
        What the robot columns are: joint angles (rad, default) or a task-space
        position (m) in the robot's base frame.
    """

    time: str = TIME_COLUMN
    robot: tuple[str, ...] = ROBOT_COLUMNS
    modalities: Mapping[str, Modality] = field(default_factory=lambda: dict(BUILT_IN))
    observe: tuple[str, ...] = ("hand",)
    time_unit: str = "s"
    layout: Layout = field(default_factory=Layout)
    robot_space: str = "joint"

    def __post_init__(self) -> None:
        if not isinstance(self.time, str) or not self.time:
            raise ValueError(f"time: expected a column name, got {self.time!r}")
        if not isinstance(self.time_unit, str) or self.time_unit not in TIME_UNITS:
            raise ValueError(f"time_unit: expected one of {list(TIME_UNITS)}, "
                             f"got {self.time_unit!r}")
        if not isinstance(self.robot_space, str) or self.robot_space not in ROBOT_SPACES:
            raise ValueError(f"robot.space: expected one of {list(ROBOT_SPACES)}, "
                             f"got {self.robot_space!r}")
        robot = _names(self.robot, "robot")
        repeated = sorted({c for c in robot if robot.count(c) > 1})
        if repeated:
            raise ValueError(f"robot: expected distinct column names, got {repeated} more than "
                             f"once")
        if self.time.strip() in robot:
            raise ValueError(f"time: expected a column other than the robot columns, got "
                             f"{self.time!r}")
        if not isinstance(self.modalities, Mapping):
            raise ValueError(f"modalities: expected a mapping name -> Modality, "
                             f"got {type(self.modalities).__name__}")
        mods = dict(self.modalities)
        for name, m in mods.items():
            if not isinstance(m, Modality) or m.name != name:
                raise ValueError(f"modalities: expected {name!r} to map to Modality {name!r}, "
                                 f"got {m!r}")
        observe = tuple(m.name for m in select(mods.values(), _choice(self.observe), "observe"))
        object.__setattr__(self, "robot", robot)
        object.__setattr__(self, "modalities", mods)
        object.__setattr__(self, "observe", observe)
        self._check_layout()

    def _check_layout(self) -> None:
        """The layout's keys against the columns and modalities."""
        if not isinstance(self.layout, Layout):
            raise ValueError(f"layout: expected a Layout, got {type(self.layout).__name__}")
        mods, segment = self.modalities, self.layout.segment
        columns = {"robot": self.robot, **{f"modalities.{n}.columns": m.dims
                                           for n, m in mods.items() if BUILT_IN.get(n) != m}}
        if self.layout.rate_hz is None:
            columns["time"] = (self.time,)
        if segment is not None:
            hand = mods.get(segment.modality)
            if hand is None or hand.kind != "position" or hand.size != 3:
                points = sorted(n for n, m in mods.items() if m.kind == "position" and m.size == 3)
                raise ValueError(f"segment.modality: expected a position modality of 3 columns "
                                 f"(x, y, z), one of {points}, got {segment.modality!r}")
            columns["segment"] = segment.columns
        check_columns(self.layout, columns)
        for name in self.layout.modality_frames:
            if mods[name].size % 3:
                raise ValueError(f"modalities.{name}.frame: expected columns in x, y, z "
                                 f"triples, got {mods[name].size} columns")

    @property
    def time_scale(self) -> float:
        """Seconds per unit of the time column (1e-3 for ``time_unit="ms"``)."""
        return TIME_UNITS[self.time_unit]

    def observed(self, observe: Sequence[str] | str | None = None) -> tuple[Modality, ...]:
        """The modalities named by ``observe`` (default :attr:`observe`), in that order.

        Their columns may not be used twice, nor be the time or a robot column.
        """
        mods = select(self.modalities.values(),
                      self.observe if observe is None else _choice(observe), "observe")
        check_modalities(mods)
        time = () if self.layout.rate_hz is not None else (self.time,)
        clash = sorted({c for m in mods for c in m.dims} & {*time, *self.robot})
        if clash:
            raise ValueError(f"observe: columns {clash} are also the time or robot columns")
        return mods

    def with_columns(self, *, human: Sequence[str] | None = None,
                     robot: Sequence[str] | None = None, time: str | None = None,
                     time_unit: str | None = None) -> DataSpec:
        """A copy with other columns: ``human`` replaces the hand's columns (position, m);
        ``time_unit`` the time column's unit."""
        spec = self if time_unit is None else replace(self, time_unit=time_unit)
        if human is not None:
            hand = Modality("hand", _names(human, "human columns"), "position", "m")
            spec = replace(spec, modalities={**spec.modalities, "hand": hand})
        if robot is not None:
            spec = replace(spec, robot=_names(robot, "robot columns"))
        if time is not None:
            spec = replace(spec, time=time)
        return spec

    @classmethod
    def load(cls, path: str | Path) -> DataSpec:
        """Read a spec file (YAML or JSON, see the module docstring)."""
        if not isinstance(path, (str, PathLike)):
            raise ValueError(f"--spec: expected the path of a YAML or JSON file, got {path!r}")
        from sandbox.validation import is_file

        path = Path(path)
        if not is_file(path):
            raise ValueError(f"--spec: expected an existing YAML or JSON file, got {str(path)!r}")
        from sandbox.validation import parse_input, read_input_text

        data = parse_input(read_input_text(path, "spec"), path, "spec",
                           as_json=path.suffix.lower() == ".json")
        try:
            return cls.from_dict(data)
        except ValueError as error:
            raise ValueError(f"spec {path}: {error}") from None

    @classmethod
    def from_dict(cls, data: Any) -> DataSpec:
        """Build from a parsed spec file (built-in modalities stay available)."""
        if not isinstance(data, Mapping):
            raise ValueError(f"expected a mapping with keys {sorted(_KEYS)}, "
                             f"got {_kind(data)}")
        unknown = sorted(set(data) - _KEYS)
        if unknown:
            raise ValueError(f"unknown keys {unknown}; expected some of {sorted(_KEYS)}")
        mods = dict(BUILT_IN)
        given = data.get("modalities") or {}
        if not isinstance(given, Mapping):
            raise ValueError(f"modalities: expected a mapping name -> {{columns, kind, units}}, "
                             f"got {_kind(given)}")
        for name, entry in given.items():
            if not isinstance(name, str) or not name.strip() or not name.isprintable():
                raise ValueError(f"modalities: expected names that are printable text, "
                                 f"got {name!r}")
            mods[name] = _modality(name, entry)
        observe = data.get("observe", ("hand",))
        if isinstance(observe, str):
            observe = [n.strip() for n in observe.split(",") if n.strip()]
        time, unit, _ = parse_time(data)
        layout = parse_layout(data, {n: e for n, e in given.items()})
        robot, space = _robot(data.get("robot", ROBOT_COLUMNS))
        return cls(time=TIME_COLUMN if time is None else time,
                   robot=robot, modalities=mods,
                   observe=tuple(_names(observe, "observe")),
                   time_unit="s" if unit is None else unit, layout=layout, robot_space=space)

    def to_dict(self) -> dict:
        """JSON-ready form (inverse of :meth:`from_dict`)."""
        layout = self.layout
        robot: Any = list(self.robot)
        if self.robot_space != "joint":
            robot = {"columns": robot, "space": self.robot_space}
        out = {"robot": robot, "observe": list(self.observe),
               "modalities": {n: _entry(m, layout) for n, m in self.modalities.items()},
               **layout.to_dict()}
        if layout.rate_hz is None:
            out["time"] = {"column": self.time, "unit": self.time_unit}
        return out


def _entry(m: Modality, layout: Layout) -> dict:
    """A modality's spec entry (position units: those of its columns, see the layout)."""
    out: dict[str, Any] = {"columns": list(m.dims), "kind": m.kind, "units": m.units}
    if m.kind == "position":
        out["units"] = layout.modality_units.get(m.name, layout.units)
        if m.name in layout.modality_frames:
            out["frame"] = layout.modality_frames[m.name].to_dict()
    elif m.name in layout.signal_filters:
        out["preprocess"] = layout.signal_filters[m.name]
    return out


def _kind(value: Any) -> str:
    """What a parsed value is, in a user's words (``nothing`` for an empty file or key)."""
    if value is None:
        return "nothing (an empty file or key)"
    words = {bool: "true/false", int: "a number", float: "a number", str: "text",
             list: "a list", dict: "a mapping"}
    return words.get(type(value), type(value).__name__)


def _choice(observe: Any) -> Sequence[str] | str:
    """``observe`` as given after checking it is ``"a,b"`` or a list of names."""
    return observe if isinstance(observe, str) else _names(observe, "observe")


def _names(values: Any, what: str) -> tuple[str, ...]:
    if isinstance(values, str) or not isinstance(values, Sequence):
        raise ValueError(f"{what}: expected a list of names, got {values!r}")
    names = tuple(values)
    if not names or not all(isinstance(v, str) and v.strip() for v in names):
        raise ValueError(f"{what}: expected non-empty names, got {list(names)!r}")
    return tuple(v.strip() for v in names)


def _robot(entry: Any) -> tuple[Any, str]:
    """``robot:`` as given: a list of columns (joint space), or ``{columns, space}``."""
    if not isinstance(entry, Mapping):
        return entry, "joint"
    unknown = sorted(map(str, set(entry) - _ROBOT_KEYS))
    if unknown:
        raise ValueError(f"robot: unknown keys {unknown}; expected some of {sorted(_ROBOT_KEYS)}")
    if "columns" not in entry:
        raise ValueError("robot: 'columns' is missing")
    return entry["columns"], entry.get("space", "joint")


def _modality(name: str, entry: Any) -> Modality:
    if not isinstance(entry, Mapping):
        raise ValueError(f"modalities.{name}: expected a mapping with 'columns' and 'kind', "
                         f"got {entry!r}")
    unknown = sorted(set(entry) - _MODALITY_KEYS)
    if unknown:
        raise ValueError(f"modalities.{name}: unknown keys {unknown}; expected some of "
                         f"{sorted(_MODALITY_KEYS)}")
    if "columns" not in entry:
        raise ValueError(f"modalities.{name}: 'columns' is missing")
    units = entry.get("units", "") or ""
    if not isinstance(units, str):
        raise ValueError(f"modalities.{name}.units: expected text such as 'm', got {units!r}")
    if entry.get("kind", "position") == "position":
        units = "m"                   # converted to metres as read (Layout.length_scale)
    try:
        return Modality(name, _names(entry["columns"], f"modalities.{name}.columns"),
                        entry.get("kind", "position"), units)
    except ValueError as error:
        raise ValueError(f"modalities.{name}: {error}") from None


def resolve(spec: str | Path | DataSpec | None = None, *, human_columns=None,
            robot_columns=None, time_unit: str | None = None) -> DataSpec:
    """The spec a command uses: ``--spec FILE`` (or the default), then ``--human-columns``,
    ``--robot-columns`` and ``--time-unit`` on top."""
    if isinstance(spec, DataSpec):
        base = spec
    else:
        base = DataSpec() if spec is None else DataSpec.load(spec)
    return base.with_columns(human=human_columns, robot=robot_columns, time_unit=time_unit)

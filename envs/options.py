"""``reset(options=...)`` of the handover environments, validated with clear errors."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sandbox import urdf
from sandbox.envs.human import HumanMotion
from sandbox.envs.sources import family_tasks

#: Keys accepted in ``options``.
OPTION_KEYS = ("task", "object", "source", "trial", "speed", "switch_to", "switch_phase",
               "motion", "grasp_offset", "session")
#: Sources that are not a folder: the generator, the keyboard teleop.
NAMED_SOURCES = ("synthetic", "teleop")
#: Largest grasp offset (m) from the tracked hand (the meeting geometry's own bound).
MAX_GRASP_OFFSET = 0.3
#: Accepted range of the human speed factor.
SPEED_RANGE = (0.25, 4.0)


@dataclass(frozen=True)
class EpisodeOptions:
    """One episode's scenario.

    Attributes
    ----------
    task : str or None
        Task (None: drawn with the environment's ``np_random``).
    object : str or None
        Object (None: the task's, see :data:`sandbox.envs.task.TASK_OBJECTS`).
    source : str
        ``"synthetic"``, ``"teleop"`` (a :class:`~sandbox.envs.teleop.TeleopMotion`
        driven by a controller) or the folder of a recorded set.
    trial : int or str or None
        Recorded trial: index among the task's (or all) trials, or file name.
    speed : float
        The human moves ``speed`` times faster than the source motion.
    switch_to : str or None
        Synthetic intent switch: the task the human changes to.
    switch_phase : float
        When the switch happens (fraction of the motion).
    motion : HumanMotion or None
        A scripted hand motion to play instead of drawing one (e.g.
        :func:`~sandbox.envs.sources.waypoint_motion`).
    grasp_offset : ndarray, shape (3,), or dict of str to ndarray, or None
        Where the object's grasp point rides relative to the tracked hand (m): one
        offset, or one per task (the model's learned meeting geometry,
        :meth:`sandbox.data.geometry.MeetingGeometry.offsets`); None:
        :data:`~sandbox.envs.task.DEFAULT_HOLD_OFFSET`.
    session : int or None
        Synthetic source only: the recording session's seed (>= 0,
        :func:`sandbox.data.synthetic.session.draw_session`); None: today's data.
    """

    task: str | None = None
    object: str | None = None
    source: str = "synthetic"
    trial: int | str | None = None
    speed: float = 1.0
    switch_to: str | None = None
    switch_phase: float = 0.5
    motion: HumanMotion | None = None
    session: int | None = None
    grasp_offset: np.ndarray | dict[str, np.ndarray] | None = None

    def hold_offset(self, task: str) -> np.ndarray | None:
        """The grasp offset (3,) m for ``task`` (None: the environment's default).

        Raises
        ------
        ValueError
            If per-task offsets were given and ``task`` is not among them.
        """
        if not isinstance(self.grasp_offset, dict):
            return self.grasp_offset
        if task not in self.grasp_offset:
            raise ValueError(f"grasp_offset: expected an offset for the episode's task "
                             f"{task!r}, got tasks {sorted(self.grasp_offset)}")
        return self.grasp_offset[task]


def parse_options(options: Mapping[str, Any] | None, family: str) -> EpisodeOptions:
    """Check ``options`` of :meth:`reset` and return them as :class:`EpisodeOptions`.

    Parameters
    ----------
    options : mapping or None
        Keys from :data:`OPTION_KEYS`.
    family : str
        The environment's synthetic family (which tasks a synthetic source knows).

    Raises
    ------
    ValueError
        On an unknown key, a task or object that does not exist, a source that is
        neither ``"synthetic"``, ``"teleop"`` nor a folder, a bad speed, or an option
        that does not apply to the source (``trial`` for synthetic, ``switch_to`` for
        recorded or teleop; ``motion`` with ``source``, ``task``, ``trial`` or ``switch_to``;
        ``session`` not an integer >= 0, or with a source other than synthetic, a
        ``motion`` or ``switch_to``).
    """
    if options is None:
        return EpisodeOptions()
    if not isinstance(options, Mapping):
        raise ValueError(f"options: expected a dict, got {type(options).__name__}")
    unknown = sorted(set(options) - set(OPTION_KEYS))
    if unknown:
        raise ValueError(f"options: expected keys among {list(OPTION_KEYS)}, got {unknown}")
    motion = _motion(options)
    source = _source(options.get("source", "synthetic"))
    task = options.get("task")
    if task is not None and not isinstance(task, str):
        raise ValueError(f"task: expected a task name, got {task!r}")
    if source == "synthetic" and motion is None:
        tasks = family_tasks(family)
        for key in ("task", "switch_to"):
            if options.get(key) is not None and options[key] not in tasks:
                raise ValueError(f"{key}: expected one of {list(tasks)} ({family}), "
                                 f"got {options[key]!r}")
        if options.get("trial") is not None:
            raise ValueError("trial: only for a recorded source; synthetic motions are drawn "
                             "from the seed")
    elif options.get("switch_to") is not None:
        raise ValueError("switch_to: only for the synthetic source")
    elif source == "teleop" and options.get("trial") is not None:
        raise ValueError("trial: only for a recorded source, not for 'teleop'")
    obj = options.get("object")
    if obj is not None and obj not in urdf.OBJECTS:
        raise ValueError(f"object: expected one of {list(urdf.OBJECTS)}, got {obj!r}")
    return EpisodeOptions(task=task, object=obj, source=source, trial=options.get("trial"),
                          speed=_speed(options.get("speed", 1.0)),
                          switch_to=options.get("switch_to"),
                          switch_phase=_phase(options.get("switch_phase", 0.5)), motion=motion,
                          grasp_offset=_grasp_offset(options.get("grasp_offset")),
                          session=_session(options, source, motion))


def _motion(options: Mapping[str, Any]) -> HumanMotion | None:
    motion = options.get("motion")
    if motion is None:
        return None
    if not isinstance(motion, HumanMotion):
        raise ValueError(f"motion: expected a sandbox.envs.human.HumanMotion, "
                         f"got {type(motion).__name__}")
    clash = [k for k in ("source", "task", "trial", "switch_to") if options.get(k) is not None]
    if clash:
        raise ValueError(f"motion: a scripted motion replaces {clash}; expected none of them, "
                         f"got {clash}")
    return motion


def _session(options: Mapping[str, Any], source: str, motion: HumanMotion | None) -> int | None:
    """The ``session`` option: None, or an int >= 0 for a drawn synthetic motion."""
    from sandbox.validation import check_integer

    value = options.get("session")
    if value is None:
        return None
    session = check_integer(value, "session", 0)
    if source != "synthetic" or motion is not None or options.get("switch_to") is not None:
        raise ValueError(f"session: only for a synthetic motion without switch_to (a recorded, "
                         f"teleop or scripted motion has its own), got session={value!r}")
    return session


def _source(value: Any) -> str:
    if value in NAMED_SOURCES:
        return value
    if isinstance(value, (str, Path)) and Path(value).is_dir():
        return str(value)
    raise ValueError(f"source: expected 'synthetic', 'teleop' or the folder of a recorded set "
                     f"(<root>/<task>/<trial>.csv), got {value!r}")


def _speed(value: Any) -> float:
    lo, hi = SPEED_RANGE
    try:
        speed = float(value)
    except (TypeError, ValueError):
        speed = float("nan")
    if isinstance(value, bool) or not np.isfinite(speed) or not lo <= speed <= hi:
        raise ValueError(f"speed: expected a number in [{lo}, {hi}], got {value!r}")
    return speed


def _phase(value: Any) -> float:
    try:
        phase = float(value)
    except (TypeError, ValueError):
        phase = float("nan")
    if isinstance(value, bool) or not 0.0 < phase <= 1.0:
        raise ValueError(f"switch_phase: expected a number in (0, 1], got {value!r}")
    return phase


def _grasp_offset(value: Any) -> np.ndarray | dict[str, np.ndarray] | None:
    """None, an offset (3,) m, or task -> offset; each finite and within MAX_GRASP_OFFSET."""
    if value is None:
        return None
    if isinstance(value, Mapping):
        if not value or not all(isinstance(k, str) for k in value):
            raise ValueError(f"grasp_offset: expected task names -> offsets (3,) m, got "
                             f"{value!r:.80}")
        return {k: _offset(v, f"grasp_offset[{k!r}]") for k, v in value.items()}
    return _offset(value, "grasp_offset")


def _offset(value: Any, name: str) -> np.ndarray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = np.full(1, np.nan)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)) \
            or np.linalg.norm(arr) > MAX_GRASP_OFFSET:
        raise ValueError(f"{name}: expected 3 finite numbers (m) within {MAX_GRASP_OFFSET} m "
                         f"of the hand, got {value!r:.80}")
    arr.flags.writeable = False
    return arr

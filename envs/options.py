"""``reset(options=...)`` of the handover environments, validated with clear errors."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sandbox import urdf
from sandbox.envs.sources import family_tasks

#: Keys accepted in ``options``.
OPTION_KEYS = ("task", "object", "source", "trial", "speed", "switch_to", "switch_phase")
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
        ``"synthetic"`` or the folder of a recorded set.
    trial : int or str or None
        Recorded trial: index among the task's (or all) trials, or file name.
    speed : float
        The human moves ``speed`` times faster than the source motion.
    switch_to : str or None
        Synthetic intent switch: the task the human changes to.
    switch_phase : float
        When the switch happens (fraction of the motion).
    """

    task: str | None = None
    object: str | None = None
    source: str = "synthetic"
    trial: int | str | None = None
    speed: float = 1.0
    switch_to: str | None = None
    switch_phase: float = 0.5


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
        neither ``"synthetic"`` nor a folder, a bad speed, or an option that does not
        apply to the source (``trial`` for synthetic, ``switch_to`` for recorded).
    """
    if options is None:
        return EpisodeOptions()
    if not isinstance(options, Mapping):
        raise ValueError(f"options: expected a dict, got {type(options).__name__}")
    unknown = sorted(set(options) - set(OPTION_KEYS))
    if unknown:
        raise ValueError(f"options: expected keys among {list(OPTION_KEYS)}, got {unknown}")
    source = _source(options.get("source", "synthetic"))
    task = options.get("task")
    if task is not None and not isinstance(task, str):
        raise ValueError(f"task: expected a task name, got {task!r}")
    if source == "synthetic":
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
    obj = options.get("object")
    if obj is not None and obj not in urdf.OBJECTS:
        raise ValueError(f"object: expected one of {list(urdf.OBJECTS)}, got {obj!r}")
    return EpisodeOptions(task=task, object=obj, source=source, trial=options.get("trial"),
                          speed=_speed(options.get("speed", 1.0)),
                          switch_to=options.get("switch_to"),
                          switch_phase=_phase(options.get("switch_phase", 0.5)))


def _source(value: Any) -> str:
    if value == "synthetic":
        return value
    if isinstance(value, (str, Path)) and Path(value).is_dir():
        return str(value)
    raise ValueError(f"source: expected 'synthetic' or the folder of a recorded set "
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

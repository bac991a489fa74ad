"""The :class:`Demonstration` container: one paired human/robot motion."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.core.validation import FloatArray, check_array, check_times


def _default_names(prefix: str, n: int) -> tuple[str, ...]:
    return tuple(f"{prefix}_{i}" for i in range(n))


@dataclass(frozen=True, eq=False)
class Demonstration:
    """One demonstration of a handover: human and robot trajectories on shared times.

    Parameters
    ----------
    times : array_like, shape (T,)
        Sample times (s), strictly increasing. The motion starts at ``times[0]``.
    human : array_like, shape (T, P)
        Observed human dims (m), e.g. the left hand x, y, z in Baxter's base frame.
        NaN marks a missing sample (tracker dropout).
    robot : array_like, shape (T, Q)
        Robot dims (rad), e.g. Baxter's seven left-arm joints. Must be finite.
    task : str
        Task label.
    human_names, robot_names : sequence of str, optional
        Names of the dims (defaults ``human_0 ...``, ``robot_0 ...``).
    source : str, optional
        Where it came from (file path, generator and seed).
    meta : mapping, optional
        Anything else worth keeping (e.g. what preprocessing did).

    The arrays are copied and made read-only, so a demonstration never changes
    and never aliases the caller's arrays.
    """

    times: FloatArray
    human: FloatArray
    robot: FloatArray
    task: str
    human_names: tuple[str, ...] = ()
    robot_names: tuple[str, ...] = ()
    source: str = ""
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        times = check_times(self.times, "times")
        n = times.size
        human = check_array(self.human, "human", 2, shape=(n, None), allow_nan=True)
        robot = check_array(self.robot, "robot", 2, shape=(n, None))
        if human.shape[1] == 0 or robot.shape[1] == 0:
            raise ValueError(
                f"expected at least one human and one robot dim, got P={human.shape[1]}, "
                f"Q={robot.shape[1]}"
            )
        if not isinstance(self.task, str) or not self.task:
            raise ValueError(f"task: expected a non-empty string, got {self.task!r}")
        hn = tuple(self.human_names) or _default_names("human", human.shape[1])
        rn = tuple(self.robot_names) or _default_names("robot", robot.shape[1])
        if len(hn) != human.shape[1] or len(rn) != robot.shape[1]:
            raise ValueError(
                f"expected {human.shape[1]} human and {robot.shape[1]} robot names, "
                f"got {len(hn)} and {len(rn)}"
            )
        for arr in (times, human, robot):
            arr.setflags(write=False)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "human", human)
        object.__setattr__(self, "robot", robot)
        object.__setattr__(self, "human_names", hn)
        object.__setattr__(self, "robot_names", rn)
        object.__setattr__(self, "meta", dict(self.meta))

    @property
    def duration(self) -> float:
        """Recorded span ``times[-1] - times[0]`` (s): the ground-truth duration."""
        return float(self.times[-1] - self.times[0])

    @property
    def n_steps(self) -> int:
        """Number of samples T."""
        return int(self.times.size)

    @property
    def phase(self) -> FloatArray:
        """Phase z in [0, 1] of every sample, shape (T,)."""
        return (self.times - self.times[0]) / self.duration

    def resample(self, n_steps: int) -> Demonstration:
        """Return the demonstration linearly interpolated on ``n_steps`` equally spaced times.

        Missing (NaN) human samples are interpolated from their valid neighbours;
        a dim without any valid sample stays NaN.
        """
        if int(n_steps) < 2:
            raise ValueError(f"n_steps: expected an integer >= 2, got {n_steps!r}")
        t = np.linspace(self.times[0], self.times[-1], int(n_steps))
        return self.replace(
            times=t,
            human=_interp_columns(t, self.times, self.human),
            robot=_interp_columns(t, self.times, self.robot),
        )

    def replace(self, **changes: Any) -> Demonstration:
        """Return a copy with some fields replaced (validated again)."""
        fields = {
            "times": self.times,
            "human": self.human,
            "robot": self.robot,
            "task": self.task,
            "human_names": self.human_names,
            "robot_names": self.robot_names,
            "source": self.source,
            "meta": self.meta,
        }
        fields.update(changes)
        return Demonstration(**fields)

    def __repr__(self) -> str:
        return (
            f"Demonstration(task={self.task!r}, T={self.n_steps}, duration={self.duration:.2f} s, "
            f"P={self.human.shape[1]}, Q={self.robot.shape[1]}, source={self.source!r})"
        )


def _interp_columns(t_new: FloatArray, t: FloatArray, values: FloatArray) -> FloatArray:
    out = np.full((t_new.size, values.shape[1]), np.nan)
    for j in range(values.shape[1]):
        ok = np.isfinite(values[:, j])
        if ok.any():
            out[:, j] = np.interp(t_new, t[ok], values[ok, j])
    return out


def stack_tasks(demos: Sequence[Demonstration]) -> dict[str, list[Demonstration]]:
    """Group demonstrations by task, keeping their order (tasks in first-seen order)."""
    groups: dict[str, list[Demonstration]] = {}
    for demo in demos:
        groups.setdefault(demo.task, []).append(demo)
    return groups

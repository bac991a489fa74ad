"""The :class:`Demonstration` container: one paired human/robot motion."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.core.modality import (
    Modality,
    check_modalities,
    default_modalities,
    select,
    slices,
)
from sandbox.validation import FloatArray, check_array, check_times


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
        Observed human dims, the modalities' columns one after the other (e.g.
        the left hand x, y, z in Baxter's base frame, m). NaN marks a missing
        sample (tracker dropout).
    robot : array_like, shape (T, Q)
        Robot dims, e.g. Baxter's seven left-arm joints (rad), or a task-space
        position (m, ``robot_space="task"``). Must be finite.
    task : str
        Task label.
    human_names, robot_names : sequence of str, optional
        Names of the dims (defaults ``human_0 ...``, ``robot_0 ...``, or the
        modalities' dims).
    modalities : sequence of Modality, optional
        What the human dims are (:mod:`sandbox.core.modality`); default one
        position modality ``"hand"`` over all of them.
    source : str, optional
        Where it came from (file path, generator and seed).
    meta : mapping, optional
        Anything else worth keeping (e.g. what preprocessing did).
    robot_space : {"joint", "task"}
        What the robot dims are: joint angles (rad, default) or a position in
        the robot's base frame (m) (:data:`sandbox.data.spec.ROBOT_SPACES`).

    The arrays are copied and made read-only, so a demonstration never changes
    and never aliases the caller's arrays.
    """

    times: FloatArray
    human: FloatArray
    robot: FloatArray
    task: str
    human_names: tuple[str, ...] = ()
    robot_names: tuple[str, ...] = ()
    modalities: tuple[Modality, ...] = ()
    source: str = ""
    meta: Mapping[str, Any] = field(default_factory=dict)
    robot_space: str = "joint"

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
        if self.robot_space not in ("joint", "task"):
            raise ValueError(f"robot_space: expected 'joint' or 'task', got {self.robot_space!r}")
        if not isinstance(self.task, str) or not self.task:
            raise ValueError(f"task: expected a non-empty string, got {self.task!r}")
        mods = tuple(self.modalities)
        if mods:
            check_modalities(mods, human.shape[1])
        hn = tuple(self.human_names) or (tuple(d for m in mods for d in m.dims) if mods else
                                         _default_names("human", human.shape[1]))
        rn = tuple(self.robot_names) or _default_names("robot", robot.shape[1])
        if len(hn) != human.shape[1] or len(rn) != robot.shape[1]:
            raise ValueError(
                f"expected {human.shape[1]} human and {robot.shape[1]} robot names, "
                f"got {len(hn)} and {len(rn)}"
            )
        mods = check_modalities(mods or default_modalities(hn), human.shape[1])
        if tuple(d for m in mods for d in m.dims) != hn:
            raise ValueError(f"human_names {list(hn)} differ from the modalities' dims "
                             f"{[d for m in mods for d in m.dims]}")
        for arr in (times, human, robot):
            arr.setflags(write=False)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "human", human)
        object.__setattr__(self, "robot", robot)
        object.__setattr__(self, "human_names", hn)
        object.__setattr__(self, "robot_names", rn)
        object.__setattr__(self, "modalities", mods)
        object.__setattr__(self, "meta", dict(self.meta))

    @property
    def duration(self) -> float:
        """Recorded span ``times[-1] - times[0]`` (s): the ground-truth duration."""
        return float(self.times[-1] - self.times[0])

    @property
    def jitter(self) -> dict[str, float]:
        """Jitter (m) of each position modality's raw tracker frames, by name, as the
        loader measured it before any filter (``meta["report"]``; :mod:`sandbox.core.jitter`);
        empty when not measured (e.g. a demonstration never preprocessed)."""
        counts = (self.meta.get("report") or {}).get("modalities") or {}
        return {name: float(c["jitter_m"]) for name, c in counts.items()
                if isinstance(c, dict) and c.get("jitter_m") is not None}

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
            "modalities": self.modalities,
            "source": self.source,
            "meta": self.meta,
            "robot_space": self.robot_space,
        }
        fields.update(changes)
        return Demonstration(**fields)

    def select(self, observe) -> Demonstration:
        """The demonstration with only the named modalities (a list or ``"a,b"``), in that order.

        An unknown name is a ``ValueError`` listing the modalities there are.
        """
        mods = select(self.modalities, observe,
                      f"observe (this demonstration has {[m.name for m in self.modalities]})")
        where = slices(self.modalities)
        cols = np.concatenate([np.arange(where[m.name].start, where[m.name].stop) for m in mods])
        meta = dict(self.meta)
        if np.ndim(meta.get("modality_measured")) == 2:
            index = [m.name for m in self.modalities]
            measured = meta["modality_measured"][:, [index.index(m.name) for m in mods]]
            meta["modality_measured"] = measured
            meta["human_measured"] = measured.any(axis=1)
        return self.replace(human=self.human[:, cols], modalities=mods, human_names=(),
                            meta=meta)

    def __repr__(self) -> str:
        observe = ",".join(m.name for m in self.modalities)
        return (
            f"Demonstration(task={self.task!r}, T={self.n_steps}, duration={self.duration:.2f} s, "
            f"observe={observe}, P={self.human.shape[1]}, Q={self.robot.shape[1]}, "
            f"source={self.source!r})"
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

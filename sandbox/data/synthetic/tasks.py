"""Task geometry and per-demonstration random draws of the synthetic handovers.

A :class:`TaskSpec` says where a task's hand motion goes on average; a
:class:`Variability` says how demonstrations vary around it (measured on the
recorded handovers, see the constants); a :class:`DemoDraw` holds one
demonstration's random numbers, so that the same draw can be applied to two
tasks (an intent switch, or the shared prefix of diverging tasks).

Timing is expressed as fractions of the demonstration's duration ``T``
(measured medians on the recordings: the hand's reach is over at ~53 % of
``T`` and the robot's at ~65 %, the robot starting with the human; the
recording runs on while both hold still).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sandbox.data.synthetic.base import HAND_START
from sandbox.data.synthetic.human import Reach
from sandbox.validation import FloatArray, check_positive

#: Median detour (rad) of the recorded arm motions from the straight joint-space
#: line at mid-motion (kinesthetic demonstrations are not straight in joint space).
WOBBLE_MEAN = np.array([0.0, -0.02, -0.05, 0.01, -0.08, -0.055, 0.0])
#: Mean deviation (m) of the recorded reaches from the straight line at half
#: the distance (they bow toward the robot, to its right and down): the via-point.
VIA_OFFSET = np.array([-0.03, -0.03, -0.025])


def _vec3(value: object, name: str) -> FloatArray:
    arr = np.array(value, dtype=float)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ValueError(f"{name}: expected 3 finite numbers (m), got {value!r}")
    arr.setflags(write=False)
    return arr


def _range(value: tuple[float, float], name: str, lo: float, hi: float) -> None:
    a, b = value
    if not lo <= a <= b <= hi:
        raise ValueError(f"{name}: expected {lo} <= low <= high <= {hi}, got {value!r}")


@dataclass(frozen=True)
class TaskSpec:
    """The mean geometry and speed of one task.

    Parameters
    ----------
    name : str
        Task label.
    end : array_like, shape (3,)
        Mean end of the shared path (m), Baxter's base frame.
    branch : array_like, shape (3,)
        Deviation (m) added after the divergence phase (zeros: none); the hand
        comes to rest at ``end + branch``.
    via : array_like, shape (3,)
        Mean via-point offset (m) from the middle of the start-end line.
    duration : tuple of float
        Mean and standard deviation (s) of the demonstration's duration.
    """

    name: str
    end: FloatArray
    branch: FloatArray = field(default_factory=lambda: np.zeros(3))
    via: FloatArray = field(default_factory=lambda: VIA_OFFSET.copy())
    duration: tuple[float, float] = (2.2, 0.3)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name: expected a non-empty string, got {self.name!r}")
        for key in ("end", "branch", "via"):
            object.__setattr__(self, key, _vec3(getattr(self, key), key))
        check_positive(self.duration[0], "duration mean")
        check_positive(self.duration[1], "duration std", allow_zero=True)


@dataclass(frozen=True)
class Variability:
    """How demonstrations vary (defaults: measured on the recordings).

    Parameters
    ----------
    start_std, end_std : tuple of float
        Per-axis standard deviations (m) of the start and end points.
    via_std : float
        Per-axis standard deviation (m) of the via-point.
    reach_on : tuple of float
        Range (uniform) of the reach's start, fraction of ``T`` (may be < 0:
        already moving when the recording starts).
    reach_off : tuple of float
        Mean and standard deviation of the reach's end, fraction of ``T``.
    divergence : tuple of float
        Mean and half-width (uniform) of the divergence phase of branching tasks.
    robot_lag : tuple of float
        Mean and standard deviation of the robot's end after the hand's,
        fraction of ``T`` (negative: the robot leads).
    skew : float
        Warp of the primary submovement's minimum-jerk phase.
    primary : float
        Duration of the primary submovement, fraction of the reach.
    correction : tuple of float
        Range (uniform) of the fraction of the path left to the corrective submovement.
    aim_std : float
        Per-axis standard deviation (m) of the primary submovement's aiming error.
    drift_m : float
        Per-axis standard deviation (m) of the slow drift while the hand holds.
    grasp_std : float
        Per-axis standard deviation (m) of where the gripper meets the hand.
    wobble_std : tuple of float
        Per-joint standard deviations (rad) of the robot's joint-space detour
        at mid-motion (around :data:`WOBBLE_MEAN`).
    duration_range : tuple of float
        Clip of the duration (s).
    """

    start_std: tuple[float, float, float] = (0.025, 0.025, 0.02)
    end_std: tuple[float, float, float] = (0.06, 0.055, 0.10)
    via_std: float = 0.04
    reach_on: tuple[float, float] = (-0.06, 0.03)
    reach_off: tuple[float, float] = (0.70, 0.06)
    divergence: tuple[float, float] = (0.5, 0.05)
    robot_lag: tuple[float, float] = (0.0, 0.04)
    skew: float = 0.8
    primary: float = 0.6
    correction: tuple[float, float] = (0.08, 0.2)
    aim_std: float = 0.03
    drift_m: float = 0.01
    grasp_std: float = 0.01
    wobble_std: tuple[float, ...] = (0.04, 0.03, 0.03, 0.06, 0.08, 0.09, 0.02)
    duration_range: tuple[float, float] = (1.7, 4.0)

    def __post_init__(self) -> None:
        for key, size in (("start_std", 3), ("end_std", 3), ("wobble_std", 7)):
            if len(getattr(self, key)) != size:
                raise ValueError(f"{key}: expected {size} numbers, got {getattr(self, key)!r}")
            for value in getattr(self, key):
                check_positive(value, key, allow_zero=True)
        for key in ("via_std", "grasp_std", "drift_m", "aim_std"):
            check_positive(getattr(self, key), key, allow_zero=True)
        if self.skew <= 1.0 / 3.0:
            raise ValueError(f"skew: expected a number > 1/3, got {self.skew!r}")
        _range(self.reach_on, "reach_on", -0.5, 0.5)
        _range(self.correction, "correction", 0.0, 0.5)
        if not 0.2 <= self.primary <= 1.0:
            raise ValueError(f"primary: expected a fraction in [0.2, 1], got {self.primary!r}")
        _range(self.duration_range, "duration_range", 0.1, 60.0)
        if not 0.2 <= self.reach_off[0] <= 1.0:
            raise ValueError(f"reach_off: expected a mean in [0.2, 1], got {self.reach_off!r}")
        if not 0.1 <= self.divergence[0] <= 0.9 or not 0 <= self.divergence[1] <= 0.1:
            raise ValueError(f"divergence: expected (0.1..0.9, 0..0.1), got {self.divergence!r}")


@dataclass(frozen=True)
class DemoDraw:
    """One demonstration's random numbers (times in s, offsets in m)."""

    duration: float
    start: FloatArray
    end_shift: FloatArray
    via_shift: FloatArray
    t_on: float
    t_off: float
    t_div: float
    robot_on: float
    robot_off: float
    grasp_shift: FloatArray
    wobble: FloatArray
    correction: float
    aim: FloatArray
    drift: FloatArray
    drift_hz: float
    tracker_seed: int


def draw_demo(spec: TaskSpec, var: Variability, rng: np.random.Generator) -> DemoDraw:
    """Draw one demonstration's random numbers for ``spec`` (see :class:`Variability`)."""
    lo, hi = var.duration_range
    T = float(np.clip(rng.normal(*spec.duration), lo, hi))
    on = rng.uniform(*var.reach_on)
    off = float(np.clip(rng.normal(*var.reach_off), max(on, 0.0) + 0.3, 1.0))
    mid, half = var.divergence
    div = float(np.clip(rng.uniform(mid - half, mid + half), on + 0.05, off - 0.1))
    robot_on = rng.uniform(0.0, 0.03)
    robot_off = float(np.clip(off + rng.normal(*var.robot_lag), robot_on + 0.3, 1.0))
    return DemoDraw(
        duration=T,
        start=HAND_START + rng.normal(0.0, var.start_std),
        end_shift=rng.normal(0.0, var.end_std),
        via_shift=rng.normal(0.0, var.via_std, 3),
        t_on=on * T,
        t_off=off * T,
        t_div=div * T,
        robot_on=robot_on * T,
        robot_off=robot_off * T,
        grasp_shift=rng.normal(0.0, var.grasp_std, 3),
        wobble=WOBBLE_MEAN + rng.normal(0.0, var.wobble_std),
        correction=rng.uniform(*var.correction),
        aim=rng.normal(0.0, var.aim_std, 3),
        drift=rng.normal(0.0, var.drift_m, 3),
        drift_hz=rng.uniform(0.3, 0.8),
        tracker_seed=int(rng.integers(2**63 - 1)),
    )


def redraw_end(draw: DemoDraw, var: Variability, rng: np.random.Generator) -> DemoDraw:
    """The same draw with a new end point (used when the robot cannot reach the first)."""
    fields = dict(draw.__dict__)
    fields["end_shift"] = rng.normal(0.0, var.end_std)
    fields["grasp_shift"] = rng.normal(0.0, var.grasp_std, 3)
    return DemoDraw(**fields)


def make_reach(spec: TaskSpec, draw: DemoDraw, var: Variability) -> Reach:
    """The clean reach of task ``spec`` under ``draw``."""
    end = spec.end + draw.end_shift
    via = 0.5 * (draw.start + end) + spec.via + draw.via_shift
    return Reach(
        points=np.stack([draw.start, via, end]),
        t_on=draw.t_on,
        t_off=draw.t_off,
        skew=var.skew,
        primary=var.primary,
        correction=draw.correction,
        aim=draw.aim,
        drift=draw.drift,
        drift_hz=draw.drift_hz,
        branch=spec.branch,
        t_div=draw.t_div,
    )

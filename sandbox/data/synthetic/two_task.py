"""The minimal two-task generator used by the core's tests and the demo.

:func:`two_task_demos` makes smooth reach-to-handover motions with two clearly
different endings and a robot side that is a fixed smooth function of the hand's
end point (no inverse kinematics), so it is fast and dependency-free.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from sandbox.core.modality import Modality
from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.arm import ArmModel, arm_positions
from sandbox.data.synthetic.base import (
    HAND_START,
    ROBOT_NAMES,
    child_rng,
    minimum_jerk,
)
from sandbox.data.synthetic.observe import SYNTHETIC_MODALITIES, check_observe
from sandbox.robot import Q_HOME
from sandbox.validation import FloatArray

#: A fixed, smooth map from the hand's end point (m) to the joint change (rad), (7, 3).
_JOINT_MAP = np.array(
    [[-0.9, 1.2, 0.1], [0.5, 0.2, -1.1], [0.3, 0.6, 0.4], [0.8, -0.3, -0.9],
     [-0.2, 0.1, 0.3], [0.6, -0.4, 1.0], [0.0, 0.2, 0.1]]
)
#: The end point (m) the joint change is measured from, and the joint change (rad) there.
_END_REF = np.array([0.80, 0.10, 0.20])
_DQ_REF = np.array([-0.45, 0.1, 0.15, -0.3, 0.0, 0.0, 0.0])


@dataclass(frozen=True)
class _Draw:
    """The distributions of :func:`two_task_demos` (its arguments of the same names)."""

    rate_hz: float
    duration_mean: float
    duration_std: float
    noise_m: float
    separation_m: float


def _observed(
    observe: tuple[str, ...], times: FloatArray, clean: FloatArray, hand: FloatArray,
    noise_m: float, arm_rng: np.random.Generator | None, arm_model: ArmModel | None,
) -> tuple[FloatArray, tuple[Modality, ...], dict[str, Any]]:
    """The observed columns (T, P), their modalities and the extra ``meta`` (clean motions)."""
    mods = tuple(SYNTHETIC_MODALITIES[name] for name in observe)
    if arm_rng is None:
        return hand, mods, {}
    arm = arm_positions(times, clean, arm_rng, model=arm_model)
    columns = {"hand": hand, "arm": arm + arm_rng.normal(0.0, noise_m, arm.shape)}
    human = np.column_stack([columns[name] for name in observe])
    return human, mods, {"clean_human": clean, "clean_arm": arm}


def two_task_demos(
    n_per_task: int,
    rng: np.random.Generator,
    *,
    rate_hz: float = 100.0,
    duration_mean: float = 2.2,
    duration_std: float = 0.25,
    noise_m: float = 0.004,
    separation_m: float = 0.30,
    observe: Sequence[str] | str = ("hand",),
    arm_model: ArmModel | None = None,
) -> list[Demonstration]:
    """Two handover tasks, ``"left"`` and ``"right"``, with different hand end points.

    The hand reaches from near :data:`HAND_START` to an end point whose y differs
    by ``separation_m`` between the tasks, with a minimum-jerk (bell-shaped
    speed) profile; the robot's joints move from :data:`~sandbox.robot.Q_HOME` toward a
    configuration that is a fixed smooth function of the hand's end point, so the
    human -> robot relation is learnable.

    Parameters
    ----------
    n_per_task : int
        Demonstrations per task (>= 2).
    rng : numpy.random.Generator
        Source of randomness; the same seed gives the same demonstrations.
    rate_hz : float
        Sample rate (Hz).
    duration_mean, duration_std : float
        Duration distribution (s), clipped to [1.7, 4.0].
    noise_m : float
        Standard deviation of white noise on the human samples (m).
    separation_m : float
        Distance between the two tasks' mean end points (m).
    observe : str or sequence of str
        Observed modalities: ``"hand"`` (default), ``"hand,arm"`` or ``"arm"``.
        The arm (:mod:`sandbox.data.synthetic.arm`, with the same white noise)
        draws from a child of ``rng``'s seed sequence, never from ``rng``;
        ``meta`` then holds ``clean_human`` (T, 3) and ``clean_arm`` (T, 6), m.
    arm_model : ArmModel, optional
        The human arm (default ``ArmModel()``).

    Returns
    -------
    list of Demonstration
        ``n_per_task`` demos of ``"left"`` followed by ``n_per_task`` of ``"right"``.
    """
    if int(n_per_task) < 2:
        raise ValueError(f"n_per_task: expected an integer >= 2, got {n_per_task!r}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    observe = check_observe(observe)
    arm_rng = child_rng(rng) if "arm" in observe else None
    draw = _Draw(rate_hz, duration_mean, duration_std, noise_m, separation_m)
    return [_demo(task, i, side, rng, draw, observe, arm_rng, arm_model)
            for task, side in (("left", 1.0), ("right", -1.0)) for i in range(int(n_per_task))]


def _demo(
    task: str, i: int, side: float, rng: np.random.Generator, draw: _Draw,
    observe: tuple[str, ...], arm_rng: np.random.Generator | None, arm_model: ArmModel | None,
) -> Demonstration:
    """Demonstration ``i`` of ``task`` (``side`` +1 left, -1 right)."""
    t, clean, hand, robot = _demo_motion(rng, side, draw)
    human, mods, meta = _observed(observe, t, clean, hand, draw.noise_m, arm_rng, arm_model)
    return Demonstration(
        times=t, human=human, robot=robot, task=task, robot_names=ROBOT_NAMES,
        modalities=mods, source=f"synthetic:two_task[{task}#{i}]",
        meta={**meta, "robot_meets_hand": False},   # no meeting geometry (sandbox.data.geometry)
    )


def _demo_motion(
    rng: np.random.Generator, side: float, draw: _Draw
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """One demonstration's times (T,) s, clean and noisy hand (T, 3) m and robot (T, 7) rad.

    Draws from ``rng``, in this order: the duration, the start, end and via
    points, the hand's noise.
    """
    dur = float(np.clip(rng.normal(draw.duration_mean, draw.duration_std), 1.7, 4.0))
    t = np.arange(0.0, dur + 0.5 / draw.rate_hz, 1.0 / draw.rate_hz)
    t[-1] = min(t[-1], dur)
    start = HAND_START + rng.normal(0.0, 0.02, 3)
    end = np.array([0.80, 0.10 + side * draw.separation_m / 2, 0.20]) + rng.normal(0, 0.03, 3)
    via = 0.5 * (start + end) + np.array([0.0, 0.0, 0.08]) + rng.normal(0, 0.01, 3)
    s = minimum_jerk(t / dur)[:, None]
    # Quadratic Bezier through the via-point keeps the path smooth and curved.
    clean = (1 - s) ** 2 * start + 2 * (1 - s) * s * via + s**2 * end
    hand = clean + rng.normal(0.0, draw.noise_m, clean.shape)
    dq = _JOINT_MAP @ (end - _END_REF) + _DQ_REF
    robot = Q_HOME + s * (dq + 0.1 * np.sin(dq))
    return t, clean, hand, robot

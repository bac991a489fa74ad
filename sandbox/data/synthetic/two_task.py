"""The minimal two-task generator used by the core's tests and the demo.

:func:`two_task_demos` makes smooth reach-to-handover motions with two clearly
different endings and a robot side that is a fixed smooth function of the hand's
end point (no inverse kinematics), so it is fast and dependency-free.
"""

from __future__ import annotations

import numpy as np

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic.base import (
    HAND_START,
    HUMAN_NAMES,
    Q_HOME,
    ROBOT_NAMES,
    minimum_jerk,
)


def two_task_demos(
    n_per_task: int,
    rng: np.random.Generator,
    *,
    rate_hz: float = 100.0,
    duration_mean: float = 2.2,
    duration_std: float = 0.25,
    noise_m: float = 0.004,
    separation_m: float = 0.30,
) -> list[Demonstration]:
    """Two handover tasks, ``"left"`` and ``"right"``, with different hand end points.

    The hand reaches from near :data:`HAND_START` to an end point whose y differs
    by ``separation_m`` between the tasks, with a minimum-jerk (bell-shaped
    speed) profile; the robot's joints move from :data:`Q_HOME` toward a
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

    Returns
    -------
    list of Demonstration
        ``n_per_task`` demos of ``"left"`` followed by ``n_per_task`` of ``"right"``.
    """
    if int(n_per_task) < 2:
        raise ValueError(f"n_per_task: expected an integer >= 2, got {n_per_task!r}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    # A fixed, smooth map from the hand's end point (m) to the joint change (rad).
    jac = np.array(
        [[-0.9, 1.2, 0.1], [0.5, 0.2, -1.1], [0.3, 0.6, 0.4], [0.8, -0.3, -0.9],
         [-0.2, 0.1, 0.3], [0.6, -0.4, 1.0], [0.0, 0.2, 0.1]]
    )
    demos = []
    for task, side in (("left", 1.0), ("right", -1.0)):
        for i in range(int(n_per_task)):
            dur = float(np.clip(rng.normal(duration_mean, duration_std), 1.7, 4.0))
            t = np.arange(0.0, dur + 0.5 / rate_hz, 1.0 / rate_hz)
            t[-1] = min(t[-1], dur)
            start = HAND_START + rng.normal(0.0, 0.02, 3)
            end = np.array([0.80, 0.10 + side * separation_m / 2, 0.20]) + rng.normal(0, 0.03, 3)
            via = 0.5 * (start + end) + np.array([0.0, 0.0, 0.08]) + rng.normal(0, 0.01, 3)
            s = minimum_jerk(t / dur)[:, None]
            # Quadratic Bezier through the via-point keeps the path smooth and curved.
            hand = (1 - s) ** 2 * start + 2 * (1 - s) * s * via + s**2 * end
            hand = hand + rng.normal(0.0, noise_m, hand.shape)
            dq = jac @ (end - np.array([0.80, 0.10, 0.20])) + np.array([-0.45, 0.1, 0.15, -0.3,
                                                                         0.0, 0.0, 0.0])
            robot = Q_HOME + s * (dq + 0.1 * np.sin(dq))
            demos.append(
                Demonstration(
                    times=t, human=hand, robot=robot, task=task,
                    human_names=HUMAN_NAMES, robot_names=ROBOT_NAMES,
                    source=f"synthetic:two_task[{task}#{i}]",
                )
            )
    return demos


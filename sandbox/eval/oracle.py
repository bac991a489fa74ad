"""The oracle of a leave-one-out fold: the true task conditioned at the true duration.

:func:`~sandbox.eval.loocv.evaluate_trial` scores, beside the static and dynamic
formulations, the robot that all kept observations condition when the task and the
duration are known (DESIGN.md section 5). It needs neither the speeds nor the task
posterior, so it is computed here without the phase estimate that
:func:`~sandbox.core.predict` makes first: the same robot, bit for bit.
"""

from __future__ import annotations

import numpy as np

from sandbox.core.factor import condition_robot
from sandbox.core.promp import trajectory_distribution


def oracle_robot(model, scorer, t_obs, y_obs, k: int, T: float):
    """The oracle's robot: task ``k`` conditioned at duration ``T`` (s) on all kept
    observations (eq. 8).

    The robot :func:`~sandbox.core.predict` conditions with ``task=k, duration=T``, bit for
    bit, without its phase estimate (speeds and posterior, which the oracle's scores do
    not use; it cost about 5 % of a fold). Returns a
    :class:`~sandbox.core.promp.WeightDistribution` over the Q robot dims.
    """
    cond = scorer.conditioner     # shrinkage="robot" or condition_floor: another scorer
    factor = cond.joint_pairs(t_obs, y_obs, np.array([float(T)]), np.array([int(k)]))[1][0]
    return condition_robot(cond.weights[k], factor, model.n_human, cond.rank[k])


def held_trajectory(robot, duration: float, basis, times):
    """Robot mean (T, Q) and covariance (T, Q, Q) at ``times`` (s) of ``robot`` played over
    ``duration`` (s), held after its end: :meth:`~sandbox.core.inference.Prediction.trajectory`
    of a prediction with this robot and duration."""
    z = np.clip(np.asarray(times, dtype=np.float64) / duration, 0.0, 1.0)
    held = int(np.count_nonzero(z >= 1.0))
    if held < 2 or not np.all(z[z.size - held:] >= 1.0):
        return trajectory_distribution(robot, basis, z)
    mean, cov = trajectory_distribution(robot, basis, z[:z.size - held + 1])
    rest = held - 1
    return (np.concatenate([mean, np.repeat(mean[-1:], rest, axis=0)]),
            np.concatenate([cov, np.repeat(cov[-1:], rest, axis=0)]))

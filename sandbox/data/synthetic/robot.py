"""The robot side of a synthetic demonstration: Baxter's left arm meeting the hand.

Like a kinesthetic demonstration, the arm moves from :data:`~sandbox.robot.Q_HOME` to a
configuration that puts the gripper at the handover point, along a joint-space
minimum-jerk trajectory timed with the human (it may lead or lag a little).

Measured on the recordings (174 trials, forward kinematics of the final
recorded joints vs the hand's resting point): the gripper tip
(:data:`~sandbox.robot.TIP_LINK`, pointing down) ends at the hand,
:data:`~sandbox.robot.GRASP_OFFSET` away
(median; per-trial spread ~6 cm in x and z, 2.5 cm in y, mostly tracker error).
The inverse kinematics (:class:`sandbox.robot.BaxterKinematics`, position only,
batched) starts from :data:`Q_HANDOVER`, the median final configuration of the
recordings, so the solutions look like the demonstrated ones (median joint
difference 0.07 rad on the recorded handover points).
"""

from __future__ import annotations

import numpy as np

from sandbox.data.synthetic.base import skewed_minimum_jerk
from sandbox.robot import GRASP_OFFSET, Q_HOME, TIP_LINK, BaxterKinematics
from sandbox.validation import FloatArray

#: Median final left-arm configuration of the recordings (rad): the IK seed.
Q_HANDOVER = np.array([-0.431, -0.781, -0.777, 1.142, 0.492, 1.296, -0.142])


def kinematics():
    """Baxter's kinematics (:class:`sandbox.robot.BaxterKinematics`, cached per process)."""
    return BaxterKinematics()


def solve_handover(targets: FloatArray, tol: float):
    """Batched inverse kinematics of the gripper at the handover points.

    Parameters
    ----------
    targets : ndarray, shape (n, 3)
        Gripper tip targets (m), Baxter's base frame.
    tol : float
        Success threshold (m) on the position error.

    Returns
    -------
    sandbox.robot.IKResult
        ``q`` (n, 7) rad, ``error`` (n,) m, ``success`` (n,) bool.
    """
    return kinematics().ik(targets, q_seed=Q_HANDOVER, link=TIP_LINK, tol=tol)


def bump(s: FloatArray) -> FloatArray:
    """Smooth bump ``16 s^2 (1 - s)^2``: 0 with zero slope at s = 0 and 1, peak 1 at 0.5."""
    s = np.clip(s, 0.0, 1.0)
    return 16.0 * s**2 * (1.0 - s) ** 2


def joint_trajectory(
    times: FloatArray,
    q_goal: FloatArray,
    t_on: float,
    t_off: float,
    wobble: FloatArray,
    limits: tuple[FloatArray, FloatArray],
    skew: float = 0.8,
) -> FloatArray:
    """Minimum-jerk joint trajectory from :data:`Q_HOME` to ``q_goal``.

    The phase is warped like the human's primary submovement (``skew``, peak
    speed at ~40 % of the motion), as in the recorded arm motions (peak joint
    speed at ~33 % of the demonstration, motion over at ~65 %).

    Parameters
    ----------
    times : ndarray, shape (T,)
        Sample times (s).
    q_goal : ndarray, shape (7,)
        Final configuration (rad).
    t_on, t_off : float
        Start and end of the motion (s).
    wobble : ndarray, shape (7,)
        Amplitude (rad) of a smooth deviation that vanishes at both ends.
    limits : tuple of ndarray, shapes (7,), (7,)
        Lower and upper joint limits (rad); the result is clipped to them.
    skew : float
        Warp of the minimum-jerk phase (1: symmetric).

    Returns
    -------
    ndarray, shape (T, 7)
        Joint angles (rad); ``Q_HOME`` before ``t_on``, ``q_goal`` after ``t_off``.
    """
    s = (times - t_on) / (t_off - t_on)
    q = Q_HOME + np.outer(skewed_minimum_jerk(s, skew), q_goal - Q_HOME)
    q = q + np.outer(bump(s), wobble)
    return np.clip(q, limits[0], limits[1])


def robot_meeting(times: FloatArray, hand_end: FloatArray, t_on: float, t_off: float, *,
                  ik_tol: float = 0.01, wobble: FloatArray | None = None
                  ) -> tuple[FloatArray, float]:
    """The robot's paired motion for a hand that comes to rest at ``hand_end``.

    The synthetic generator's construction for one given handover point: the
    gripper tip's target is ``hand_end`` + :data:`GRASP_OFFSET`, the
    configuration there comes from :func:`solve_handover`, and the arm moves
    from :data:`Q_HOME` along :func:`joint_trajectory` between ``t_on`` and
    ``t_off`` (e.g. when a teleoperated hand starts and stops).

    Parameters
    ----------
    times : ndarray, shape (T,)
        Sample times (s).
    hand_end : array_like, shape (3,)
        Where the hand rests (m), Baxter's base frame.
    t_on, t_off : float
        Start and end (s) of the arm's motion, ``t_on < t_off``.
    ik_tol : float
        Required gripper position error (m).
    wobble : array_like, shape (7,), optional
        Joint-space detour at mid-motion (rad); default the recordings' median,
        :data:`sandbox.data.synthetic.tasks.WOBBLE_MEAN`.

    Returns
    -------
    q : ndarray, shape (T, 7)
        Joint angles (rad).
    error : float
        Gripper position error (m) at ``hand_end + GRASP_OFFSET``.

    Raises
    ------
    ValueError
        If ``t_off <= t_on`` or Baxter's left arm cannot reach the point within ``ik_tol``.
    """
    from sandbox.data.synthetic.tasks import WOBBLE_MEAN

    hand_end = np.asarray(hand_end, dtype=float)
    if hand_end.shape != (3,) or not np.isfinite(hand_end).all():
        raise ValueError(f"hand_end: expected 3 finite numbers (m), got {hand_end!r}")
    if not t_off > t_on:
        raise ValueError(f"t_on, t_off: expected t_on < t_off (s), got {t_on!r}, {t_off!r}")
    res = solve_handover((hand_end + GRASP_OFFSET)[None], ik_tol)
    if not res.success[0]:
        raise ValueError(
            f"hand_end: expected a handover point Baxter's left arm can reach (IK within "
            f"{ik_tol} m), got ({', '.join(f'{v:.3f}' for v in hand_end)}) m, "
            f"{res.error[0]:.3f} m out of reach")
    kin = kinematics()
    wobble = WOBBLE_MEAN if wobble is None else np.asarray(wobble, dtype=float)
    q = joint_trajectory(np.asarray(times, dtype=float), res.q[0], t_on, t_off, wobble,
                         (kin.lower, kin.upper))
    return q, float(res.error[0])

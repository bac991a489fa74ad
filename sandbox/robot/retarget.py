"""Retargeting: a plan learned on Baxter (or in task space) carried out by any arm.

The demonstrations were recorded with Baxter's left-arm joints. Another arm
cannot follow Baxter's joints, but it can follow Baxter's fingertip:

1. the robot part of a plan is taken to task space: a joint-space plan
   (n, 7) of Baxter goes through Baxter's forward kinematics to its fingertip
   path (n, 3) (:data:`~sandbox.robot.TIP_LINK`, in the world, Baxter's
   ``base`` frame); a task-space plan (n, 3) already is one;
2. the path is expressed in the arm's root frame (its base stands at
   :attr:`~sandbox.robot.arms.ArmSpec.base`) and goes through the arm's
   inverse kinematics (:mod:`sandbox.robot.ik`, damped least squares within
   the joint limits), each point seeded with the previous solution so the
   joints move continuously;
3. each step moves at most ``max_velocity * dt`` per joint (the URDF's speed
   limits), as every policy already does for Baxter.

A point the arm cannot reach (IK error above ``tol``) is reported, never
hidden: the solution is the closest configuration found and
:attr:`Retargeted.reached` says which points were reached.
:func:`reachability` gives the fraction of points (e.g. the training meeting
points) an arm reaches, and :func:`check_reach` warns below
:data:`REACH_WARNING`.

Examples
--------
>>> import numpy as np
>>> from sandbox.robot import Q_HOME
>>> arm = Retargeter("ur5")
>>> out = arm.plan(np.linspace(0, 1, 5), np.repeat(Q_HOME[None], 5, 0))
>>> out.q.shape, bool(out.reached.all())
((5, 6), True)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.robot.facts import TIP_LINK
from sandbox.robot.kinematics import ArmKinematics, BaxterKinematics
from sandbox.validation import check_array, check_positive, check_times

FloatArray = NDArray[np.float64]
#: IK position tolerance (m) of retargeting: a point farther than this from the arm's
#: best configuration is out of reach.
IK_TOL = 0.01
#: Below this fraction of reached meeting points, :func:`check_reach` warns.
REACH_WARNING = 0.95


@dataclass(frozen=True)
class Retargeted:
    """A plan carried out by one arm.

    Attributes
    ----------
    q : ndarray, shape (n, dof)
        Joint configurations (rad), within the joint limits and speed limits.
    points : ndarray, shape (n, 3)
        The task-space path it follows (world, m).
    error : ndarray, shape (n,)
        Distance (m) from the arm's tip at ``q`` to each point.
    reached : ndarray of bool, shape (n,)
        ``error <= tol``.
    """

    q: FloatArray
    points: FloatArray
    error: FloatArray
    reached: NDArray[np.bool_]


class Retargeter:
    """One arm following Baxter's (or a task-space) robot part.

    Parameters
    ----------
    robot : str
        A name of :data:`sandbox.robot.arms.ROBOTS`.
    tol : float
        IK position tolerance (m), default :data:`IK_TOL`.

    Attributes
    ----------
    kinematics : ArmKinematics
        The arm's kinematics (root frame).
    base : ndarray, shape (4, 4)
        The arm's root pose in the world (m).
    max_velocity : ndarray, shape (dof,)
        Joint speed limits (rad/s) from the URDF.
    """

    def __init__(self, robot: str = "baxter", tol: float = IK_TOL) -> None:
        self.kinematics = ArmKinematics(robot)
        self.robot = robot
        self.tol = check_positive(tol, "tol")
        self.base = np.array(self.kinematics.spec.base)
        self._inverse = np.linalg.inv(self.base)
        self.max_velocity = np.array(self.kinematics.max_velocity)
        self._baxter = BaxterKinematics()

    @property
    def dof(self) -> int:
        """Number of the arm's joints."""
        return self.kinematics.dof

    def task_points(self, robot_part: ArrayLike) -> FloatArray:
        """The task-space path (n, 3) m (world) of a robot part: Baxter joints (n, 7) rad
        through Baxter's forward kinematics to :data:`~sandbox.robot.TIP_LINK`, or
        positions (n, 3) m as they are."""
        part = np.asarray(robot_part, dtype=float)
        if part.ndim != 2 or part.shape[1] not in (3, 7):
            raise ValueError(f"robot_part: expected Baxter joints (n, 7) rad or task-space "
                             f"positions (n, 3) m, got shape {part.shape}")
        part = check_array(part, "robot_part", 2)
        return part if part.shape[1] == 3 else self._baxter.fk(part, link=TIP_LINK)

    def tip(self, q: ArrayLike) -> FloatArray:
        """World position (..., 3) m of the arm's tip at joints ``q`` (..., dof) rad."""
        local = self.kinematics.fk(q, link=self.kinematics.tip_link)
        return local @ self.base[:3, :3].T + self.base[:3, 3]

    def solve(self, points: ArrayLike, q_seed: ArrayLike) -> Retargeted:
        """IK of world ``points`` (n, 3) m, all from ``q_seed`` (dof,) or (n, dof) rad."""
        points = check_array(points, "points", 2, shape=(None, 3))
        local = points @ self._inverse[:3, :3].T + self._inverse[:3, 3]
        result = self.kinematics.ik(local, q_seed=q_seed, tol=self.tol)
        return Retargeted(result.q, points, result.error, result.success)

    def plan(self, times: ArrayLike, robot_part: ArrayLike,
             q_start: ArrayLike | None = None) -> Retargeted:
        """A whole plan for the arm, point after point, within joint and speed limits.

        Parameters
        ----------
        times : array_like, shape (n,)
            Increasing knot times (s).
        robot_part : array_like, shape (n, 7) or (n, 3)
            Baxter joints (rad) or task-space positions (m, world).
        q_start : array_like, shape (dof,), optional
            Configuration at ``times[0]`` (default the arm's home).

        Returns
        -------
        Retargeted
        """
        t = check_times(times, "times")
        points = self.task_points(robot_part)
        if len(points) != t.size:
            raise ValueError(f"robot_part: expected {t.size} rows (one per time), "
                             f"got {len(points)}")
        q = np.array(self.kinematics.spec.q_home if q_start is None else q_start, dtype=float)
        q = check_array(q, "q_start", 1, shape=(self.dof,))
        out = np.empty((t.size, self.dof))
        previous_t = t[0]
        for i, point in enumerate(points):
            goal = self.solve(point[None], q).q[0]
            step = self.max_velocity * (t[i] - previous_t)
            q = q + np.clip(goal - q, -step, step) if i else goal
            out[i], previous_t = q, t[i]
        error = np.linalg.norm(self.tip(out) - points, axis=1)
        return Retargeted(out, points, error, error <= self.tol)


def reachability(robot: str, points: ArrayLike, tol: float = IK_TOL) -> float:
    """Fraction of world ``points`` (n, 3) m that ``robot``'s tip reaches within ``tol`` m
    (IK from its home configuration, with restarts)."""
    arm = Retargeter(robot, tol)
    return float(arm.solve(points, arm.kinematics.spec.q_home).reached.mean())


def check_reach(robot: str, points: ArrayLike, what: str = "training meeting points",
                tol: float = IK_TOL) -> float:
    """:func:`reachability` of ``points``; a ``UserWarning`` below :data:`REACH_WARNING`."""
    fraction = reachability(robot, points, tol)
    if fraction < REACH_WARNING:
        warnings.warn(f"robot {robot}: reaches {fraction:.2f} of the {what} (below "
                      f"{REACH_WARNING}); episodes meeting elsewhere end 'unreachable'",
                      UserWarning, stacklevel=2)
    return fraction

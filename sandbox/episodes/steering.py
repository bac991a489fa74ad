"""From a policy's goal to an action, for any arm: the speed limit, retargeting, the gripper.

A policy's model plans Baxter's seven left-arm joints (rad) or, fitted in task
space, a position (m, Baxter's ``base`` frame = the world). The arm that acts
is Baxter (``robot="baxter"``, the default) or another arm of
:mod:`sandbox.robot.arms`:

* Baxter with a joint-space model: the goal is the joint target, as ever;
* any other case: the goal is **retargeted** (:mod:`sandbox.robot.retarget`):
  taken to task space (Baxter's fingertip by forward kinematics, or the
  task-space position as it is) and solved by the arm's inverse kinematics,
  seeded with the previous target, within its joint limits. The blended
  command of the predictor is retargeted at each control step, so the plans
  are blended as before (in the model's space) and the arm follows the blend.
  A Baxter joint-space model used with another arm says so
  (``Steering.retargeted``).

Then, for every arm, the target moves from the previous one by at most
``max_velocity * dt`` per joint (the URDF's speed limits) and the gripper closes
when the arm's fingertip (forward kinematics of the observed joints) is within
``close_radius`` of the object. Baxter's fingers close in one physics step (5 m/s);
the others take ``Steering.close_lead`` seconds to half close (Panda and the
UR5's simple gripper 0.1 s, the Kinova 0.4 s), so for them the gripper also closes
when the fingertip-to-object gap, extrapolated from its last change over that
time, would be within ``close_radius``: they close as they arrive, not after. A goal
the arm cannot reach (IK error above
:data:`~sandbox.robot.retarget.IK_TOL`) sets ``Steering.unreachable``: the
arm goes to its closest configuration and the episode runners report the
outcome ``"unreachable"`` when the episode ends without a handover.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from sandbox.robot import TIP_LINK, joint_speed_limits
from sandbox.robot.arms import arm_spec
from sandbox.validation import check_array, check_positive

FloatArray = NDArray[np.float64]


class Steering:
    """A goal to an action (dof + 1,): speed-limited target, retargeting and the gripper rule.

    Attributes
    ----------
    robot : str
        The arm acting (:data:`sandbox.robot.arms.ROBOTS`).
    dof : int
        Its number of joints (the action has ``dof + 1`` entries).
    retargeted : bool
        A Baxter joint-space model drives another arm (through task space).
    unreachable : bool
        The latest goal was out of the arm's reach.
    """

    _target: FloatArray | None

    def _setup_steering(self, control_hz: float, close_radius: float, max_velocity,
                        robot: str = "baxter", task_space: bool = False) -> None:
        from sandbox.robot import BaxterKinematics

        spec = arm_spec(robot)
        self.robot, self.dof = robot, spec.dof
        self.dt = 1.0 / check_positive(control_hz, "control_hz")
        self.close_radius = check_positive(close_radius, "close_radius")
        self.retarget = None
        if robot != "baxter" or task_space:
            from sandbox.robot.retarget import Retargeter

            self.retarget = Retargeter(robot)
        if max_velocity is None:
            max_velocity = (joint_speed_limits() if self.retarget is None
                            else self.retarget.max_velocity)
        self.max_velocity = check_array(max_velocity, "max_velocity", 1, shape=(self.dof,))
        check_positive(float(self.max_velocity.min()), "max_velocity")
        self.kinematics = BaxterKinematics()
        self.retargeted = robot != "baxter" and not task_space
        self.unreachable = False
        self.close_lead = 0.0 if robot == "baxter" else _half_closing_time(robot)
        self._gap: FloatArray | None = None

    def _check_q(self, obs: Mapping[str, FloatArray]) -> FloatArray:
        """The observed joints ``obs["q"]`` (dof,) rad."""
        return check_array(obs["q"], "obs['q']", 1, shape=(self.dof,))

    def _act(self, q: FloatArray, goal: FloatArray, obs: Mapping[str, FloatArray]) -> FloatArray:
        """Action (dof + 1,): ``goal`` (the model's: 7 Baxter joints rad, or a position m)
        approached at most ``max_velocity * dt`` from the previous target (from ``q`` at
        first); the gripper closed near the object."""
        if self._target is None:
            self._gap = None                          # a new episode
        previous = q if self._target is None else self._target
        if self.retarget is not None:
            goal = self._arm_goal(goal, previous)
        step = self.max_velocity * self.dt
        self._target = previous + np.clip(goal - previous, -step, step)
        if self.retarget is None:
            tip = self.kinematics.fk(q, link=TIP_LINK)
        else:
            tip = self.retarget.tip(q)
        gap = np.asarray(obs["object"], dtype=float) - tip
        close = bool(np.linalg.norm(gap) < self.close_radius)
        if self.close_lead > 0.0 and self._gap is not None:   # a slower gripper than Baxter's
            ahead = gap + (gap - self._gap) / self.dt * self.close_lead
            close = close or bool(np.linalg.norm(ahead) < self.close_radius)
        self._gap = gap
        return np.append(self._target, 1.0 if close else -1.0)

    def _arm_goal(self, goal: FloatArray, seed: FloatArray) -> FloatArray:
        """The arm's joints (dof,) rad for a model goal, by IK seeded at ``seed``."""
        assert self.retarget is not None
        point = self.retarget.task_points(np.asarray(goal, dtype=float)[None])
        solved = self.retarget.solve(point, seed)
        self.unreachable = not bool(solved.reached[0])
        return solved.q[0]


def _half_closing_time(robot: str) -> float:
    """Time (s) the arm's fingers take from open to half closed, at their URDF speed limit."""
    from sandbox.robot.arm_files import arm_urdf_path
    from sandbox.robot.urdf import read_joints

    spec = arm_spec(robot)
    speed = {j.name: j.velocity for j in read_joints(arm_urdf_path(robot)).values()}
    return max(abs(o - c) / 2.0 / speed[f] for f, o, c in
               zip(spec.fingers, spec.finger_open, spec.finger_closed, strict=True))


def meeting_points(model, rng: np.random.Generator, draws: int = 20) -> FloatArray:
    """The model's meeting points (n, 3) m, world: where each task's robot plan ends.

    Per task, the end (phase 1) of the prior mean robot trajectory and of ``draws``
    trajectories drawn from the task's weight distribution, taken to task space
    (Baxter's fingertip for a joint-space model, the position for a task-space one).
    """
    from sandbox.core.promp import trajectory_distribution
    from sandbox.robot.retarget import Retargeter

    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    ends = []
    for task in model.task_models:
        mean, cov = trajectory_distribution(task.weights, model.basis, np.array([1.0]))
        robot = slice(model.n_human, model.n_human + model.n_robot)
        mu, sigma = mean[0, robot], cov[0, robot, robot]
        ends += [mu, *rng.multivariate_normal(mu, sigma, size=draws, method="eigh")]
    return Retargeter("baxter").task_points(np.array(ends))


def reach_report(model, robot: str) -> tuple[float, str | None]:
    """Fraction of ``model``'s meeting points (:func:`meeting_points`, seed 0) that ``robot``
    reaches (a ``UserWarning`` below :data:`~sandbox.robot.retarget.REACH_WARNING`), and a
    note when a Baxter joint-space model is retargeted to another arm (None otherwise)."""
    from sandbox.robot.retarget import check_reach

    fraction = check_reach(robot, meeting_points(model, np.random.default_rng(0)))
    note = None
    if robot != "baxter" and getattr(model, "robot_space", "joint") == "joint":
        note = (f"robot {robot}: the model plans Baxter's joints; its plans are retargeted "
                f"(Baxter's fingertip path through the {robot}'s inverse kinematics)")
    return fraction, note

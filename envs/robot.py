"""The robot in the environment: an arm under position control and its gripper.

Any arm of :mod:`sandbox.robot.arms` (:class:`RobotArm`; :class:`BaxterArm` is
Baxter's). Reaches PyBullet only through :class:`~sandbox.envs.pybullet.Simulation`.
Baxter's right arm and head are held at the recorded posture; the arm starts at
its home configuration with the gripper open.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.envs.pybullet import Simulation
from sandbox.robot.arms import arm_spec

FloatArray = NDArray[np.float64]

#: Right-arm posture of the recordings (rad; constant during every recorded trial).
Q_RIGHT = np.array([-0.285, -1.031, 0.907, 1.601, -0.482, 1.124, -0.208])
RIGHT_JOINTS = ("right_s0", "right_s1", "right_e0", "right_e1", "right_w0", "right_w1",
                "right_w2")
#: Opening below which the gripper counts as closed (fraction of its travel).
CLOSED_BELOW = 0.5


class RobotArm:
    """An arm of :mod:`sandbox.robot.arms` and its gripper, position-controlled.

    Parameters
    ----------
    sim : Simulation
        Where to load the arm (as body ``robot``, e.g. ``"baxter"``), at its world pose.
    robot : str
        A name of :data:`sandbox.robot.arms.ROBOTS` (default ``"baxter"``).

    Attributes
    ----------
    spec : ArmSpec
        The arm's description (joints, tip link, home, base pose, fingers).
    lower, upper : ndarray, shape (dof,)
        Arm joint limits (rad).
    max_velocity : ndarray, shape (dof,)
        Joint speed limits (rad/s) from the URDF (Baxter: 1.5 for shoulder and elbow,
        4.0 for the wrist); the motors never exceed them.
    max_force : ndarray, shape (dof,)
        Joint effort limits (N m) from the URDF.
    """

    def __init__(self, sim: Simulation, robot: str = "baxter") -> None:
        self.spec = arm_spec(robot)
        self.name = robot
        self.sim = sim
        self.baxter = sim.load_robot(self.name, robot)
        self.lower, self.upper = self.baxter.lower.copy(), self.baxter.upper.copy()
        self.max_force, self.max_velocity = sim.joint_limits(self.name, self.baxter.arm)
        self._finger_force, self._finger_speed = sim.joint_limits(self.name,
                                                                  self.baxter.fingers)
        self._finger_travel = self.baxter.limits[self.spec.fingers[0]][1]
        if robot == "baxter":          # mirrored fingers, travel from the URDF
            self._open = np.array([self._finger_travel, -self._finger_travel])
        else:
            self._open = np.array(self.spec.finger_open)
        self._closed = np.array(self.spec.finger_closed, dtype=float)
        self.tip_link = self.baxter.links[self.spec.tip_link]
        self._held = self._held_joints()
        # what every step sends and reads, as PyBullet takes it (Python floats, one list)
        self._arm_limits = (self.max_force.tolist(), self.max_velocity.tolist())
        self._finger_commands = {close: (self._closed if close else self._open).tolist()
                                 for close in (False, True)}
        self._finger_limits = (self._finger_force.tolist(), self._finger_speed.tolist())
        self._state_joints, self._dof = [*self.baxter.arm, *self.baxter.fingers], self.spec.dof
        self._arm_joints, self._finger_joints = list(self.baxter.arm), list(self.baxter.fingers)
        #: The gripper command the motors hold (None: unknown, sent at the next act()).
        self._gripper_sent: bool | None = None
        #: Whether the motors hold the speed limits (sent with the first command after reset;
        #: later commands go in one array call, which carries none: the motors keep them).
        self._limits_sent = False

    @property
    def dof(self) -> int:
        """Number of arm joints."""
        return self.spec.dof

    def _held_joints(self) -> tuple[list[int], FloatArray]:
        """Joints outside the arm and gripper, with the posture they are held at."""
        joints = self.baxter.joints
        held = dict(self.spec.held)
        for name in self.baxter.limits:
            if name not in held and joints[name] not in (*self.baxter.arm, *self.baxter.fingers):
                held[name] = 0.0
        return [joints[n] for n in held], np.array(list(held.values()))

    def reset(self, q: ArrayLike | None = None) -> None:
        """Teleport the arm to ``q`` (dof,) rad (default home) at rest, gripper open; motors
        hold it there."""
        q = np.clip(np.asarray(self.spec.q_home if q is None else q, dtype=float), self.lower,
                    self.upper)
        joints, posture = self._held
        if joints:
            self.sim.reset_joints(self.name, joints, posture)
            self.sim.control_joints(self.name, joints, posture, np.full(len(joints), 100.0),
                                    np.full(len(joints), 1.0))
        self.sim.reset_joints(self.name, self.baxter.arm, q)
        self.sim.reset_joints(self.name, self.baxter.fingers, self._open)
        self._gripper_sent, self._limits_sent = None, False
        self.act(q, close=False)

    def act(self, q_target: ArrayLike, close: bool) -> None:
        """Command joint targets ``q_target`` (dof,) rad (clipped to limits) and the gripper.

        The motors keep a command until the next one: the gripper's is sent only when it
        changes (and at every :meth:`reset`). The speed limits go with the first command
        after :meth:`reset` (one PyBullet call per joint); the motors keep them, so later
        commands go in one array call
        (:meth:`~sandbox.envs.pybullet.Simulation.retarget_joints`), the same motion.
        """
        q_target = np.minimum(np.maximum(np.asarray(q_target, dtype=float), self.lower),
                              self.upper)                  # np.clip, without its wrapper
        self.command(q_target.tolist(), close)

    def command(self, q_target: list[float], close: bool) -> None:
        """:meth:`act` with targets already within the joint limits, as a list of dof floats
        (rad): what the environment's step sends (it clipped the action itself)."""
        sim, name = self.sim, self.name
        if self._limits_sent:
            sim.retarget_joints(name, self._arm_joints, q_target, self._arm_limits[0])
        else:
            sim.control_joints(name, self._arm_joints, q_target, *self._arm_limits)
        close = bool(close)
        if close is not self._gripper_sent:
            if self._limits_sent:
                sim.retarget_joints(name, self._finger_joints, self._finger_commands[close],
                                    self._finger_limits[0])
            else:
                sim.control_joints(name, self._finger_joints, self._finger_commands[close],
                                   *self._finger_limits)
            self._gripper_sent = close
        self._limits_sent = True

    def joint_state(self) -> tuple[FloatArray, FloatArray]:
        """Arm joint positions (dof,) rad and velocities (dof,) rad/s."""
        return self.sim.joint_states(self.name, self.baxter.arm)

    def state(self) -> tuple[FloatArray, FloatArray, float]:
        """:meth:`joint_state` and :meth:`gripper_opening` read at once (one PyBullet call):
        positions (dof,) rad, velocities (dof,) rad/s, opening in [0, 1]."""
        q, dq, opening = self.read()
        return np.array(q), np.array(dq), opening

    def read(self) -> tuple[list[float], list[float], float]:
        """:meth:`state` as Python floats (what the environment's step reads): positions
        (dof,) rad and velocities (dof,) rad/s as lists, the opening in [0, 1]."""
        q, dq = self.sim.joint_states_floats(self.name, self._state_joints)
        dof = self._dof
        return q[:dof], dq[:dof], self._opening(q[dof:])

    def gripper_opening(self) -> float:
        """Finger opening in [0, 1]: 0 closed, 1 fully open (mean of both fingers)."""
        q, _ = self.sim.joint_states(self.name, self.baxter.fingers)
        return self._opening(q)

    def _opening(self, q: FloatArray | list[float]) -> float:
        """The opening in [0, 1] of finger positions ``q`` (2,) (rad or m)."""
        if self.name == "baxter":         # in floats: the same arithmetic as on float64
            opening = 0.5 * (float(q[0]) - float(q[1])) / self._finger_travel
        else:
            opening = float(np.mean((np.asarray(q, dtype=float) - self._closed)
                                    / (self._open - self._closed)))
        return min(max(float(opening), 0.0), 1.0)

    def gripper_closed(self) -> bool:
        """Whether the fingers have closed past :data:`CLOSED_BELOW` of their travel."""
        return self.gripper_opening() < CLOSED_BELOW

    def tip_position(self) -> FloatArray:
        """World position (3,) m of the gripper's fingertip point (the arm's tip link)."""
        return self.sim.link_position(self.name, self.tip_link)


class BaxterArm(RobotArm):
    """Baxter's left arm and gripper, position-controlled: :class:`RobotArm` of ``"baxter"``.

    Parameters
    ----------
    sim : Simulation
        Where to load Baxter (as body ``"baxter"``).
    """

    def __init__(self, sim: Simulation) -> None:
        super().__init__(sim, "baxter")

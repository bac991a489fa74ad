"""Baxter in the environment: the left arm under position control and its gripper.

Reaches PyBullet only through :class:`~sandbox.envs.pybullet.Simulation`. The
right arm and the head are held at the recorded posture; the left arm starts
at the recorded home configuration with the gripper open.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.envs.pybullet import Simulation
from sandbox.robot import Q_HOME, TIP_LINK

FloatArray = NDArray[np.float64]

#: Right-arm posture of the recordings (rad; constant during every recorded trial).
Q_RIGHT = np.array([-0.285, -1.031, 0.907, 1.601, -0.482, 1.124, -0.208])
RIGHT_JOINTS = ("right_s0", "right_s1", "right_e0", "right_e1", "right_w0", "right_w1",
                "right_w2")
#: Opening below which the gripper counts as closed (fraction of its travel).
CLOSED_BELOW = 0.5


class BaxterArm:
    """Baxter's left arm and gripper, position-controlled.

    Parameters
    ----------
    sim : Simulation
        Where to load Baxter (as body ``"baxter"``).

    Attributes
    ----------
    lower, upper : ndarray, shape (7,)
        Left-arm joint limits (rad).
    max_velocity : ndarray, shape (7,)
        Joint speed limits (rad/s) from the URDF (1.5 for shoulder and elbow,
        4.0 for the wrist); the motors never exceed them.
    max_force : ndarray, shape (7,)
        Joint effort limits (N m) from the URDF.
    """

    name = "baxter"

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.baxter = sim.load_baxter(self.name)
        self.lower, self.upper = self.baxter.lower.copy(), self.baxter.upper.copy()
        self.max_force, self.max_velocity = sim.joint_limits(self.name, self.baxter.arm)
        self._finger_force, self._finger_speed = sim.joint_limits(self.name,
                                                                  self.baxter.fingers)
        self._finger_travel = self.baxter.limits["l_gripper_l_finger_joint"][1]
        self.tip_link = self.baxter.links[TIP_LINK]
        self._held = self._held_joints()

    def _held_joints(self) -> tuple[list[int], FloatArray]:
        """Joints outside the left arm and gripper, with the posture they are held at."""
        joints = self.baxter.joints
        held = {n: q for n, q in zip(RIGHT_JOINTS, Q_RIGHT, strict=True)}
        for name in self.baxter.limits:
            if name not in held and joints[name] not in (*self.baxter.arm, *self.baxter.fingers):
                held[name] = 0.0
        return [joints[n] for n in held], np.array(list(held.values()))

    def reset(self, q: ArrayLike = Q_HOME) -> None:
        """Teleport the arm to ``q`` (7,) rad at rest, gripper open; motors hold it there."""
        q = np.clip(np.asarray(q, dtype=float), self.lower, self.upper)
        joints, posture = self._held
        self.sim.reset_joints(self.name, joints, posture)
        self.sim.control_joints(self.name, joints, posture, np.full(len(joints), 100.0),
                                np.full(len(joints), 1.0))
        self.sim.reset_joints(self.name, self.baxter.arm, q)
        self.sim.reset_joints(self.name, self.baxter.fingers,
                              [self._finger_travel, -self._finger_travel])
        self.act(q, close=False)

    def act(self, q_target: ArrayLike, close: bool) -> None:
        """Command joint targets ``q_target`` (7,) rad (clipped to limits) and the gripper."""
        q_target = np.clip(np.asarray(q_target, dtype=float), self.lower, self.upper)
        self.sim.control_joints(self.name, self.baxter.arm, q_target, self.max_force,
                                self.max_velocity)
        travel = 0.0 if close else self._finger_travel
        self.sim.control_joints(self.name, self.baxter.fingers, [travel, -travel],
                                self._finger_force, self._finger_speed)

    def joint_state(self) -> tuple[FloatArray, FloatArray]:
        """Arm joint positions (7,) rad and velocities (7,) rad/s."""
        return self.sim.joint_states(self.name, self.baxter.arm)

    def gripper_opening(self) -> float:
        """Finger opening in [0, 1]: 0 closed, 1 fully open (mean of both fingers)."""
        q, _ = self.sim.joint_states(self.name, self.baxter.fingers)
        opening = 0.5 * (q[0] - q[1]) / self._finger_travel
        return float(np.clip(opening, 0.0, 1.0))

    def gripper_closed(self) -> bool:
        """Whether the fingers have closed past :data:`CLOSED_BELOW` of their travel."""
        return self.gripper_opening() < CLOSED_BELOW

    def tip_position(self) -> FloatArray:
        """World position (3,) m of the gripper's fingertip point (:data:`TIP_LINK`)."""
        return self.sim.link_position(self.name, self.tip_link)

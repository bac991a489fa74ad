"""The robots the sandbox drives: one description per arm, Baxter's beside the others.

Every arm comes from the installed ``example-robot-data`` (nothing is
downloaded, nothing is copied into the repository): its URDF, meshes, joint
limits, speed limits and inertias are read from there. What the URDF does not
say is stated here, once per robot: the arm joints driven (in the order of
``q``), the tip link placed at the handover, the home configuration, the
gripper's finger joints and where the arm's base stands in the world.

The world is Baxter's ``base`` frame (the frame of the recordings and of every
human motion): x forward, y left, z up, the floor at
:data:`~sandbox.robot.FLOOR_Z`. Baxter stands at its origin; each other arm
stands on a pedestal in front-left of it, where the demonstrations' meeting
points fall within its reach (see :mod:`sandbox.robot.retarget`, which checks
that the arm reaches at least 95 % of them).

========  =========================  ======  ======================================
name      URDF (example-robot-data)  joints  gripper
========  =========================  ======  ======================================
baxter    baxter_description         7       Rethink electric gripper (left arm)
panda     panda_description/panda    7       Franka hand, two prismatic fingers
ur5       ur_description/ur5_robot   6       none in the package: a simple
                                             two-finger gripper is added
                                             (:data:`SIMPLE_GRIPPER`)
kinova    kinova_description         6       Kinova 2-finger hand (j2s6s200); the
                                             package makes its fingers fixed, the
                                             sandbox makes them revolute to close
========  =========================  ======  ======================================

Examples
--------
>>> from sandbox.robot.arms import arm_spec
>>> arm_spec("panda").tip_link, len(arm_spec("ur5").joints)
('panda_hand_tcp', 6)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sandbox.robot.facts import ARM_JOINTS, FLOOR_Z, Q_HOME, TIP_LINK

FloatArray = NDArray[np.float64]

#: The simple two-finger gripper given to an arm whose package has none (the UR5): a
#: 8 x 4 x 2 cm palm on the flange link, two 1.5 x 1 x 6 cm fingers sliding 0 .. 4 cm
#: apart from the middle (prismatic, 0.2 m/s, 40 N), and a fingertip point ``sandbox_tip``
#: 9 cm from the flange, between the fingertips. Written into the arm's cached URDF.
SIMPLE_GRIPPER = """
  <link name="sandbox_palm">
    <visual><origin xyz="0 0 0.01"/><geometry><box size="0.04 0.08 0.02"/></geometry>
      <material name="sandbox_grey"><color rgba="0.3 0.3 0.3 1"/></material></visual>
    <inertial><mass value="0.2"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0"
      izz="1e-4"/></inertial>
  </link>
  <joint name="sandbox_palm_joint" type="fixed">
    <parent link="{flange}"/><child link="sandbox_palm"/><origin xyz="0 0 0" rpy="{rpy}"/>
  </joint>
  <link name="sandbox_finger_left">
    <visual><origin xyz="0 0.005 0.03"/><geometry><box size="0.015 0.01 0.06"/></geometry>
      <material name="sandbox_grey"/></visual>
    <collision><origin xyz="0 0.005 0.03"/><geometry><box size="0.015 0.01 0.06"/></geometry>
      </collision>
    <inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0"
      izz="1e-5"/></inertial>
  </link>
  <joint name="sandbox_finger_left_joint" type="prismatic">
    <parent link="sandbox_palm"/><child link="sandbox_finger_left"/>
    <origin xyz="0 0 0.02"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" velocity="0.2" effort="40"/>
  </joint>
  <link name="sandbox_finger_right">
    <visual><origin xyz="0 -0.005 0.03"/><geometry><box size="0.015 0.01 0.06"/></geometry>
      <material name="sandbox_grey"/></visual>
    <collision><origin xyz="0 -0.005 0.03"/><geometry><box size="0.015 0.01 0.06"/></geometry>
      </collision>
    <inertial><mass value="0.05"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0"
      izz="1e-5"/></inertial>
  </link>
  <joint name="sandbox_finger_right_joint" type="prismatic">
    <parent link="sandbox_palm"/><child link="sandbox_finger_right"/>
    <origin xyz="0 0 0.02"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="0.04" velocity="0.2" effort="40"/>
  </joint>
  <link name="sandbox_tip"/>
  <joint name="sandbox_tip_joint" type="fixed">
    <parent link="sandbox_palm"/><child link="sandbox_tip"/><origin xyz="0 0 0.09"/>
  </joint>
"""


def _readonly(values) -> FloatArray:
    out = np.array(values, dtype=np.float64)
    out.flags.writeable = False
    return out


def _base_pose(position, yaw: float = 0.0) -> FloatArray:
    pose = np.eye(4)
    c, s = np.cos(yaw), np.sin(yaw)
    pose[:2, :2] = [[c, -s], [s, c]]
    pose[:3, 3] = position
    return _readonly(pose)


@dataclass(frozen=True)
class ArmSpec:
    """What the sandbox needs to know about one arm beyond its URDF.

    Attributes
    ----------
    name : str
        Registry name (``"baxter"``, ``"panda"``, ``"ur5"``, ``"kinova"``).
    title : str
        Human-readable name.
    urdf : str
        URDF path inside ``example-robot-data``'s ``robots/`` folder.
    joints : tuple of str
        The driven arm joints (revolute), in the order of ``q``; ``dof = len(joints)``.
    tip_link : str
        The link placed at the handover point (the gripper's fingertip point).
    q_home : ndarray, shape (dof,)
        Home configuration (rad), read-only: every episode starts there.
    base : ndarray, shape (4, 4)
        Pose of the URDF's root link in the world (Baxter's ``base`` frame, m), read-only.
    fingers : tuple of str
        The gripper's finger joints.
    finger_open, finger_closed : tuple of float
        Each finger joint's open and closed position (m or rad).
    gripper_added : bool
        The package ships no gripper for this arm: :data:`SIMPLE_GRIPPER` is added.
    revolute_fingers : tuple of str
        Finger joints the package declares ``fixed`` that the sandbox makes revolute.
    held : tuple of (str, float)
        Other joints held at a posture (rad), e.g. Baxter's right arm (rest at 0).
    """

    name: str
    title: str
    urdf: str
    joints: tuple[str, ...]
    tip_link: str
    q_home: FloatArray
    base: FloatArray
    fingers: tuple[str, ...]
    finger_open: tuple[float, ...]
    finger_closed: tuple[float, ...]
    gripper_added: bool = False
    revolute_fingers: tuple[str, ...] = ()
    held: tuple[tuple[str, float], ...] = ()

    @property
    def dof(self) -> int:
        """Number of arm joints (the length of ``q``)."""
        return len(self.joints)


#: Baxter's right-arm posture of the recordings (rad; constant in every recorded trial).
BAXTER_RIGHT = (("right_s0", -0.285), ("right_s1", -1.031), ("right_e0", 0.907),
                ("right_e1", 1.601), ("right_w0", -0.482), ("right_w1", 1.124),
                ("right_w2", -0.208))

#: Where the Panda, the UR5 and the Kinova stand (world pose of the URDF's root link): on a
#: pedestal at the table's height (0.74 m above the floor), 0.25 m behind the table's near
#: edge, facing +x like Baxter. From there the meeting points of the synthetic demos and
#: of the recorded set (x 0.63 .. 0.98 m, y -0.05 .. 0.38 m, z -0.06 .. 0.49 m in the
#: world) lie 0.35 .. 0.75 m from the shoulder, within each arm's reach
#: (:func:`sandbox.robot.retarget.reachability`: all of them; the tests hold it >= 0.95).
PEDESTAL = _base_pose((0.3, 0.2, FLOOR_Z + 0.74))

#: Every arm, by name. The other arms' home configurations put their tip within 5 mm of
#: Baxter's home fingertip point (where every demonstration starts), the gripper pointing
#: down (damped least squares from a nominal posture, rounded to 0.01 rad).
ARMS: dict[str, ArmSpec] = {
    "baxter": ArmSpec(
        "baxter", "Rethink Baxter (left arm)", "baxter_description/urdf/baxter.urdf",
        ARM_JOINTS, TIP_LINK, Q_HOME, _base_pose((0.0, 0.0, 0.0)),
        ("l_gripper_l_finger_joint", "l_gripper_r_finger_joint"), (0.020833, -0.020833),
        (0.0, 0.0), held=BAXTER_RIGHT),
    "panda": ArmSpec(
        "panda", "Franka Emika Panda with its hand", "panda_description/urdf/panda.urdf",
        tuple(f"panda_joint{i}" for i in range(1, 8)), "panda_hand_tcp",
        _readonly([0.24, -0.31, 0.23, -2.32, 0.09, 1.9, 0.78]), PEDESTAL,
        ("panda_finger_joint1", "panda_finger_joint2"), (0.04, 0.04), (0.0, 0.0)),
    "ur5": ArmSpec(
        "ur5", "Universal Robots UR5 (simple two-finger gripper)",
        "ur_description/urdf/ur5_robot.urdf",
        ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
         "wrist_2_joint", "wrist_3_joint"), "sandbox_tip",
        _readonly([0.23, -1.76, 1.75, -1.61, -1.53, 0.0]), PEDESTAL,
        ("sandbox_finger_left_joint", "sandbox_finger_right_joint"), (0.04, 0.04), (0.0, 0.0),
        gripper_added=True),
    "kinova": ArmSpec(
        "kinova", "Kinova Jaco 2 (j2s6s200, 2-finger hand)",
        "kinova_description/robots/kinova.urdf",
        tuple(f"j2s6s200_joint_{i}" for i in range(1, 7)), "j2s6s200_end_effector",
        _readonly([0.5, 2.28, 5.54, -1.26, 5.19, 0.05]), PEDESTAL,
        ("j2s6s200_joint_finger_1", "j2s6s200_joint_finger_2"), (0.0, 0.0), (0.8, 0.8),
        revolute_fingers=("j2s6s200_joint_finger_1", "j2s6s200_joint_finger_2")),
}
#: The registry's names, Baxter (the default) first.
ROBOTS = tuple(ARMS)


def arm_spec(name: str) -> ArmSpec:
    """The :class:`ArmSpec` of robot ``name``; ``ValueError`` (one line, listing the known
    ones) for any other name."""
    if not isinstance(name, str) or name not in ARMS:
        raise ValueError(f"robot: expected one of {', '.join(ROBOTS)}, got {name!r}")
    return ARMS[name]

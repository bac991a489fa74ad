"""Baxter's model: robot files, forward and inverse kinematics, PyBullet loading.

The model (URDF and meshes) comes from the installed PyPI package
``example-robot-data``; nothing is stored in this repository. This package
imports nothing else of the project but the neutral :mod:`sandbox.validation`:
the policies, the synthetic data, the environments and the viewer read
Baxter's facts here.

- :class:`BaxterKinematics`: batched forward kinematics and damped
  least-squares inverse kinematics of the left arm, pure numpy.
- :func:`urdf_path`: the URDF with absolute mesh paths (written to a per-user
  cache), for PyBullet and viewers; :func:`mesh_dir`: the DAE meshes;
  :func:`visuals`: each link's visual geometry (mesh file, pose in the link).
- Facts (:mod:`sandbox.robot.facts`): :data:`Q_HOME` the recorded home
  configuration of the left arm (:func:`q_home`: a writable copy),
  :data:`TIP_LINK` the gripper's fingertip link, :data:`GRASP_OFFSET` where it
  meets the hand, :data:`FLOOR_Z` the floor's height and
  :func:`joint_speed_limits` the arm's speed limits from the URDF.
- :mod:`sandbox.robot.bullet` (imports pybullet, so not imported here):
  :func:`~sandbox.robot.bullet.load_baxter` into a ``BulletClient``.

Notation: ``q`` (..., 7) left-arm joint angles (rad) in the order
:data:`ARM_JOINTS`; positions in Baxter's ``base`` frame (m); poses are 4x4
homogeneous matrices.
"""

from sandbox.robot.assets import mesh_dir, urdf_path, visuals
from sandbox.robot.facts import (
    ARM_JOINTS,
    FLOOR_Z,
    GRASP_OFFSET,
    Q_HOME,
    TIP_LINK,
    joint_speed_limits,
)
from sandbox.robot.ik import IKResult
from sandbox.robot.kinematics import BaxterKinematics, q_home

__all__ = [
    "ARM_JOINTS",
    "BaxterKinematics",
    "FLOOR_Z",
    "GRASP_OFFSET",
    "IKResult",
    "Q_HOME",
    "TIP_LINK",
    "joint_speed_limits",
    "mesh_dir",
    "q_home",
    "urdf_path",
    "visuals",
]

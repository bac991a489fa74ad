"""Baxter's model: robot files, forward and inverse kinematics, PyBullet loading.

The model (URDF and meshes) comes from the installed PyPI package
``example-robot-data``; nothing is stored in this repository.

- :class:`BaxterKinematics`: batched forward kinematics and damped
  least-squares inverse kinematics of the left arm, pure numpy.
- :func:`urdf_path`: the URDF with absolute mesh paths (written to a per-user
  cache), for PyBullet and viewers; :func:`mesh_dir`: the DAE meshes;
  :func:`visuals`: each link's visual geometry (mesh file, pose in the link).
- :func:`q_home`: the recorded home configuration of the left arm.
- :mod:`sandbox.robot.bullet` (imports pybullet, so not imported here):
  :func:`~sandbox.robot.bullet.load_baxter` into a ``BulletClient``.

Notation: ``q`` (..., 7) left-arm joint angles (rad) in the order
:data:`ARM_JOINTS`; positions in Baxter's ``base`` frame (m); poses are 4x4
homogeneous matrices.
"""

from sandbox.robot.assets import mesh_dir, urdf_path, visuals
from sandbox.robot.ik import IKResult
from sandbox.robot.kinematics import ARM_JOINTS, BaxterKinematics, q_home

__all__ = [
    "ARM_JOINTS",
    "BaxterKinematics",
    "IKResult",
    "mesh_dir",
    "q_home",
    "urdf_path",
    "visuals",
]

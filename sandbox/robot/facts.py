"""Baxter's facts the rest of the project uses, stated once.

- :data:`ARM_JOINTS`: the seven left-arm joints, in the order of ``q``.
- :data:`Q_HOME`: the left arm's home configuration in the recordings (rad).
- :data:`TIP_LINK`: the link placed at the handover point (the gripper's fingertip point).
- :data:`GRASP_OFFSET`: where that tip meets the tracked hand (m).
- :data:`FLOOR_Z`: the floor's height in Baxter's base frame (m).
- :func:`joint_speed_limits`: the arm joints' speed limits, read from the URDF.

Positions are in Baxter's ``base`` frame, in metres; angles in radians.

Examples
--------
>>> from sandbox.robot import ARM_JOINTS, Q_HOME, joint_speed_limits
>>> dict(zip(ARM_JOINTS, joint_speed_limits().tolist()))["left_w0"]
4.0
>>> Q_HOME.shape
(7,)
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from sandbox.robot.assets import source_urdf_path
from sandbox.robot.urdf import read_joints
from sandbox.validation import FloatArray


def _readonly(values: list[float]) -> FloatArray:
    out = np.array(values, dtype=np.float64)
    out.flags.writeable = False
    return out


#: The seven left-arm joints, in the order of ``q`` (and of the recordings' columns).
ARM_JOINTS = ("left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2")
#: Baxter's left-arm home configuration in the recordings (7,) rad, read-only: the
#: robot starts every synthetic demonstration and every episode there.
Q_HOME = _readonly([0.07, -0.89, -0.95, 1.45, 0.52, 1.29, -0.12])
#: The electric gripper's fingertip point (a URDF link, 0.1577 m along the wrist
#: flange's z): the point placed at the handover, and the one that grasps.
TIP_LINK = "left_gripper"
#: Median position (3,) m of the gripper tip relative to the hand's resting point in the
#: recordings (174 trials, forward kinematics of the final joints), read-only.
GRASP_OFFSET = _readonly([0.005, -0.010, -0.020])
#: Floor height in Baxter's base frame (m): the top of the floor the simulation loads.
FLOOR_Z = -0.926


def joint_speed_limits(urdf: str | Path | None = None) -> FloatArray:
    """Speed limits (7,) rad/s of :data:`ARM_JOINTS`: the URDF's ``<limit velocity>``.

    Parameters
    ----------
    urdf : str or pathlib.Path, optional
        A Baxter URDF; default the one of the installed ``example-robot-data``.

    Returns
    -------
    ndarray, shape (7,)
        A new array, in the order of ``q``.

    Raises
    ------
    ValueError
        If the URDF lacks an arm joint or its velocity limit.
    """
    path = Path(urdf) if urdf is not None else source_urdf_path()
    return np.array(_speed_limits(str(path.resolve())))


@functools.cache
def _speed_limits(path: str) -> FloatArray:
    by_name = {joint.name: joint for joint in read_joints(path).values()}
    missing = [n for n in ARM_JOINTS if n not in by_name or not np.isfinite(by_name[n].velocity)]
    if missing:
        raise ValueError(f"{path}: expected Baxter's left-arm joints with a velocity limit, "
                         f"missing {missing}")
    return _readonly([by_name[n].velocity for n in ARM_JOINTS])

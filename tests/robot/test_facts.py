"""Baxter's facts (sandbox/robot/facts.py) agree with the URDF, read here independently."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from sandbox.robot import (
    ARM_JOINTS,
    FLOOR_Z,
    GRASP_OFFSET,
    Q_HOME,
    TIP_LINK,
    BaxterKinematics,
    joint_speed_limits,
    q_home,
)
from sandbox.robot.assets import source_urdf_path


@pytest.fixture(scope="module")
def urdf() -> ET.Element:
    return ET.parse(source_urdf_path()).getroot()


def _limits(urdf: ET.Element) -> dict[str, dict[str, float]]:
    """``<limit>`` attributes of every joint with one, by joint name."""
    return {j.get("name"): {k: float(v) for k, v in j.find("limit").attrib.items()}
            for j in urdf.iter("joint") if j.find("limit") is not None}


def test_speed_limits_are_the_urdfs_limit_velocity(urdf):
    limits = _limits(urdf)
    expected = [limits[name]["velocity"] for name in ARM_JOINTS]
    np.testing.assert_array_equal(joint_speed_limits(), expected)
    # Regression: the values the policy hard-coded before they were read from the URDF.
    np.testing.assert_array_equal(joint_speed_limits(), [1.5, 1.5, 1.5, 1.5, 4.0, 4.0, 4.0])


def test_speed_limits_are_a_fresh_array_each_call():
    first = joint_speed_limits()
    first[:] = 0.0
    assert joint_speed_limits().min() > 0


def test_speed_limits_of_a_urdf_without_them_are_refused(tmp_path):
    joints = "".join(
        f'<joint name="{name}" type="revolute"><parent link="a{i}"/><child link="a{i + 1}"/>'
        f'<limit lower="-1" upper="1"/></joint>' for i, name in enumerate(ARM_JOINTS))
    path = tmp_path / "no_velocity.urdf"
    path.write_text(f'<robot name="r">{joints}</robot>')
    with pytest.raises(ValueError, match="velocity limit"):
        joint_speed_limits(path)


def test_home_pose_is_within_the_urdfs_joint_limits(urdf):
    limits = _limits(urdf)
    lower = np.array([limits[name]["lower"] for name in ARM_JOINTS])
    upper = np.array([limits[name]["upper"] for name in ARM_JOINTS])
    assert Q_HOME.shape == (7,)
    assert np.all((lower < Q_HOME) & (Q_HOME < upper))


def test_tip_link_is_a_link_of_the_urdf_moved_by_the_left_arm(urdf):
    assert TIP_LINK in {link.get("name") for link in urdf.iter("link")}
    assert TIP_LINK in BaxterKinematics().links


def test_shared_constants_are_read_only_and_q_home_gives_a_writable_copy():
    for constant in (Q_HOME, GRASP_OFFSET):
        with pytest.raises(ValueError):
            constant[0] = 1.0
    copy = q_home()
    copy[0] = 1.0
    np.testing.assert_array_equal(q_home(), Q_HOME)
    assert GRASP_OFFSET.shape == (3,) and np.linalg.norm(GRASP_OFFSET) < 0.05  # m, near the hand


def test_floor_is_below_the_pedestal_and_the_home_pose():
    kin = BaxterKinematics()
    assert -1.0 < FLOOR_Z < -0.9
    assert kin.fk(Q_HOME, link=TIP_LINK)[2] > FLOOR_Z + 0.5

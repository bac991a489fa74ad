"""The robot registry (issue 23 item 1): one description per arm, read from its URDF."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.robot import ARM_JOINTS, Q_HOME, TIP_LINK, BaxterKinematics, joint_speed_limits
from sandbox.robot.arm_files import arm_text, arm_urdf_path
from sandbox.robot.arms import ARMS, ROBOTS, arm_spec
from sandbox.robot.kinematics import ArmKinematics
from sandbox.robot.urdf import read_joints

#: Joint counts and tip links of the arms, from their makers' documentation.
EXPECTED = {"baxter": (7, "left_gripper"), "panda": (7, "panda_hand_tcp"),
            "ur5": (6, "sandbox_tip"), "kinova": (6, "j2s6s200_end_effector")}


def test_the_registry_names_four_arms_baxter_first():
    assert ROBOTS == ("baxter", "panda", "ur5", "kinova")
    for name, (dof, tip) in EXPECTED.items():
        spec = arm_spec(name)
        assert (spec.dof, spec.tip_link, spec.name) == (dof, tip, name)


@pytest.mark.parametrize("bad", ["Panda", "iiwa", "", None, 3])
def test_an_unknown_robot_is_a_one_line_error_listing_the_known_ones(bad):
    with pytest.raises(ValueError) as caught:
        arm_spec(bad)
    message = str(caught.value)
    assert "\n" not in message and message.startswith("robot: expected one of")
    assert all(name in message for name in ROBOTS)


def test_baxters_public_names_are_its_registry_entry():
    spec = arm_spec("baxter")
    assert spec.joints == ARM_JOINTS and spec.tip_link == TIP_LINK
    assert spec.q_home is Q_HOME and np.array_equal(spec.base, np.eye(4))
    assert isinstance(BaxterKinematics(), ArmKinematics)
    np.testing.assert_array_equal(ArmKinematics("baxter").max_velocity, joint_speed_limits())


@pytest.mark.parametrize("name", ROBOTS)
def test_limits_and_speed_limits_come_from_the_urdf(name):
    spec, kin = arm_spec(name), ArmKinematics(name)
    by_name = {j.name: j for j in read_joints(arm_urdf_path(name)).values()}
    for i, joint in enumerate(spec.joints):
        assert by_name[joint].type in ("revolute", "continuous")
        assert kin.lower[i] == by_name[joint].lower and kin.upper[i] == by_name[joint].upper
        assert kin.max_velocity[i] == by_name[joint].velocity > 0
    assert np.all(spec.q_home >= kin.lower) and np.all(spec.q_home <= kin.upper)
    assert not spec.q_home.flags.writeable and not spec.base.flags.writeable


@pytest.mark.parametrize("name", ROBOTS[1:])
def test_every_arm_starts_where_baxters_fingertip_starts(name):
    """The demos start at Baxter's home fingertip: the other arms' homes put their tip there."""
    baxter_tip = BaxterKinematics().fk(Q_HOME, link=TIP_LINK)
    spec = arm_spec(name)
    tip = ArmKinematics(name).fk(spec.q_home) @ spec.base[:3, :3].T + spec.base[:3, 3]
    assert np.linalg.norm(tip - baxter_tip) < 0.005


def test_the_ur5_gets_the_simple_gripper_and_the_kinova_closing_fingers():
    ur5 = {j.name: j for j in read_joints(arm_urdf_path("ur5")).values()}
    for finger in arm_spec("ur5").fingers:
        assert ur5[finger].type == "prismatic" and ur5[finger].parent == "sandbox_palm"
    assert ur5["sandbox_palm_joint"].parent == "tool0"
    kinova = {j.name: j for j in read_joints(arm_urdf_path("kinova")).values()}
    assert all(kinova[f].type == "revolute" for f in arm_spec("kinova").fingers)
    assert "package://" not in arm_text("panda") and "sandbox_palm" not in arm_text("panda")


def test_the_tip_of_the_simple_gripper_is_9_cm_beyond_the_flange():
    kin = ArmKinematics("ur5")
    q = arm_spec("ur5").q_home
    flange, tip = kin.fk_pose(q, link="tool0"), kin.fk(q)
    np.testing.assert_allclose(tip, flange[:3, 3] + 0.09 * flange[:3, 2], atol=1e-12)


def test_the_arm_kinematics_checks_q_against_its_own_joints():
    with pytest.raises(ValueError, match=r"q: expected joint angles of shape \(\.\.\., 6\)"):
        ArmKinematics("ur5").fk(np.zeros(7))
    with pytest.raises(ValueError, match="link"):
        ArmKinematics("panda").fk(np.zeros(7), link="left_gripper")
    assert set(ARMS) == set(ROBOTS)

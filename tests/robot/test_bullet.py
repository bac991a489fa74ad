"""Baxter in PyBullet, and the numpy FK cross-checked against PyBullet's link states."""

from __future__ import annotations

import numpy as np
import pybullet
import pytest
from pybullet_utils.bullet_client import BulletClient

from sandbox.robot import ARM_JOINTS, BaxterKinematics, q_home
from sandbox.robot.bullet import (
    FINGER_JOINTS,
    arm_positions,
    bullet_ik,
    link_pose,
    load_baxter,
    reset_arm,
    reset_gripper,
)


@pytest.fixture(scope="module")
def clients():
    """Two independent DIRECT clients, each with a Baxter (loading takes ~1.5 s each)."""
    made = [BulletClient(connection_mode=pybullet.DIRECT) for _ in range(2)]
    yield [(c, load_baxter(c)) for c in made]
    for c in made:
        c.disconnect()


@pytest.fixture(scope="module")
def baxter(clients):
    return clients[0][1]


def test_maps_and_limits(baxter):
    kin = BaxterKinematics()
    assert baxter.links["base"] == -1
    assert len(baxter.arm) == 7 and len(set(baxter.arm)) == 7
    for name, index in zip(ARM_JOINTS, baxter.arm, strict=True):
        assert baxter.joints[name] == index
        info = baxter.client.getJointInfo(baxter.body, index)
        assert info[1].decode() == name and info[2] == pybullet.JOINT_REVOLUTE
    assert baxter.fingers == tuple(baxter.joints[n] for n in FINGER_JOINTS)
    np.testing.assert_allclose(baxter.lower, kin.lower)
    np.testing.assert_allclose(baxter.upper, kin.upper)
    assert baxter.limits[FINGER_JOINTS[0]] == pytest.approx((0.0, 0.020833))
    assert {"left_hand_link", "left_gripper", "l_gripper_l_finger"} <= set(baxter.links)


def test_numpy_fk_matches_pybullet_link_states_to_a_micrometre(baxter):
    kin = BaxterKinematics()
    rng = np.random.default_rng(0)
    links = ("left_upper_elbow", "left_wrist", "left_hand_link", "left_gripper")
    for q in rng.uniform(kin.lower, kin.upper, size=(25, 7)):
        reset_arm(baxter, q)
        np.testing.assert_allclose(arm_positions(baxter), q, atol=1e-12)
        for link in links:
            pose = link_pose(baxter, link)
            np.testing.assert_allclose(pose[:3, 3], kin.fk(q, link=link), atol=1e-6)
            np.testing.assert_allclose(pose[:3, :3], kin.fk_pose(q, link=link)[:3, :3], atol=1e-6)


def test_two_clients_do_not_clash(clients):
    (c0, b0), (c1, b1) = clients
    assert c0._client != c1._client
    reset_arm(b0, q_home())
    reset_arm(b1, np.zeros(7))
    np.testing.assert_allclose(arm_positions(b0), q_home())
    np.testing.assert_allclose(arm_positions(b1), np.zeros(7))
    kin = BaxterKinematics()
    np.testing.assert_allclose(
        link_pose(b0, "left_gripper")[:3, 3], kin.fk(q_home(), "left_gripper"), atol=1e-6
    )
    np.testing.assert_allclose(
        link_pose(b1, "left_gripper")[:3, 3], kin.fk(np.zeros(7), "left_gripper"), atol=1e-6
    )


def test_gripper_fingers_mirror_each_other(baxter):
    reset_gripper(baxter, 1.0)
    left, right = (s[0] for s in baxter.client.getJointStates(baxter.body, baxter.fingers))
    assert left == pytest.approx(0.020833) and right == pytest.approx(-0.020833)
    reset_gripper(baxter, 0.0)
    gap_closed = np.linalg.norm(
        link_pose(baxter, "l_gripper_l_finger_tip")[:3, 3]
        - link_pose(baxter, "l_gripper_r_finger_tip")[:3, 3]
    )
    reset_gripper(baxter, 1.0)
    gap_open = np.linalg.norm(
        link_pose(baxter, "l_gripper_l_finger_tip")[:3, 3]
        - link_pose(baxter, "l_gripper_r_finger_tip")[:3, 3]
    )
    assert gap_open - gap_closed == pytest.approx(2 * 0.020833, abs=1e-6)
    with pytest.raises(ValueError, match="opening"):
        reset_gripper(baxter, 1.5)


def test_iterated_pybullet_ik_reaches_targets_and_restores_the_arm(baxter):
    kin = BaxterKinematics()
    rng = np.random.default_rng(1)
    q_true = np.clip(q_home() + rng.normal(0.0, 0.3, size=(10, 7)), kin.lower, kin.upper)
    reset_arm(baxter, np.zeros(7))
    reached = 0
    for target in kin.fk(q_true, link="left_gripper"):
        q, err = bullet_ik(baxter, target, q_home())
        assert np.all(q >= kin.lower) and np.all(q <= kin.upper)
        assert err == pytest.approx(
            np.linalg.norm(kin.fk(q, link="left_gripper") - target), abs=1e-6
        )
        reached += err <= 0.01
    assert reached >= 9
    np.testing.assert_allclose(arm_positions(baxter), np.zeros(7))


def test_bad_arguments_are_refused(baxter):
    with pytest.raises(ValueError, match="client"):
        load_baxter(pybullet)
    with pytest.raises(ValueError, match="q"):
        reset_arm(baxter, np.zeros(6))
    with pytest.raises(ValueError, match="link"):
        link_pose(baxter, "nope")
    with pytest.raises(ValueError, match="target"):
        bullet_ik(baxter, [np.nan, 0, 0], q_home())

"""Forward kinematics in numpy: properties, Jacobian, error paths, and the recordings.

The cross-check against PyBullet's link states is in ``test_bullet.py``.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from sandbox.robot import ARM_JOINTS, BaxterKinematics

GRIPPER_OFFSET_M = 0.025 + 0.1327  # URDF: left_gripper_base_joint + left_endpoint (constants)


@pytest.fixture(scope="module")
def kin() -> BaxterKinematics:
    return BaxterKinematics()


@pytest.fixture(scope="module")
def qs(kin) -> np.ndarray:
    return np.random.default_rng(0).uniform(kin.lower, kin.upper, size=(64, 7))


def test_api_attributes(kin):
    assert kin.joint_names == ARM_JOINTS
    assert kin.lower.shape == kin.upper.shape == (7,)
    assert np.all(kin.lower < kin.upper)
    assert {"left_hand_link", "left_gripper", "left_wrist"} <= set(kin.links)
    with pytest.raises(ValueError):
        kin.lower[0] = 0.0  # read-only


def test_construction_is_cached():
    assert BaxterKinematics()._model is BaxterKinematics()._model


def test_batch_shapes_match_single_evaluations(kin, qs):
    batch = qs[:6].reshape(2, 3, 7)
    poses = kin.fk_pose(batch, link="left_hand_link")
    assert poses.shape == (2, 3, 4, 4) and kin.fk(batch).shape == (2, 3, 3)
    for i in range(2):
        for j in range(3):
            np.testing.assert_allclose(poses[i, j], kin.fk_pose(batch[i, j], link="left_hand_link"))
    np.testing.assert_allclose(kin.fk(batch), poses[..., :3, 3])


def test_poses_are_rigid_transforms(kin, qs):
    pose = kin.fk_pose(qs)
    rot = pose[:, :3, :3]
    np.testing.assert_allclose(
        rot @ np.swapaxes(rot, 1, 2), np.broadcast_to(np.eye(3), rot.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-12)
    np.testing.assert_array_equal(pose[:, 3], np.broadcast_to([0, 0, 0, 1], (len(qs), 4)))


def test_gripper_point_is_157_mm_along_the_hand_z_axis(kin, qs):
    hand = kin.fk_pose(qs, link="left_hand_link")
    tip = kin.fk(qs, link="left_gripper")
    np.testing.assert_allclose(tip, hand[:, :3, 3] + GRIPPER_OFFSET_M * hand[:, :3, 2], atol=1e-12)


def test_first_joint_rotates_the_arm_about_a_vertical_axis_through_its_origin(kin):
    q = np.zeros((2, 7))
    q[1, 0] = 0.7
    p0, p1 = kin.fk(q, link="left_gripper")
    axis_point = kin.fk(q[0], link="left_upper_shoulder")  # child frame of left_s0
    assert p0[2] == pytest.approx(p1[2], abs=1e-12)  # s0 axis is vertical (mount has yaw only)
    assert np.linalg.norm((p0 - axis_point)[:2]) == pytest.approx(
        np.linalg.norm((p1 - axis_point)[:2])
    )


def test_jacobian_matches_finite_differences(kin, qs):
    q = qs[:5]
    jac = kin.jacobian(q, link="left_gripper")
    eps = 1e-6
    for i in range(7):
        dq = np.zeros(7)
        dq[i] = eps
        plus, minus = kin.fk_pose(q + dq), kin.fk_pose(q - dq)
        np.testing.assert_allclose(jac[:, :3, i], (plus - minus)[:, :3, 3] / (2 * eps), atol=1e-7)
        # Angular part: (dR/dq) R^T is the skew matrix of the angular velocity column.
        rot = kin.fk_pose(q)[:, :3, :3]
        skew = (plus - minus)[:, :3, :3] / (2 * eps) @ np.swapaxes(rot, 1, 2)
        omega = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], -1)
        np.testing.assert_allclose(jac[:, 3:, i], omega, atol=1e-7)


def test_link_poses_agree_with_fk_pose(kin, qs):
    poses = kin.link_poses(qs[:3])
    assert set(poses) == set(kin.links)
    for link in ("left_upper_elbow", "left_gripper", "base"):
        np.testing.assert_allclose(poses[link], kin.fk_pose(qs[:3], link=link))


def test_arguments_are_not_mutated(kin, qs):
    q = qs[:4].copy()
    kin.fk(q)
    kin.jacobian(q)
    np.testing.assert_array_equal(q, qs[:4])


@pytest.mark.parametrize(
    "q", [np.zeros(6), np.zeros((3, 8)), 0.0, [[np.nan] * 7], [np.inf] * 7, "q"]
)
def test_bad_joint_arrays_are_refused(kin, q):
    with pytest.raises(ValueError, match="q"):
        kin.fk(q)


@pytest.mark.parametrize(
    "link", ["no_such_link", "right_hand_link", "head", "l_gripper_l_finger", 3]
)
def test_links_not_moved_by_the_left_arm_alone_are_refused(kin, link):
    with pytest.raises(ValueError, match="link"):
        kin.fk_pose(np.zeros(7), link=link)


def _read_trial(path) -> tuple[np.ndarray, np.ndarray]:
    with open(path, newline="") as handle:
        rows = csv.reader(handle)
        header = next(rows)
        data = np.array([[float(v) for v in row] for row in rows])
    joints = data[:, [header.index(n) for n in ARM_JOINTS]]
    hand = data[:, [header.index(f"baxter_left_hand_{a}") for a in "xyz"]]
    return joints, hand


def test_fk_matches_the_recorded_end_effector_within_a_constant_offset(kin, recorded_dir):
    """All trials: FK(left_*) vs the robot's own baxter_left_hand_* (data README: ~11 mm, +z)."""
    files = sorted(recorded_dir.glob("*/*.csv"))
    assert len(files) == 174
    diffs = []
    for path in files:
        joints, hand = _read_trial(path)
        diffs.append(kin.fk(joints, link="left_hand_link") - hand)
    diff = np.concatenate(diffs)
    dist = np.linalg.norm(diff, axis=1)
    offset = diff.mean(axis=0)
    # Measured: mean 10.9 mm, max 22.2 mm, offset (+1.2, -0.7, +10.6) mm.
    assert 0.008 < dist.mean() < 0.014 and dist.max() < 0.03
    assert 0.008 < offset[2] < 0.013 and np.all(np.abs(offset[:2]) < 0.003)
    # Nearly constant: once the mean offset is removed, what is left is small.
    assert np.linalg.norm(diff - offset, axis=1).mean() < 0.003

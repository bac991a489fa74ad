"""Damped-least-squares inverse kinematics: accuracy, limits, failures, error paths."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.robot import BaxterKinematics, IKResult, q_home
from sandbox.robot.ik import _rotation_error


@pytest.fixture(scope="module")
def kin() -> BaxterKinematics:
    return BaxterKinematics()


def _front_workspace(kin, link, n, seed=0):
    """Reachable targets: FK of random in-limit configurations ending in front of Baxter."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(kin.lower, kin.upper, size=(20 * n, 7))
    p = kin.fk(q, link=link)
    front = (p[:, 0] > 0.4) & (p[:, 1] > -0.2) & (p[:, 2] > -0.4) & (p[:, 2] < 0.7)
    assert front.sum() >= n
    return p[front][:n], q[front][:n]


def _within_limits(kin, q):
    return np.all(q >= kin.lower) and np.all(q <= kin.upper)


@pytest.mark.parametrize("link", ["left_gripper", "left_hand_link"])
def test_reachable_targets_are_reached_within_1_cm(kin, link):
    targets, _ = _front_workspace(kin, link, 400)
    res = kin.ik(targets, link=link)
    assert isinstance(res, IKResult)
    assert res.q.shape == (400, 7) and res.error.shape == res.success.shape == (400,)
    assert res.success.mean() >= 0.95  # measured: 1.0 on 2000 targets
    assert _within_limits(kin, res.q)
    # The reported error is the true error of the returned configuration.
    np.testing.assert_allclose(
        res.error, np.linalg.norm(kin.fk(res.q, link=link) - targets, axis=1)
    )
    np.testing.assert_array_equal(res.success, res.error <= 0.01)


def test_tolerance_is_an_argument(kin):
    targets, _ = _front_workspace(kin, "left_gripper", 50, seed=1)
    res = kin.ik(targets, tol=1e-4)
    assert res.success.mean() >= 0.95 and np.all(res.error[res.success] <= 1e-4)
    assert np.all(kin.ik(targets, tol=0.05, max_iter=1, restarts=0).error > 0)


def test_unreachable_targets_are_failures_not_crashes(kin):
    targets = np.array([[3.0, 0.0, 0.0], [0.0, 0.0, 3.0], [1.6, 0.5, 0.2], [0.8, 0.3, 0.1]])
    res = kin.ik(targets)
    np.testing.assert_array_equal(res.success, [False, False, False, True])
    assert np.all(res.error[:3] > 0.2) and np.all(np.isfinite(res.q))
    assert _within_limits(kin, res.q)


def test_targets_at_the_seed_return_the_seed(kin):
    seed = q_home()
    res = kin.ik(kin.fk(seed, link="left_gripper"), q_seed=seed)
    np.testing.assert_array_equal(res.q[0], seed)
    assert res.iterations[0] == 0 and res.success[0]


def test_default_seed_is_the_recorded_home_configuration(kin):
    target = kin.fk(q_home() + 0.05, link="left_gripper")
    np.testing.assert_array_equal(kin.ik(target).q, kin.ik(target, q_seed=q_home()).q)


def test_solutions_stay_near_a_nearby_seed(kin):
    rng = np.random.default_rng(3)
    seeds = q_home() + rng.normal(0.0, 0.2, size=(30, 7))
    seeds = np.clip(seeds, kin.lower, kin.upper)
    targets = kin.fk(seeds, link="left_gripper") + rng.normal(0.0, 0.02, size=(30, 3))
    res = kin.ik(targets, q_seed=seeds)
    assert res.success.all()
    assert np.max(np.abs(res.q - seeds)) < 0.5  # rad: no jump to another branch


def test_seed_outside_the_limits_is_clipped(kin):
    seed = kin.upper + 1.0
    res = kin.ik([0.8, 0.3, 0.1], q_seed=seed)
    assert res.success[0] and _within_limits(kin, res.q)


def test_position_and_orientation_targets(kin):
    targets, q_true = _front_workspace(kin, "left_gripper", 100, seed=2)
    rotations = kin.fk_pose(q_true, link="left_gripper")[:, :3, :3]
    res = kin.ik(targets, orientations=rotations, angle_tol=0.02)
    assert res.success.mean() >= 0.95  # measured: 0.995 on 2000 targets
    got = kin.fk_pose(res.q, link="left_gripper")[:, :3, :3]
    angle = np.linalg.norm(_rotation_error(rotations, got), axis=1)
    np.testing.assert_allclose(res.angle_error, angle, atol=1e-12)
    assert np.all(angle[res.success] <= 0.02)


def test_rotation_error_known_answers():
    def rz(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    current = np.stack([np.eye(3), rz(0.3), np.eye(3)])
    target = np.stack([rz(0.5), rz(0.3), rz(np.pi)])
    err = _rotation_error(target, current)
    np.testing.assert_allclose(err[0], [0.0, 0.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(err[1], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(err[2]), [0.0, 0.0, np.pi], atol=1e-6)


def test_inputs_are_not_mutated_and_results_are_deterministic(kin):
    targets, _ = _front_workspace(kin, "left_gripper", 20, seed=4)
    seed = np.tile(q_home(), (20, 1))
    before = (targets.copy(), seed.copy())
    first, second = kin.ik(targets, q_seed=seed), kin.ik(targets, q_seed=seed)
    np.testing.assert_array_equal(targets, before[0])
    np.testing.assert_array_equal(seed, before[1])
    np.testing.assert_array_equal(first.q, second.q)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"targets": [[0.8, 0.3]]}, "targets"),
        ({"targets": [[np.nan, 0.3, 0.1]]}, "targets"),
        ({"targets": [0.8, 0.3, 0.1], "q_seed": np.zeros(6)}, "q_seed"),
        ({"targets": np.zeros((2, 3)), "q_seed": np.zeros((3, 7))}, "q_seed"),
        ({"targets": [0.8, 0.3, 0.1], "q_seed": [np.nan] * 7}, "q_seed"),
        ({"targets": [0.8, 0.3, 0.1], "link": "head"}, "link"),
        ({"targets": [0.8, 0.3, 0.1], "tol": 0.0}, "tol"),
        ({"targets": [0.8, 0.3, 0.1], "tol": np.nan}, "tol"),
        ({"targets": [0.8, 0.3, 0.1], "restarts": -1}, "restarts"),
        ({"targets": [0.8, 0.3, 0.1], "orientations": 2 * np.eye(3)}, "orientations"),
        ({"targets": [0.8, 0.3, 0.1], "orientations": np.eye(4)}, "orientations"),
    ],
)
def test_bad_arguments_are_refused(kin, kwargs, match):
    with pytest.raises(ValueError, match=match):
        kin.ik(**kwargs)


def test_rest_posture_pull_moves_solutions_toward_it(kin):
    targets, _ = _front_workspace(kin, "left_gripper", 40, seed=5)
    rest = np.clip(q_home() + 0.6, kin.lower, kin.upper)
    plain = kin.ik(targets)
    pulled = kin.ik(targets, q_rest=rest, rest_gain=0.3, tol=0.01)
    assert pulled.success.mean() >= 0.95
    both = pulled.success & plain.success
    dist_pulled = np.linalg.norm(pulled.q - rest, axis=1)[both]
    dist_plain = np.linalg.norm(plain.q - rest, axis=1)[both]
    assert np.median(dist_pulled) < np.median(dist_plain)
    with pytest.raises(ValueError, match="q_rest"):
        kin.ik(targets, q_rest=np.zeros(5))

"""Baxter in the environment: limits, position control, gripper, fingertip."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic.base import Q_HOME
from sandbox.envs.robot import Q_RIGHT, RIGHT_JOINTS
from sandbox.episodes.policies import MAX_VELOCITY
from sandbox.robot import BaxterKinematics


def test_limits_come_from_the_urdf(diverging_env):
    robot = diverging_env.unwrapped.robot
    kin = BaxterKinematics()
    np.testing.assert_allclose(robot.lower, kin.lower)
    np.testing.assert_allclose(robot.upper, kin.upper)
    np.testing.assert_allclose(robot.max_velocity, MAX_VELOCITY)  # the policy's copy
    np.testing.assert_allclose(robot.max_force, [50, 50, 50, 50, 15, 15, 15])


def test_arm_tracks_a_target_within_its_speed_limits(diverging_env):
    env = diverging_env.unwrapped
    env.reset(seed=0)
    target = Q_HOME + np.array([0.3, 0.2, -0.2, -0.3, 0.4, -0.3, 0.5])
    speeds = []
    for _ in range(100):
        obs, *_ = env.step(np.append(target, -1.0))
        speeds.append(np.abs(obs["dq"]))
    np.testing.assert_allclose(obs["q"], target, atol=0.01)
    assert np.all(np.max(speeds, axis=0) <= MAX_VELOCITY * 1.05)


def test_fingertip_matches_forward_kinematics(diverging_env):
    env = diverging_env.unwrapped
    obs, _ = env.reset(seed=0)
    for _ in range(20):
        obs, *_ = env.step(np.append(Q_HOME + 0.2, -1.0))
    tip = BaxterKinematics().fk(obs["q"], link="left_gripper")
    np.testing.assert_allclose(env.robot.tip_position(), tip, atol=1e-6)


def test_gripper_opens_and_closes(diverging_env):
    env = diverging_env.unwrapped
    obs, _ = env.reset(seed=0)
    assert obs["gripper"][0] == pytest.approx(1.0) and not env.robot.gripper_closed()
    for _ in range(10):
        obs, *_ = env.step(np.append(Q_HOME, 1.0))
    assert obs["gripper"][0] < 0.05 and env.robot.gripper_closed()
    for _ in range(10):
        obs, *_ = env.step(np.append(Q_HOME, -0.5))
    assert obs["gripper"][0] > 0.95


def test_right_arm_and_head_hold_their_posture(diverging_env):
    env = diverging_env.unwrapped
    env.reset(seed=0)
    for _ in range(100):
        env.step(np.append(Q_HOME, -1.0))
    joints = [env.robot.baxter.joints[n] for n in RIGHT_JOINTS]
    q, _ = env.sim.joint_states("baxter", joints)
    np.testing.assert_allclose(q, Q_RIGHT, atol=0.02)

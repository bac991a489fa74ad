"""Baxter in the environment: limits, position control, gripper, fingertip."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.envs.robot import Q_RIGHT, RIGHT_JOINTS
from sandbox.robot import Q_HOME, BaxterKinematics, joint_speed_limits

MAX_VELOCITY = joint_speed_limits()  # the policies' default


def test_limits_come_from_the_urdf(diverging_env):
    robot = diverging_env.unwrapped.robot
    kin = BaxterKinematics()
    np.testing.assert_allclose(robot.lower, kin.lower)
    np.testing.assert_allclose(robot.upper, kin.upper)
    np.testing.assert_allclose(robot.max_velocity, MAX_VELOCITY)  # the policy's default
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


def test_array_commands_keep_the_speed_limits_of_the_first_command(diverging_env):
    """After reset, act() sends the targets in one array call, which carries no speed limit:
    the motion is the per-joint commands' with the limits, bit for bit, not the one
    without them."""
    env = diverging_env.unwrapped
    robot, sim = env.robot, env.sim
    targets = np.random.default_rng(0).uniform(robot.lower, robot.upper, (8, robot.dof))

    def run(command) -> np.ndarray:
        env.reset(seed=0)
        states = []
        for target in targets:
            command(target)
            for _ in range(env.substeps):
                sim.step_physics()
            states.append(np.concatenate(robot.state()[:2]))
        return np.array(states)

    arm = robot.baxter.arm
    fast = run(lambda q: robot.act(q, close=False))
    limited = run(lambda q: sim.control_joints("baxter", arm, q, robot.max_force,
                                               robot.max_velocity))
    unlimited = run(lambda q: sim.control_joints("baxter", arm, q, robot.max_force,
                                                 1e6 * robot.max_velocity))
    np.testing.assert_array_equal(fast, limited)
    assert np.abs(fast - unlimited).max() > 0.1      # the limits shape this motion


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

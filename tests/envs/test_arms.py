"""Every arm in the environments (issue 23 item 3): ids, spaces, checker, determinism."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence

import sandbox.envs
from sandbox.robot.arms import ROBOTS, arm_spec
from sandbox.robot.retarget import Retargeter


@pytest.fixture(scope="module", params=ROBOTS)
def arm_env(request):
    env = gym.make("sandbox/HandoverDiverging-v2", robot=request.param)
    yield request.param, env
    env.close()


def _rollout(env, seed: int, n_steps: int = 60):
    """Observations, rewards and infos of a seeded random rollout around the home pose."""
    obs, info = env.reset(seed=seed)
    rng = np.random.default_rng(0)
    out = [obs, info]
    home = env.unwrapped.robot.spec.q_home
    for k in range(n_steps):
        action = np.append(home + rng.normal(0.0, 0.2, home.size), 1.0 if k > 40 else -1.0)
        obs, reward, terminated, truncated, info = env.step(action)
        out += [obs, reward, terminated, truncated, info]
    return out


def test_the_v2_ids_take_any_arm_and_the_baxter_ids_are_aliases():
    assert sandbox.envs.ROBOT_IDS == ["sandbox/Handover-v2", "sandbox/HandoverDiverging-v2"]
    for env_id in sandbox.envs.ROBOT_IDS:
        assert gym.spec(env_id).kwargs["robot"] == "baxter"
        assert gym.spec(env_id).entry_point == gym.spec(sandbox.envs.ENV_IDS[0]).entry_point


def test_check_env_passes_and_the_spaces_fit_the_arm(arm_env):
    name, env = arm_env
    check_env(env.unwrapped, skip_render_check=True)
    dof = arm_spec(name).dof
    assert env.action_space.shape == (dof + 1,)
    assert env.observation_space["q"].shape == env.observation_space["dq"].shape == (dof,)
    obs, _ = env.reset(seed=0)
    np.testing.assert_allclose(obs["q"], arm_spec(name).q_home, atol=0.01)
    assert obs["gripper"][0] > 0.99      # open at the start


def test_the_same_seed_gives_the_same_episode(arm_env):
    _, env = arm_env
    assert data_equivalence(_rollout(env, 4), _rollout(env, 4), exact=True)


def test_the_tip_in_the_simulation_is_the_retargeters(arm_env):
    name, env = arm_env
    env.reset(seed=0)
    robot = env.unwrapped.robot
    q, _ = robot.joint_state()
    np.testing.assert_allclose(robot.tip_position(), Retargeter(name).tip(q), atol=1e-6)


def test_closing_the_gripper_closes_it(arm_env):
    """Within 1.5 s (the Kinova's fingers turn at 1 rad/s, the slowest)."""
    _, env = arm_env
    env.reset(seed=0)
    action = np.append(env.unwrapped.robot.spec.q_home, 1.0)
    for _ in range(75):
        obs, *_ = env.step(action)
    assert obs["gripper"][0] < 0.5 and env.unwrapped.robot.gripper_closed()


def test_an_unknown_robot_and_a_wrong_action_are_refused():
    with pytest.raises(ValueError, match="robot: expected one of baxter, panda, ur5, kinova"):
        gym.make("sandbox/Handover-v2", robot="iiwa")
    env = gym.make("sandbox/HandoverDiverging-v2", robot="ur5")
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match=r"action"):
            env.step(np.zeros(8))
    finally:
        env.close()


def test_a_sync_vector_env_takes_the_robot():
    envs = gym.make_vec("sandbox/HandoverDiverging-v2", num_envs=2, vectorization_mode="sync",
                        robot="kinova")
    try:
        obs, _ = envs.reset(seed=0)
        assert obs["q"].shape == (2, 6) and envs.single_action_space.shape == (7,)
    finally:
        envs.close()

"""The handover itself: the object rides in the hand, moves to the gripper, and the reward."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic.robot import Q_HANDOVER
from sandbox.envs.task import DEFAULT_HOLD_OFFSET, TASK_OBJECTS, RewardWeights, object_for
from sandbox.robot import Q_HOME, BaxterKinematics


def hold_until(env, q, t_end, close=False):
    """Step with constant targets ``q`` until time ``t_end``; the last step's outputs."""
    while True:
        out = env.step(np.append(q, 1.0 if close else -1.0))
        if out[0]["time"][0] >= t_end - 1e-9 or out[2]:
            return out


def reach_config(env):
    """Joint angles putting the fingertip at the object's grasp point once the hand rests."""
    motion = env.unwrapped.motion
    target = motion.true[-1] + DEFAULT_HOLD_OFFSET
    result = BaxterKinematics().ik(target[None], q_seed=Q_HANDOVER, link="left_gripper",
                                   tol=0.002)
    assert result.success.all()
    return result.q[0], motion.duration


def test_the_object_rides_in_the_hand(diverging_env):
    env = diverging_env.unwrapped
    env.reset(seed=4, options={"task": "up"})
    for _ in range(60):
        obs, *_ = env.step(np.append(Q_HOME, -1.0))
        hand, _ = env.sim.pose("human_hand")
        np.testing.assert_allclose(hand, env.motion.position(obs["time"][0]), atol=1e-9)
        np.testing.assert_allclose(obs["object"], hand + DEFAULT_HOLD_OFFSET, atol=5e-4)


def test_closing_at_the_object_hands_it_over(diverging_env):
    env = diverging_env.unwrapped
    env.reset(seed=4, options={"task": "left"})
    q, duration = reach_config(env)
    obs, *_ = hold_until(env, q, duration + 0.5)
    assert np.linalg.norm(env.robot.tip_position() - obs["object"]) < 0.01
    for _ in range(10):  # the fingers close in a few steps
        obs, reward, terminated, truncated, info = env.step(np.append(q, 1.0))
        if terminated:
            break
    assert terminated and not truncated and info["is_success"]
    assert info["handover_time"] <= duration + 0.5 + 0.1
    assert info["handover_time"] == pytest.approx(obs["time"][0])
    assert info["reward_success"] == 10.0 and reward > 9.0
    assert obs["gripper"][0] < 0.5
    # the object now follows the gripper and the hand lets go of it
    offset = obs["object"] - env.robot.tip_position()
    for _ in range(40):
        obs, *_ = env.step(np.append(Q_HOME, 1.0))
    hand, _ = env.sim.pose("human_hand")
    np.testing.assert_allclose(obs["object"] - env.robot.tip_position(), offset, atol=0.01)
    assert np.linalg.norm(obs["object"] - hand) > 0.1


def test_closing_away_from_the_object_does_not(diverging_env):
    env = diverging_env.unwrapped
    env.reset(seed=4, options={"task": "left"})
    q, duration = reach_config(env)
    env.step(np.append(Q_HOME, 1.0))
    obs, _, terminated, _, info = hold_until(env, Q_HOME, 1.0, close=True)
    assert not terminated and not info["is_success"] and obs["gripper"][0] < 0.5
    assert info["distance"] > env.task.grasp_radius
    # opening and coming back later still works
    hold_until(env, q, duration + 0.5)
    *_, terminated, _, info = hold_until(env, q, duration + 0.6, close=True)
    assert terminated and info["is_success"]


def test_open_gripper_at_the_object_does_not_hand_over(diverging_env):
    env = diverging_env.unwrapped
    env.reset(seed=4, options={"task": "down"})
    q, duration = reach_config(env)
    *_, terminated, _, info = hold_until(env, q, duration + 1.0)
    assert not terminated and info["distance"] < 0.01 and not info["is_success"]


def test_task_objects():
    assert object_for("pencil_box") == "box"
    assert object_for("gummed_paper") == "tape"
    assert object_for("measurement_tape") == "measuring_tape"
    assert object_for("screw_driver") == "screwdriver"
    assert object_for("left") == "box"
    assert object_for("left", default="tape") == "tape"
    from sandbox import urdf

    assert set(TASK_OBJECTS.values()) == set(urdf.OBJECTS)


def test_reward_weights_are_validated():
    with pytest.raises(ValueError, match="success"):
        RewardWeights(success=-1.0)
    with pytest.raises(ValueError, match="distance"):
        RewardWeights(distance=float("nan"))


def test_reward_weights_scale_the_terms():
    from sandbox.envs.task import HandoverTask

    task = HandoverTask.__new__(HandoverTask)  # the terms need only the weights
    task.weights = RewardWeights(distance=2.0, success=5.0, action_rate=0.5)
    terms = task.reward_terms(0.1, True, np.array([1.0, 2.0, 0, 0, 0, 0, 0]))
    assert terms == {"reward_distance": -0.2, "reward_success": 5.0, "reward_action_rate": -2.5}


def test_the_object_rides_at_the_given_grasp_offset(diverging_env):
    """The meeting geometry of a session (issue 21): one offset, or one per task."""
    env = diverging_env.unwrapped
    offset = np.array([0.04, -0.06, 0.03])
    for given in (offset, {"up": offset.tolist(), "down": [0.0, 0.0, 0.0]}):
        _, info = env.reset(seed=4, options={"task": "up", "grasp_offset": given})
        np.testing.assert_allclose(info["grasp_offset"], offset)
        for _ in range(20):
            obs, *_ = env.step(np.append(Q_HOME, -1.0))
            hand, _ = env.sim.pose("human_hand")
            np.testing.assert_allclose(obs["object"], hand + offset, atol=5e-4)
    _, info = env.reset(seed=4, options={"task": "up"})          # back to the default
    np.testing.assert_allclose(info["grasp_offset"], DEFAULT_HOLD_OFFSET)


def test_per_task_offsets_must_cover_the_episodes_task(diverging_env):
    with pytest.raises(ValueError, match=r"grasp_offset: expected an offset for .*'up'"):
        diverging_env.reset(seed=4, options={"task": "up", "grasp_offset": {"down": [0, 0, 0]}})

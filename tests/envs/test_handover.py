"""The handover environments through the Gymnasium API: registration, checker, determinism."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env, data_equivalence

import sandbox.envs
from sandbox.envs import ENV_IDS, LEGACY_IDS, MAX_EPISODE_STEPS, BaxterHandoverEnv
from sandbox.robot import Q_HOME

TERMS = ("reward_distance", "reward_success", "reward_action_rate")


def rollout(env, seed: int, n_steps: int = 120, options=None, close_after: int = 60):
    """Observations, rewards and infos of a seeded random rollout (gripper closes late)."""
    obs, info = env.reset(seed=seed, options=options)
    rng = np.random.default_rng(0)
    out = [obs, info]
    for k in range(n_steps):
        action = rng.uniform(env.action_space.low, env.action_space.high)
        action[7] = 1.0 if k >= close_after else -1.0
        obs, reward, terminated, truncated, info = env.step(action)
        out += [obs, reward, terminated, truncated, info]
        if terminated or truncated:
            break
    return out


@pytest.fixture(scope="module")
def second_env():
    """A second diverging environment, made directly (not through ``gym.make``)."""
    env = BaxterHandoverEnv(family="diverging")
    yield env
    env.close()


def test_ids_are_registered_with_a_time_limit():
    assert ENV_IDS == ["sandbox/BaxterHandover-v1", "sandbox/BaxterHandoverDiverging-v1"]
    assert LEGACY_IDS == ["sandbox/BaxterHandover-v0", "sandbox/BaxterHandoverDiverging-v0"]
    for ids, body in ((ENV_IDS, True), (LEGACY_IDS, False)):
        for env_id, family in zip(ids, ("objects", "diverging")):
            spec = gym.spec(env_id)
            assert spec.max_episode_steps == MAX_EPISODE_STEPS
            assert spec.kwargs == {"family": family, "observe_body": body}


def test_reimporting_does_not_register_twice():
    import importlib

    importlib.reload(sandbox.envs)
    assert sandbox.envs.ENV_IDS == ENV_IDS


@pytest.mark.filterwarnings("ignore:.*symmetric and normalized")  # targets are in rad, by design
@pytest.mark.filterwarnings("error:.*observation")  # e.g. NaN outside the observation space
@pytest.mark.parametrize("fixture", ["objects_env", "diverging_env"])
def test_check_env(fixture, request):
    check_env(request.getfixturevalue(fixture).unwrapped, skip_render_check=False)


@pytest.mark.filterwarnings("ignore:.*symmetric and normalized")
@pytest.mark.filterwarnings("ignore:.*out of date")  # the v0 ids, kept for one release
@pytest.mark.filterwarnings("error:.*observation")
@pytest.mark.parametrize("env_id", LEGACY_IDS)
def test_check_env_legacy_ids(env_id):
    env = gym.make(env_id)
    try:
        check_env(env.unwrapped)
        obs, _ = env.reset(seed=0)
        assert set(obs) == {"hand", "object", "q", "dq", "gripper", "time"}
    finally:
        env.close()


@pytest.mark.filterwarnings("ignore:.*out of date")
def test_legacy_ids_keep_the_v0_observation(diverging_env):
    legacy = gym.make("sandbox/BaxterHandoverDiverging-v0")
    try:
        old, new = rollout(legacy, seed=4, n_steps=30), rollout(diverging_env, seed=4, n_steps=30)
    finally:
        legacy.close()
    body = ("hand_valid", "hand_time", "arm", "arm_valid", "emg", "emg_valid")  # v1 only
    for a, b in zip([old[0], *old[2::5]], [new[0], *new[2::5]]):
        assert data_equivalence(a, {k: v for k, v in b.items() if k not in body}, exact=True)


def test_module_prefixed_make_1000_random_steps_and_close_twice():
    env = gym.make("sandbox.envs:sandbox/BaxterHandover-v1")
    env.reset(seed=0)
    env.action_space.seed(0)
    episodes = 0
    for _ in range(1000):
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs) and np.isfinite(reward)
        if terminated or truncated:
            episodes += 1
            env.reset()
    assert episodes >= 3  # 300-step time limit
    env.close()
    env.close()


def test_same_seed_same_rollout_across_resets_and_instances(diverging_env, second_env):
    first = rollout(diverging_env, seed=5)
    rollout(diverging_env, seed=6)  # something else in between
    assert data_equivalence(first, rollout(diverging_env, seed=5), exact=True)
    assert data_equivalence(first, rollout(second_env, seed=5), exact=True)
    assert not data_equivalence(first[0], rollout(diverging_env, seed=7, n_steps=0)[0])


def test_two_envs_stepped_alternately_do_not_interfere(diverging_env, second_env):
    alone = rollout(diverging_env, seed=3, n_steps=40)
    obs_a, _ = diverging_env.reset(seed=3)
    second_env.reset(seed=11)
    rng, other = np.random.default_rng(0), np.random.default_rng(1)
    for _ in range(40):
        action = rng.uniform(diverging_env.action_space.low, diverging_env.action_space.high)
        action[7] = -1.0
        second_env.step(other.uniform(second_env.action_space.low, second_env.action_space.high))
        obs_a, *_ = diverging_env.step(action)
    assert data_equivalence(obs_a, alone[2 + 5 * 39], exact=True)
    assert diverging_env.unwrapped.bullet_client._client != second_env.bullet_client._client


def test_observations_share_no_memory(diverging_env):
    """Each observation's entries are new arrays (slices of one per step): writing into one
    changes no other entry, no later observation and nothing the environment keeps."""
    first, _ = diverging_env.reset(seed=0)
    second, *_ = diverging_env.step(np.append(Q_HOME, -1.0))
    keep = {k: v.copy() for k, v in second.items()}
    for value in first.values():
        value[...] = 7
        assert all(not np.shares_memory(value, other[k])
                   for other in (first, second) for k in other if other[k] is not value)
    third, *_ = diverging_env.step(np.append(Q_HOME, -1.0))
    assert data_equivalence(second, keep, exact=True) and third["q"][0] != 7
    assert third["hand_valid"].dtype == np.int8 and third["hand_valid"].shape == (1,)


def test_reward_is_the_sum_of_its_terms(diverging_env):
    out = rollout(diverging_env, seed=2, n_steps=80, close_after=0)
    for reward, info in zip(out[3::5], out[6::5]):
        assert reward == pytest.approx(sum(info[k] for k in TERMS), abs=1e-12)
        assert info["reward_distance"] == pytest.approx(-info["distance"])
        assert info["reward_action_rate"] <= 0.0


def test_holding_still_costs_no_action_rate_and_ends_by_time_limit(diverging_env):
    diverging_env.reset(seed=1)
    action = np.append(Q_HOME, -1.0)
    steps = 0
    truncated = False
    while not truncated:
        obs, reward, terminated, truncated, info = diverging_env.step(action)
        assert info["reward_action_rate"] == 0.0 and not terminated
        steps += 1
    assert steps == MAX_EPISODE_STEPS
    assert obs["time"][0] == pytest.approx(MAX_EPISODE_STEPS / 50.0)
    assert info["handover_time"] is None and not info["is_success"]


def test_spaces_and_first_observation(objects_env):
    env = objects_env.unwrapped
    assert env.action_space.shape == (8,)
    np.testing.assert_array_equal(env.action_space.low[:7], env.robot.lower)
    obs, info = objects_env.reset(seed=0)
    assert set(obs) == {"hand", "hand_valid", "hand_time", "arm", "arm_valid", "emg",
                        "emg_valid", "object", "q", "dq", "gripper", "time"}
    assert obs["arm_valid"].dtype == np.int8 and obs["emg"].shape == (8,)
    np.testing.assert_allclose(obs["q"], Q_HOME, atol=1e-6)
    assert obs["gripper"][0] == pytest.approx(1.0) and obs["time"][0] == 0.0
    assert np.linalg.norm(obs["object"] - obs["hand"]) < 0.1
    assert info["task"] in ("box", "glasses_case", "tape") and info["object"] == info["task"]


def test_out_of_range_targets_act_like_the_limits(diverging_env):
    env = diverging_env.unwrapped
    runs = []
    for target in (env.robot.upper + 5.0, env.robot.upper, env.robot.lower - 5.0):
        env.reset(seed=0)
        runs.append([env.step(np.append(target, -1.0))[0]["q"] for _ in range(20)])
    np.testing.assert_array_equal(runs[0], runs[1])
    assert np.all(runs[0][-1] > Q_HOME) and np.all(runs[2][-1] < Q_HOME)


@pytest.mark.parametrize("action", [np.zeros(7), np.zeros((1, 8)), np.full(8, np.nan), "up"])
def test_bad_action_is_refused(diverging_env, action):
    diverging_env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        diverging_env.unwrapped.step(action)


def test_step_before_reset_is_refused():
    env = BaxterHandoverEnv(family="diverging")
    try:
        with pytest.raises(RuntimeError, match="reset"):
            env.step(np.append(Q_HOME, -1.0))
    finally:
        env.close()


@pytest.mark.parametrize("kwargs, match", [
    ({"family": "kitchen"}, "family"),
    ({"render_mode": "ascii"}, "render_mode"),
    ({"viewer_options": {"live": False}}, "viewer_options"),
    ({"viewer_options": ["fps"]}, "viewer_options"),
    ({"substeps": 0}, "substeps"),
    ({"substeps": 2.5}, "substeps"),
    ({"control_hz": -50.0}, "control_hz"),
    ({"default_object": "banana"}, "default_object"),
    ({"observe_body": "yes"}, "observe_body"),
])
def test_bad_constructor_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        BaxterHandoverEnv(**kwargs)


def test_render_rgb_array(objects_env, diverging_env):
    objects_env.reset(seed=0)
    image = objects_env.render()
    assert image.shape == (360, 480, 3) and image.dtype == np.uint8
    assert image.std() > 10  # not a blank frame
    diverging_env.reset(seed=0)
    assert diverging_env.render() is None
    assert objects_env.metadata["render_modes"] == ["human", "rgb_array"]


def test_viewer_hook_names_the_bodies(objects_env):
    env = objects_env.unwrapped
    ids = env.body_ids
    for name in ("baxter", "human_hand", "table", "floor", "box", "tape", "screwdriver"):
        assert name in ids
    assert len(set(ids.values())) == len(ids)
    assert env.bullet_client.getNumBodies() == len(ids)


def test_synthetic_episodes_observe_the_arm_but_no_emg(diverging_env):
    obs, _ = diverging_env.reset(seed=0)
    motion = diverging_env.unwrapped.motion
    for _ in range(25):
        obs, *_ = diverging_env.step(np.append(obs["q"], -1.0))
    assert obs["arm_valid"][0] == 1 and obs["emg_valid"][0] == 0
    np.testing.assert_array_equal(obs["arm"], motion.body_measurement("arm", 0.5))
    np.testing.assert_array_equal(obs["emg"], np.zeros(8))
    elbow, shoulder = obs["arm"][:3], obs["arm"][3:]
    assert 0.15 < np.linalg.norm(obs["hand"] - elbow) < 0.45  # a forearm, m
    assert 0.15 < np.linalg.norm(elbow - shoulder) < 0.45  # an upper arm, m


def test_scripted_and_teleop_episodes_observe_no_arm_and_no_emg(diverging_env):
    from sandbox.envs.sources import waypoint_motion

    motion = waypoint_motion([0.0, 1.0], [[1.1, 0.0, 0.2], [0.8, 0.1, 0.2]],
                             np.random.default_rng(0))
    for options in ({"motion": motion}, {"source": "teleop"}):
        obs, _ = diverging_env.reset(seed=0, options=options)
        obs, *_ = diverging_env.step(np.append(obs["q"], -1.0))
        assert obs["arm_valid"][0] == 0 and obs["emg_valid"][0] == 0
        assert not obs["arm"].any() and not obs["emg"].any()


def test_recorded_episodes_observe_arm_and_emg_deterministically(objects_env, recorded_dir):
    options = {"source": str(recorded_dir), "task": "pencil_box", "trial": 1}
    first = rollout(objects_env, seed=2, n_steps=100, options=options)
    assert data_equivalence(first, rollout(objects_env, seed=2, n_steps=100, options=options),
                            exact=True)
    motion = objects_env.unwrapped.motion
    observations = [first[0], *first[2::5]]
    valid = np.array([[o["arm_valid"][0], o["emg_valid"][0]] for o in observations])
    assert valid[-1].all()  # both measured by the end
    for k, obs in enumerate(observations):
        for name in ("arm", "emg"):
            expected = motion.body_measurement(name, k * 0.02)
            if obs[f"{name}_valid"][0]:
                np.testing.assert_allclose(obs[name], expected)
            else:  # nothing measured yet: zeros, flagged
                assert np.isnan(expected).all() and not obs[name].any()


def test_human_intent_follows_an_intent_switch_and_the_speed(diverging_env):
    options = {"task": "up", "switch_to": "right", "switch_phase": 0.5}
    diverging_env.reset(seed=0, options=options)
    env = diverging_env.unwrapped
    switch = env.motion.meta["intent"].switch_time
    assert env.human_intent(0.0) == "up"  # and now: t = 0
    assert env.human_intent(switch - 0.01) == "up" and env.human_intent(switch + 0.01) == "right"
    diverging_env.reset(seed=0, options={**options, "speed": 2.0})  # the switch comes 2x sooner
    assert env.human_intent(switch / 2 - 0.01) == "up"
    assert env.human_intent(switch / 2 + 0.01) == "right"
    diverging_env.reset(seed=0, options={"task": "left"})
    assert env.human_intent(0.0) == env.human_intent(5.0) == "left"


def test_human_intent_is_unknown_for_teleop_and_scripted_hands(diverging_env):
    from sandbox.envs.sources import waypoint_motion

    motion = waypoint_motion([0.0, 1.0], [[1.1, 0.0, 0.2], [0.8, 0.1, 0.2]],
                             np.random.default_rng(0), task="left")
    for options in ({"motion": motion}, {"source": "teleop"}):
        diverging_env.reset(seed=0, options=options)
        assert diverging_env.unwrapped.human_intent() is None
    with pytest.raises(RuntimeError, match="reset"):
        BaxterHandoverEnv(family="diverging").human_intent()


def test_human_intent_of_a_recorded_trial_is_its_task(objects_env, recorded_dir):
    objects_env.reset(seed=0, options={"source": str(recorded_dir), "task": "pencil_box"})
    assert objects_env.unwrapped.human_intent(0.5) == "pencil_box"


# -- tracker frames: time stamps and repeated samples (issue 16 item 6) ---------------------
def test_a_sample_the_tracker_repeats_arrives_invalid_with_its_own_time(diverging_env):
    """The tracker (30 Hz frames) is slower than the env (50 Hz): a step without a new
    frame has ``hand_valid`` 0 and the held frame's time; a new frame is stamped with
    the time it was taken, not with the step's."""
    obs, _ = diverging_env.reset(seed=0, options={"task": "up"})
    motion = diverging_env.unwrapped.motion
    assert obs["hand_valid"][0] == 1 and obs["hand_time"][0] == motion.frame_time(0.0) <= 0.0
    rows, previous = [], obs
    for _ in range(50):
        obs, *_ = diverging_env.step(np.append(Q_HOME, -1.0))
        rows.append((obs["time"][0], obs["hand_time"][0], obs["hand_valid"][0]))
        if obs["hand_valid"][0]:
            assert obs["hand_time"][0] > previous["hand_time"][0]
        else:
            assert obs["hand_time"][0] == previous["hand_time"][0]
            np.testing.assert_array_equal(obs["hand"], previous["hand"])  # held, not NaN
        assert obs["hand_time"][0] <= obs["time"][0]
        np.testing.assert_array_equal(obs["hand"], motion.measurement(obs["time"][0]))
        previous = obs
    new = sum(valid for _, _, valid in rows)
    assert 0 < new < len(rows)  # fewer new frames than steps
    assert new == pytest.approx(30 * 1.0, abs=6)  # ~30 frames in 1 s of steps
    assert diverging_env.observation_space.contains(obs)


def test_the_teleoperated_hand_is_stamped_with_its_frames(diverging_env):
    obs, _ = diverging_env.reset(seed=0, options={"source": "teleop"})
    stamps = [obs["hand_time"][0]]
    for _ in range(10):
        obs, *_ = diverging_env.step(np.append(Q_HOME, -1.0))
        stamps.append(obs["hand_time"][0])
    frames = sorted(set(stamps))
    np.testing.assert_allclose(np.diff(frames), 1 / 30, atol=1e-9)

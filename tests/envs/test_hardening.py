"""Regression and property tests of the environments' input checks (issue 13, findings 9, 10)."""

from __future__ import annotations

import os
import warnings

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sandbox.envs import BaxterHandoverEnv, RewardWeights
from sandbox.envs.handover import ClosedEnvironmentError

#: Examples per property test; raise ``SANDBOX_FUZZ_EXAMPLES`` for a longer campaign.
EXAMPLES = int(os.environ.get("SANDBOX_FUZZ_EXAMPLES", "80"))


@pytest.fixture(scope="module")
def env():
    """A diverging env of this module, reset once (gymnasium's PassiveEnvChecker breaks the
    first step if the first reset raised, so the bad-input tests never reset it first)."""
    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.step(env.action_space.sample())
    yield env
    env.close()


@pytest.fixture(scope="module")
def closed_env():
    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    env.reset(seed=0)
    env.close()
    return env


@pytest.mark.parametrize("call", [lambda e: e.reset(seed=0), lambda e: e.step(np.zeros(8)),
                                  lambda e: e.unwrapped.step(np.zeros(8))])
def test_a_closed_environment_says_so(closed_env, call):
    """issue 13 finding 10: after `close()`, `step()`/`reset()` raised a bare PyBullet error;
    they raise ClosedEnvironmentError, both Gymnasium's class and a RuntimeError."""
    with pytest.raises(ClosedEnvironmentError, match="the environment is closed") as error:
        call(closed_env)
    assert isinstance(error.value, RuntimeError)
    assert isinstance(error.value, gym.error.ClosedEnvironmentError)
    closed_env.close()  # still safe to call again


def test_render_of_a_closed_environment_says_so():
    """issue 13 finding 10: `render()` after `close()` is the same clear error."""
    env = BaxterHandoverEnv(render_mode="rgb_array")
    env.close()
    with pytest.raises(ClosedEnvironmentError):
        env.render()


def test_reward_weights_as_a_dict_are_checked_at_construction():
    """issue 13 finding 10: `reward_weights` given as a dict passed construction and failed at
    reset; a dict of RewardWeights' fields is now accepted, anything else refused at once."""
    env = BaxterHandoverEnv(reward_weights={"success": 5.0})
    try:
        assert env.task.weights == RewardWeights(success=5.0)
        env.reset(seed=0)
    finally:
        env.close()
    for bad in ({"succes": 5.0}, {"success": float("nan")}, 3, [1.0, 2.0, 3.0], "weights"):
        with pytest.raises(ValueError, match="reward weight|reward_weights"):
            BaxterHandoverEnv(reward_weights=bad)


BAD_KWARGS = [
    {"family": ["objects"]}, {"family": None}, {"render_mode": "text"},
    {"control_hz": None}, {"control_hz": "fast"}, {"control_hz": np.inf}, {"control_hz": 1e9},
    {"substeps": None}, {"substeps": np.inf}, {"substeps": 1e12}, {"substeps": "3"},
    {"substeps": 2.5}, {"substeps": True}, {"grasp_radius": None}, {"grasp_radius": [1.0]},
    {"default_object": ["box"]}, {"default_object": None}, {"observe_body": None},
    {"viewer_options": [("fps", 30)]}, {"viewer_options": {"fps": "x"}},
    {"viewer_options": {"camera": (1, 2)}}, {"viewer_options": {"realtime": "yes"}},
    {"viewer_options": {"host": 7}}, {"viewer_options": {"colour": 1}},
]


@pytest.mark.parametrize("kwargs", BAD_KWARGS)
def test_bad_arguments_are_value_errors_at_construction(kwargs):
    """issue 13 finding 9: env arguments accept what the docstring says and raise ValueError
    (not TypeError/OverflowError, not later at reset) otherwise."""
    with pytest.raises(ValueError, match="expected"):
        BaxterHandoverEnv(**kwargs)


BAD_OPTIONS = [
    {"task": ["up"]}, {"object": ["box"]}, {"object": {}}, {"source": None}, {"source": 3},
    {"trial": [1]}, {"speed": None}, {"speed": "fast"}, {"speed": np.inf},
    {"switch_to": ["up"]}, {"switch_phase": None}, {"switch_phase": np.nan}, {"motion": 3},
    {1: 2}, "task=up", [("task", "up")],
]


@pytest.mark.parametrize("options", BAD_OPTIONS)
def test_bad_reset_options_are_value_errors(env, options):
    """issue 13 finding 9: `reset(options=...)` entries of the wrong type are ValueErrors."""
    with pytest.raises(ValueError):
        env.reset(seed=0, options=options)


@pytest.mark.parametrize("seed", ["abc", -1, 1.5, np.inf, [1, 2], True])
def test_bad_seeds_are_value_errors(env, seed):
    """issue 13 finding 9: a seed that is not None or an integer >= 0 is a ValueError."""
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=seed)


VALUES = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                   st.sampled_from([1e300, -1e300, 0.0, 5.0, -5.0]))
ACTIONS = st.one_of(
    st.lists(VALUES, min_size=8, max_size=8).map(np.array),
    st.lists(st.floats(-4.0, 4.0), min_size=8, max_size=8).map(np.array),
    st.lists(VALUES, min_size=0, max_size=12).map(np.array),
    st.sampled_from([None, "abc", {"q": 1}, np.zeros((1, 8)), np.zeros((8, 1)),
                     np.array(["x"] * 8), [[0.0] * 8]]),
)


def _finite_action(action) -> bool:
    try:
        a = np.asarray(action, dtype=float)
    except (TypeError, ValueError):
        return False
    return a.shape == (8,) and bool(np.isfinite(a).all())


@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(seed=st.integers(0, 2**32), task=st.sampled_from(["left", "right", "up", "down", None]),
       actions=st.lists(ACTIONS, min_size=1, max_size=8))
def test_random_actions_only_raise_value_errors_and_observations_stay_in_the_space(
        env, seed, task, actions):
    """issue 13 item 9: actions with NaN, inf, huge values or the wrong shape raise only
    ValueError; every observation is finite and inside the observation space."""
    space = env.observation_space
    obs, _ = env.reset(seed=seed, options={"task": task} if task else None)
    assert space.contains(obs)
    for action in actions:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # gymnasium's passive checker on odd actions
            try:
                obs, reward, terminated, truncated, info = env.step(action)
            except ValueError:
                assert not _finite_action(action)
                continue
        assert _finite_action(action)
        assert space.contains(obs)
        assert all(np.isfinite(v).all() for v in obs.values())
        assert np.isfinite(reward)
        if terminated or truncated:
            break

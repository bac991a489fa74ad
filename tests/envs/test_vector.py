"""Vector environments: ``gym.make_vec`` of every id, sync and async, against single envs."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv

from sandbox.envs import ENV_IDS, LEGACY_IDS, ROBOT_IDS
from sandbox.envs.vector import make_vector_env

ALL_IDS = ENV_IDS + LEGACY_IDS + ROBOT_IDS
#: Short episodes, so a few steps cross an autoreset.
EPISODE_STEPS = 3
N_STEPS = 5


def _actions(space, n_steps: int, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.uniform(space.low, space.high) for _ in range(n_steps)]


def _single_rollouts(env_id: str, num_envs: int, seed: int, actions) -> list[list[dict]]:
    """Observations of ``num_envs`` separate envs seeded as a vector env seeds them
    (``seed + i``), reset after an episode ends (Gymnasium's next-step autoreset)."""
    out = []
    for i in range(num_envs):
        env = gym.make(env_id, max_episode_steps=EPISODE_STEPS)
        obs, _ = env.reset(seed=seed + i)
        seen, done = [obs], False
        for action in actions:
            if done:
                obs, _ = env.reset()
                done = False
            else:
                obs, _, terminated, truncated, _ = env.step(action[i])
                done = terminated or truncated
            seen.append(obs)
        env.close()
        out.append(seen)
    return out


def _vector_rollout(env, seed: int, actions) -> list[dict]:
    obs, _ = env.reset(seed=seed)
    seen = [obs]
    for action in actions:
        obs, *_ = env.step(action)
        seen.append(obs)
    env.close()
    return seen


def _assert_same(vector_obs: list[dict], single_obs: list[list[dict]]) -> None:
    for t, batch in enumerate(vector_obs):
        for i, singles in enumerate(single_obs):
            for key, value in singles[t].items():
                np.testing.assert_array_equal(batch[key][i], value, err_msg=f"{key} step {t}")


@pytest.fixture(scope="module")
def reference():
    """Single-env rollouts of the diverging id, 2 envs, seed 7, and their actions."""
    env_id, num_envs, seed = ENV_IDS[1], 2, 7
    probe = gym.make(env_id)
    actions = [np.stack(a) for a in zip(*[_actions(probe.action_space, N_STEPS, 10 + i)
                                           for i in range(num_envs)])]
    probe.close()
    return env_id, num_envs, seed, actions, _single_rollouts(env_id, num_envs, seed, actions)


@pytest.mark.slow
@pytest.mark.parametrize("mode, vector_kwargs, kind", [
    ("sync", {}, SyncVectorEnv),
    ("async", {"context": "forkserver"}, AsyncVectorEnv),
    ("async", {"context": "spawn"}, AsyncVectorEnv),
    (None, {}, AsyncVectorEnv),                      # the registered vector entry point
])
def test_make_vec_matches_single_envs(reference, mode, vector_kwargs, kind):
    env_id, num_envs, seed, actions, singles = reference
    env = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode,
                       vector_kwargs=vector_kwargs, max_episode_steps=EPISODE_STEPS)
    assert isinstance(env, kind)
    assert env.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    _assert_same(_vector_rollout(env, seed, actions), singles)


def test_the_entry_point_starts_async_workers_from_a_forkserver():
    env = gym.make_vec(ENV_IDS[1], num_envs=1)
    try:
        assert isinstance(env, AsyncVectorEnv)
        assert env.context == "forkserver"
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ALL_IDS)
def test_every_id_vectorizes_with_one_simulator_per_sub_env(env_id):
    env = gym.make_vec(env_id, num_envs=2, vectorization_mode="sync")
    try:
        clients = {sub.unwrapped.sim.client._client for sub in env.envs}
        assert len(clients) == 2
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs)
        obs, reward, *_ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs) and reward.shape == (2,)
    finally:
        env.close()


@pytest.mark.parametrize("env_id", ALL_IDS)
def test_specs_serialise_to_json_for_datasets(env_id):
    """Minari stores the env spec as JSON, which a callable entry point would break."""
    spec = gym.spec(env_id)
    assert gym.envs.registration.EnvSpec.from_json(spec.to_json()) == spec


def test_register_envs_accepts_the_package_in_a_fresh_process():
    code = ("import gymnasium as gym, sandbox.envs; gym.register_envs(sandbox.envs); "
            "print(sorted(i for i in gym.registry if i.startswith('sandbox/')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300, check=True)
    assert out.stdout.strip().splitlines()[-1] == str(sorted(ALL_IDS))


@pytest.mark.parametrize("kwargs, message", [
    ({"num_envs": 0}, "num_envs"),
    ({"num_envs": True}, "num_envs"),
    ({"vectorizer": "threads"}, "vectorizer"),
    ({"context": "fork"}, "context"),
    ({"family": "cups"}, "family"),
])
def test_make_vector_env_rejects_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        make_vector_env(**kwargs)

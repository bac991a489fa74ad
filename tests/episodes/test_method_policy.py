"""The other methods drive the environments like the IProMP policy (``episodes --policies bip``)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import sandbox.envs  # noqa: F401  (registers the environments)
from sandbox.episodes.libraries import library_of
from sandbox.episodes.method_policy import MethodPolicy
from sandbox.episodes.policies import fit_family_model


def test_the_episodes_models_keep_their_demos_for_the_methods():
    model = fit_family_model("diverging")
    library = library_of(model)
    assert library.exact and library is library_of(model)
    assert [w.shape[0] for w in library.weights] == [t.n_demos for t in model.task_models]


@pytest.mark.parametrize("method", ["bip", "nearest"])
def test_a_method_policy_hands_over_in_a_diverging_episode(method):
    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    policy = MethodPolicy(fit_family_model("diverging"), method, dow_t=0.2)
    obs, info = env.reset(seed=3)
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        done = terminated or truncated
    env.close()
    assert policy.predictor.updates and policy.history
    assert set(policy.task_posterior) == set(policy.predictor.model.tasks)
    if method == "bip":       # measured: BIP recognises this episode and hands over
        assert policy.task == info["task"] and info["is_success"]


def test_an_unknown_method_names_the_valid_ones():
    with pytest.raises(ValueError, match="^method: expected one of bip, ebip, dtw, nearest, "
                                         "got 'static'$"):
        MethodPolicy(fit_family_model("diverging"), "static")

"""Policies: the predictor as a controller (velocity limits, gripper, subsampling, reset)."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

import sandbox.policies
from sandbox.data.synthetic.base import Q_HOME
from sandbox.envs.sources import synthetic_motion
from sandbox.policies import (
    MAX_VELOCITY,
    IProMPPolicy,
    StaticPolicy,
    fit_family_model,
)
from sandbox.robot import BaxterKinematics


@pytest.fixture(scope="module")
def model():
    return fit_family_model("diverging")


def observations(task="up", seed=0, hz=50.0, q=Q_HOME, extra_s=1.0):
    """Observations (dicts) of a synthetic motion at ``hz``, the arm fixed at ``q``."""
    motion = synthetic_motion("diverging", task, np.random.default_rng(seed))
    for t in np.arange(0.0, motion.duration + extra_s, 1.0 / hz):
        yield {"hand": motion.measurement(t), "object": motion.position(t) + [0, 0, -0.02],
               "q": np.array(q, dtype=float), "dq": np.zeros(7), "gripper": np.ones(1),
               "time": np.array([t])}


def test_fitted_model_is_cached_per_arguments(model):
    assert fit_family_model("diverging") is model
    assert model.tasks == ("left", "right", "up", "down", "straight")
    assert fit_family_model("two_task", n_per_task=5) is not model


@pytest.mark.parametrize("hz, subsample", [(50.0, 2), (100.0, 5), (20.0, 1), (10.0, 1)])
def test_subsampling_keeps_about_20_observations_per_second(model, hz, subsample):
    policy = IProMPPolicy(model, control_hz=hz)
    assert policy.subsample == subsample == policy.predictor.subsample


def test_targets_move_within_the_speed_limits(model):
    policy = IProMPPolicy(model, dow_t=0.2)
    targets = np.array([policy(obs)[:7] for obs in observations()])
    steps = np.abs(np.diff(np.vstack([Q_HOME, targets]), axis=0))
    assert np.all(steps <= MAX_VELOCITY / 50.0 + 1e-12)
    assert np.abs(targets[-1] - Q_HOME).max() > 0.2  # it does move
    assert policy.predictor.updates  # and re-predicted along the way


def test_dynamic_policy_recognises_the_task(model):
    for task in ("left", "down"):
        policy = IProMPPolicy(model)
        for obs in observations(task, seed=1):
            policy(obs)
        assert policy.task == task
        assert policy.task_posterior[task] > 0.5
        assert policy.history[-1][1] == task and len(policy.history) > 100


def test_static_policy_predicts_once(model):
    policy = StaticPolicy(model, ratio=0.3)
    for obs in observations():
        policy(obs)
    assert len(policy.predictor.updates) == 1
    assert policy.predictor.updates[0].time == pytest.approx(policy.predictor.decision_time,
                                                             abs=0.05)


def test_gripper_closes_only_near_the_object(model):
    policy = IProMPPolicy(model)
    tip = BaxterKinematics().fk(Q_HOME, link="left_gripper")
    obs = next(observations())
    near = {**obs, "object": tip + [0.02, 0.0, 0.02]}
    far = {**obs, "object": tip + [0.05, 0.0, 0.0]}
    assert policy(near)[7] == 1.0
    policy.reset()
    assert policy(far)[7] == -1.0


def test_time_going_back_starts_a_new_episode(model):
    policy = IProMPPolicy(model)
    for obs in observations(extra_s=0.0):
        policy(obs)
    assert policy.predictor.updates
    policy(next(observations()))
    assert not policy.predictor.updates and len(policy.history) == 1


def test_missing_hand_samples_are_skipped(model):
    policy = IProMPPolicy(model)
    obs = next(observations())
    action = policy({**obs, "hand": np.full(3, np.nan)})
    assert np.isfinite(action).all() and policy.predictor.n_skipped == 1


@pytest.mark.parametrize("kwargs, match", [
    ({"control_hz": 0.0}, "control_hz"),
    ({"close_radius": -0.1}, "close_radius"),
    ({"max_velocity": np.ones(6)}, "max_velocity"),
    ({"max_velocity": -np.ones(7)}, "max_velocity"),
    ({"dow_t": 0.0}, "dow_t"),
])
def test_bad_arguments_are_refused(model, kwargs, match):
    with pytest.raises(ValueError, match=match):
        IProMPPolicy(model, **kwargs)


def test_bad_observation_is_refused(model):
    policy = IProMPPolicy(model)
    obs = next(observations())
    with pytest.raises(ValueError, match="q"):
        policy({**obs, "q": np.zeros(6)})
    with pytest.raises(ValueError, match="hand"):
        policy({**obs, "hand": np.zeros(2)})


def test_unfitted_model_is_refused():
    from sandbox.core import IProMP

    with pytest.raises(RuntimeError, match="not fitted"):
        StaticPolicy(IProMP())


def test_docstring_example_runs():
    result = doctest.testmod(sandbox.policies, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0

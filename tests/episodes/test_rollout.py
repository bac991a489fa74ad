"""The one episode loop (:func:`rollout`) and what a policy shows of itself (:class:`Beliefs`)."""

from __future__ import annotations

import doctest
import math

import numpy as np
import pytest

import sandbox.envs  # noqa: F401
import sandbox.episodes.rollout
from sandbox.episodes.demos_recording import HeldRobot
from sandbox.episodes.policies import IProMPPolicy, RecordedRobotPolicy, fit_family_model
from sandbox.episodes.policy import Beliefs, Policy, beliefs_of
from sandbox.episodes.rollout import Step, rollout
from sandbox.robot import Q_HOME


@pytest.fixture(scope="module")
def model():
    return fit_family_model("diverging", n_per_task=6, seed=0)


def _by_hand(env, policy, seed, n):
    """The loop written out: the reference the rollout must reproduce."""
    obs, _ = env.reset(seed=seed)
    policy.reset()
    out = []
    for _ in range(n):
        action = policy(obs)
        obs, reward, terminated, truncated, info = env.step(action)
        out.append((action, obs["q"], reward))
    return out


def test_rollout_takes_the_same_steps_as_the_loop_written_out(env, model):
    expected = _by_hand(env, IProMPPolicy(model), 5, 12)
    seen = []
    last = rollout(env, IProMPPolicy(model), seed=5, max_steps=12,
                   on_step=lambda s: seen.append((s.action, s.obs["q"], s.reward)))
    assert last.n == 12 and len(seen) == 12
    for (a, q, r), (b, p, s) in zip(expected, seen):
        assert np.array_equal(a, b) and np.array_equal(q, p) and r == s


def test_hooks_see_the_reset_then_every_step_and_until_stops_before_a_step(env, model):
    calls = []
    last = rollout(env, IProMPPolicy(model), seed=1, options={"task": "up"},
                   on_reset=lambda s: calls.append(("reset", s.n, s.reset_info["task"])),
                   on_step=lambda s: calls.append(("step", s.n, s.time)),
                   until=lambda s: s.n == 3)
    assert calls[0] == ("reset", 0, "up")
    assert [c[1] for c in calls[1:]] == [1, 2, 3] and last.n == 3 and not last.done
    assert calls[-1][2] == pytest.approx(3 * 0.02)
    assert last.previous is not None and last.previous["time"][0] == pytest.approx(0.04)


def test_rollout_runs_to_the_end_of_the_episode(env):
    class Hold:
        def reset(self):
            pass

        def __call__(self, obs):
            return np.append(Q_HOME, -1.0)

    last = rollout(env, Hold(), seed=0)
    assert isinstance(last, Step) and last.done and last.truncated and last.n == 300


def test_policies_follow_the_protocol_and_show_their_beliefs(model):
    policy = IProMPPolicy(model)
    assert isinstance(policy, Policy)
    beliefs = policy.beliefs
    assert beliefs.tasks == tuple(model.tasks) and beliefs.n_updates == 0
    assert beliefs.task == policy.task and beliefs.task_posterior == policy.task_posterior
    held = HeldRobot(policy)
    assert isinstance(held, Policy) and held.beliefs.tasks == beliefs.tasks
    robot = RecordedRobotPolicy(np.arange(3) * 0.1, np.zeros((3, 7)), "left")
    assert isinstance(robot, Policy)
    assert robot.beliefs.task == "left" and robot.beliefs.task_posterior == {"left": 1.0}
    with pytest.raises(RuntimeError, match="no predictor"):
        robot.beliefs.plan()


def test_beliefs_are_a_snapshot_of_the_predictor(env, model):
    policy = IProMPPolicy(model)
    rollout(env, policy, seed=2, max_steps=40)
    beliefs, predictor = policy.beliefs, policy.predictor
    assert beliefs.updates == tuple(predictor.updates) and beliefs.n_updates >= 1
    assert beliefs.duration == predictor.duration and beliefs.alpha == predictor.alpha
    for got, want in zip(beliefs.plan(), predictor.plan()):
        assert np.array_equal(got, want)
    assert np.array_equal(beliefs.command(0.5)[0], predictor.command(0.5)[0])
    assert np.array_equal(beliefs.observations()[0], predictor.observations()[0])
    with pytest.raises(AttributeError):
        beliefs.task = "other"  # frozen


def test_a_policy_without_beliefs_is_read_by_its_task():
    class Bare:
        task = "up"

    assert beliefs_of(Bare()) == Beliefs(task="up")
    assert beliefs_of(object()).task == "" and math.isnan(beliefs_of(object()).duration)


def test_docstring_example_runs():
    result = doctest.testmod(sandbox.episodes.rollout, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0

"""Policies: the predictor as a controller (velocity limits, gripper, subsampling, reset)."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

import sandbox.episodes.policies
from sandbox.envs.sources import synthetic_motion
from sandbox.episodes.policies import (
    IProMPPolicy,
    RecordedRobotPolicy,
    StaticPolicy,
    fit_family_model,
    modality_values,
)
from sandbox.robot import Q_HOME, BaxterKinematics, joint_speed_limits

MAX_VELOCITY = joint_speed_limits()  # the policies' default


@pytest.fixture(scope="module")
def model():
    return fit_family_model("diverging")


@pytest.fixture(scope="module")
def arm_model():
    return fit_family_model("diverging", n_per_task=8, observe="hand,arm")


def observations(task="up", seed=0, hz=50.0, q=Q_HOME, extra_s=1.0, body=False):
    """Observations (dicts) of a synthetic motion at ``hz``, the arm fixed at ``q``.

    With ``body`` they carry the v1 entries: the arm, and no EMG (flag 0).
    """
    motion = synthetic_motion("diverging", task, np.random.default_rng(seed))
    for t in np.arange(0.0, motion.duration + extra_s, 1.0 / hz):
        obs = {"hand": motion.measurement(t), "object": motion.position(t) + [0, 0, -0.02],
               "q": np.array(q, dtype=float), "dq": np.zeros(7), "gripper": np.ones(1),
               "time": np.array([t])}
        if body:
            obs.update(arm=motion.body_measurement("arm", t), arm_valid=np.ones(1, np.int8),
                       emg=np.zeros(8), emg_valid=np.zeros(1, np.int8))
        yield obs


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
    result = doctest.testmod(sandbox.episodes.policies, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_modality_values_turn_unflagged_entries_into_nan():
    obs = {"hand": np.ones(3), "arm": np.zeros(6), "arm_valid": np.zeros(1, np.int8),
           "emg": np.full(8, 5.0), "emg_valid": np.ones(1, np.int8)}
    values = modality_values(obs, ["hand", "arm", "emg"])
    assert np.isnan(values["arm"]).all() and values["emg"][0] == 5.0
    assert obs["arm"][0] == 0.0  # not changed
    assert set(modality_values({"hand": np.ones(3)}, ["hand", "arm"], required=False)) == {"hand"}
    with pytest.raises(ValueError, match="'arm' entry"):
        modality_values({"hand": np.ones(3)}, ["hand", "arm"])
    with pytest.raises(ValueError, match="names"):
        modality_values(obs, ["leg"])


def test_policy_feeds_every_modality_its_model_has(model, arm_model):
    assert IProMPPolicy(model).observe == ("hand",)
    policy = IProMPPolicy(arm_model)
    assert policy.observe == ("hand", "arm")
    for obs in observations(body=True):
        policy(obs)
    _, y = policy.predictor.stream.observations()
    assert np.isfinite(y).all()  # the arm was fed at every kept step
    restricted = IProMPPolicy(arm_model, observe="hand")
    for obs in observations(body=True):
        restricted(obs)
    _, y = restricted.predictor.stream.observations()
    assert np.isnan(y[:, 3:]).all() and np.isfinite(y[:, :3]).all()


def test_a_missing_modality_is_marginalised_not_zero_filled(arm_model):
    with_arm, without_arm, legacy = (IProMPPolicy(arm_model) for _ in range(3))
    hand_only = IProMPPolicy(arm_model, observe="hand")
    for obs in observations(task="left", body=True):
        unflagged = {**obs, "arm": np.zeros(6), "arm_valid": np.zeros(1, np.int8)}
        v0 = {k: v for k, v in obs.items() if k not in ("arm", "arm_valid", "emg", "emg_valid")}
        actions = [with_arm(obs), without_arm(unflagged), legacy(v0), hand_only(obs)]
    _, y = without_arm.predictor.stream.observations()
    assert np.isnan(y[:, 3:]).all()  # NaN (marginalised), not zeros
    np.testing.assert_array_equal(actions[1], actions[3])  # same as observing the hand only
    np.testing.assert_array_equal(actions[2], actions[3])  # a v0 observation: the same
    assert without_arm.task == with_arm.task == "left"


def test_explicit_observe_is_checked(arm_model, model):
    with pytest.raises(ValueError, match="observe"):
        IProMPPolicy(model, observe="hand,arm")  # not the model's
    with pytest.raises(ValueError, match="environments observe"):
        StaticPolicy(arm_model, observe=["hand", "leg"])
    policy = StaticPolicy(arm_model, observe=["hand", "arm"])
    obs = next(observations())
    with pytest.raises(ValueError, match="'arm' entry"):
        policy(obs)  # a v0 observation lacks the arm it must observe


def test_recorded_robot_policy_follows_the_recording_within_the_speed_limits():
    times = np.linspace(10.0, 12.0, 21)                  # absolute times: the trial starts at 0
    robot = Q_HOME + np.outer(np.linspace(0.0, 0.2, 21), np.ones(7))   # 0.1 rad/s per joint
    policy = RecordedRobotPolicy(times, robot, "pencil_box")
    obs = next(observations(q=robot[0]))
    tip = BaxterKinematics().fk(robot[0], link="left_gripper")
    first = policy({**obs, "time": np.array([0.0]), "object": tip + [0.2, 0.0, 0.0]})
    np.testing.assert_allclose(first[:7], Q_HOME + 0.1 * policy.dt, atol=1e-12)
    assert first[7] == -1.0 and policy.task == "pencil_box"
    assert policy.task_posterior == {"pencil_box": 1.0}
    policy.reset()
    far = policy({**obs, "time": np.array([5.0]), "object": tip + [0.01, 0.0, 0.0]})
    # past the end: the last recorded pose, reached no faster than the speed limit allows
    np.testing.assert_allclose(far[:7], robot[0] + np.minimum(0.2, MAX_VELOCITY * policy.dt))
    assert far[7] == 1.0


@pytest.mark.parametrize("kwargs, match", [
    ({"times": [0.0, 0.0]}, "increasing"),
    ({"robot": np.zeros((2, 6))}, "robot"),
    ({"task": ""}, "task"),
    ({"close_radius": -1.0}, "close_radius"),
])
def test_recorded_robot_policy_refuses_bad_arguments(kwargs, match):
    args = {"times": [0.0, 1.0], "robot": np.zeros((2, 7)), "task": "t", **kwargs}
    with pytest.raises(ValueError, match=match):
        RecordedRobotPolicy(args.pop("times"), args.pop("robot"), args.pop("task"), **args)


def test_a_slower_tracker_feeds_the_predictor_its_frames_stamped_with_their_time(model):
    """Issue 16 item 6: rows without a new frame (``hand_valid`` 0) are skipped, the others
    are observed at the frame's own time (``hand_time``), not at the step's."""
    motion = synthetic_motion("diverging", "up", np.random.default_rng(0))
    policy, given, stale = IProMPPolicy(model), None, 0
    for t in np.arange(0.0, 1.5, 0.02):
        frame = motion.frame_time(t)
        stale += frame == given
        obs = {"hand": motion.measurement(t), "hand_valid": np.array([frame != given], np.int8),
               "hand_time": np.array([frame]), "object": np.zeros(3), "q": Q_HOME.copy(),
               "time": np.array([t])}
        given = frame
        policy(obs)
    times, _ = policy.predictor.observations()
    assert stale > 0 and policy.predictor.n_skipped == stale
    frames = {motion.frame_time(t) for t in np.arange(0.0, 1.5, 0.02)}
    assert set(times) <= frames and len(times) == (len(frames) + 1) // 2  # subsample 2
    assert policy.beliefs.n_updates >= 5 and policy.beliefs.updates[-1].time in frames


def test_without_frame_entries_the_step_time_stamps_the_row(model):
    from sandbox.episodes.policies import tracker_row

    obs = next(observations())
    t, values = tracker_row({**obs, "time": np.array([0.5])}, ["hand"])
    assert t == 0.5 and np.array_equal(values["hand"], obs["hand"])
    t, values = tracker_row({**obs, "hand_time": np.array([0.4]), "hand_valid": np.zeros(1)},
                            ["hand"])
    assert t == 0.4 and np.isnan(values["hand"]).all()

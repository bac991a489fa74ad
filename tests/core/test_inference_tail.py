"""The robot is conditioned on the motion only, not on what the hand does after the meeting
(:func:`sandbox.core.inference.conditioned_robot`, issue 21)."""

import numpy as np
import pytest

from sandbox.core import IProMP, predict
from sandbox.core.inference import conditioned_robot
from sandbox.core.likelihood import Scorer
from sandbox.core.stream import ObservationStream

from . import synth


@pytest.fixture(scope="module")
def setup():
    model = IProMP(n_basis=9).fit(synth.demos(np.random.default_rng(0), n_per_task=8))
    demo = synth.demos(np.random.default_rng(1), n_per_task=1)[0]        # task0, unseen
    stream = ObservationStream(model, subsample=5)
    for t, y in zip(demo.times - demo.times[0], demo.human):
        stream.accept(t, y)
    times, values = stream.observations()
    T = float(times[-1])
    # the hand retracts 15 cm after the meeting, for 0.4 s
    tail_t = T + 0.05 * np.arange(1, 9)
    tail_y = np.repeat(values[-1:] - np.array([0.15, 0.0, 0.0]), tail_t.size, axis=0)
    return model, Scorer(model), times, values, np.r_[times, tail_t], np.vstack([values, tail_y])


def test_a_tail_after_the_end_does_not_move_the_robot(setup):
    model, scorer, times, values, long_t, long_y = setup
    T = float(times[-1])
    short = predict(model, scorer, times, values, task=0, duration=T)
    tail = predict(model, scorer, long_t, long_y, task=0, duration=T)
    np.testing.assert_allclose(tail.robot.mean, short.robot.mean, rtol=0, atol=1e-10)
    np.testing.assert_allclose(tail.robot.factor, short.robot.factor, rtol=0, atol=1e-10)
    # ... though the tail is still scored: it is evidence for the task and the speed
    assert not np.allclose(tail.log_likelihood, short.log_likelihood)


def test_observations_before_the_end_do_move_the_robot(setup):
    model, scorer, times, values, _, _ = setup
    T = float(times[-1])
    full = predict(model, scorer, times, values, task=0, duration=T)
    half = predict(model, scorer, times[:times.size // 2], values[:times.size // 2],
                   task=0, duration=T)
    assert np.abs(full.robot.mean - half.robot.mean).max() > 1e-3


def test_the_reused_factor_is_the_recomputed_one(setup):
    model, scorer, times, values, _, _ = setup
    pred = predict(model, scorer, times, values)               # factors of all observations
    k, T = pred.task_index, pred.duration
    again = conditioned_robot(model, scorer, times, values, k, T)      # recomputed
    np.testing.assert_allclose(pred.robot.mean, again.mean, rtol=0, atol=1e-9)


@pytest.mark.parametrize("k", [0, 1])
def test_for_task_conditions_as_predict_does(setup, k):
    model, scorer, _, _, long_t, long_y = setup
    pred = predict(model, scorer, long_t, long_y)
    other = pred.for_task(model, k, scorer=scorer)
    direct = predict(model, scorer, long_t, long_y, task=k, duration=float(pred.durations[k]))
    np.testing.assert_allclose(other.robot.mean, direct.robot.mean, rtol=0, atol=1e-9)
    assert other.duration == pytest.approx(float(pred.durations[k]))

import numpy as np
import pytest

from sandbox.core.model import IProMP
from sandbox.core.predictor import DynamicPredictor, StaticPredictor

from . import synth


@pytest.fixture(scope="module")
def model():
    rng = np.random.default_rng(0)
    return IProMP(n_basis=15).fit(synth.demos(rng, n_per_task=10, n_tasks=3, noise=0.003))


def _stream(pred, demo):
    for t, y in zip(demo.times, demo.human):
        pred.observe(t, y)
    return pred


@pytest.mark.parametrize("task", [0, 1, 2])
def test_separated_tasks_are_recognised(model, task):
    demo = synth.replay(task, 2.1, noise=0.003, rng=np.random.default_rng(task))
    pred = _stream(DynamicPredictor(model, dow_t=0.2), demo)
    assert pred.task == f"task{task}"
    assert pred.task_posterior[f"task{task}"] > 0.99
    assert pred.duration == pytest.approx(2.1, rel=0.05)
    mean, _ = pred.command(demo.times[-1])
    np.testing.assert_allclose(mean, demo.robot[-1], atol=0.05)


def test_updates_happen_at_window_boundaries(model):
    demo = synth.replay(0, 2.0)
    pred = _stream(DynamicPredictor(model, dow_t=0.5), demo)
    np.testing.assert_allclose([u.time for u in pred.updates], [0.5, 1.0, 1.5, 2.0], atol=1e-9)
    assert all(np.isfinite(u.jump) and u.jump >= 0 for u in pred.updates)


def test_before_first_update_follows_prior_mixture(model):
    pred = DynamicPredictor(model, dow_t=0.2)
    P = model.n_human
    from sandbox.core.promp import trajectory_distribution

    t = np.array([0.7])
    means, covs = [], []
    for task in model.task_models:
        m, c = trajectory_distribution(task.weights.dims(slice(P, None)), model.basis,
                                       np.clip(t / task.mean_duration, 0, 1))
        means.append(m[0])
        covs.append(c[0])
    mix = np.mean(means, axis=0)
    cov = np.mean([c + np.outer(m - mix, m - mix) for m, c in zip(means, covs)], axis=0)
    mean_cmd, cov_cmd = pred.command(0.7)
    np.testing.assert_allclose(mean_cmd, mix, atol=1e-6)   # knots every dt: linear interp
    np.testing.assert_allclose(cov_cmd, cov, atol=1e-6)


def test_executed_commands_are_never_rewritten(model):
    demo = synth.replay(1, 2.2)
    pred = DynamicPredictor(model, dow_t=0.1)
    executed = []
    for t, y in zip(demo.times, demo.human):
        executed.append(pred.command(t)[0])
        pred.observe(t, y)
    after = np.array([pred.command(t)[0] for t in demo.times])
    np.testing.assert_allclose(after, np.array(executed), atol=1e-12)


def test_covariances_stay_spd_after_any_updates(model):
    rng = np.random.default_rng(5)
    pred = DynamicPredictor(model, dow_t=0.1)
    t = 0.0
    for _ in range(300):   # random walk of the hand, not like any task
        t += 0.01
        pred.observe(t, np.array([1.0, 0.0, 0.2]) + rng.normal(0, 0.2, 3))
    _, _, covs = pred.plan()
    assert len(pred.updates) == 30
    np.testing.assert_allclose(covs, covs.transpose(0, 2, 1), atol=1e-15)
    assert np.linalg.eigvalsh(covs).min() > 0


def test_conditioning_never_widens_the_robot_distribution(model):
    demo = synth.replay(2, 2.0)
    pred = _stream(DynamicPredictor(model, dow_t=1.0), demo)
    k = model.task_index(pred.task)
    P = model.n_human
    prior = model.task_models[k].weights.dims(slice(P, None)).cov()
    post = pred.last_prediction.robot.cov()
    assert np.linalg.eigvalsh(prior - post).min() > -1e-10


def test_nan_rows_are_skipped_not_propagated(model):
    demo = synth.replay(0, 2.0)
    clean = _stream(DynamicPredictor(model, dow_t=0.2), demo)
    pred = DynamicPredictor(model, dow_t=0.2)
    rows = []
    for i, (t, y) in enumerate(zip(demo.times, demo.human)):
        rows.append((t, y))
        if i % 7 == 3:
            rows.append((t, np.array([np.nan, 0.0, 0.0])))
    for t, y in rows:
        pred.observe(t, y)
    assert pred.n_skipped == sum(1 for i in range(demo.times.size) if i % 7 == 3)
    np.testing.assert_allclose(pred.observations()[0], clean.observations()[0])
    np.testing.assert_allclose(pred.command(2.0)[0], clean.command(2.0)[0])


def test_subsample_keeps_one_in_five(model):
    demo = synth.replay(0, 1.0)
    pred = _stream(DynamicPredictor(model, dow_t=10.0), demo)
    np.testing.assert_allclose(pred.observations()[0], demo.times[::5])


def test_latest_window_mode_uses_only_its_window(model):
    demo = synth.replay(0, 2.0)
    pred = _stream(DynamicPredictor(model, dow_t=0.5, window="latest"), demo)
    counts = [u.n_observations for u in pred.updates]
    assert counts[0] == 11 and all(c == 10 for c in counts[1:])


def test_static_predicts_once_at_the_ratio(model):
    demo = synth.replay(1, 2.0)
    pred = _stream(StaticPredictor(model, ratio=0.4, expected_duration=2.0), demo)
    assert len(pred.updates) == 1
    assert pred.updates[0].time == pytest.approx(0.8)
    online = StaticPredictor(model, ratio=0.5)
    prior_T = np.dot(model.priors, [t.mean_duration for t in model.task_models])
    assert online.decision_time == pytest.approx(0.5 * prior_T)
    mean, _ = pred.prediction(np.array([2.0]))
    assert mean.shape == (1, 7)


def test_errors(model):
    pred = DynamicPredictor(model)
    with pytest.raises(ValueError, match=r"expected 3 values \(hand \(3\)\), got 2"):
        pred.observe(0.0, [1.0, 2.0])
    pred.observe(0.5, [1.0, 0.0, 0.2])
    with pytest.raises(ValueError, match="previous"):
        pred.observe(0.4, [1.0, 0.0, 0.2])
    with pytest.raises(ValueError, match="infinity"):
        pred.observe(0.6, [np.inf, 0.0, 0.2])
    with pytest.raises(RuntimeError, match="no update"):
        StaticPredictor(model).prediction([0.1])
    with pytest.raises(RuntimeError, match="not fitted"):
        DynamicPredictor(IProMP())
    with pytest.raises(ValueError, match="dow_t"):
        DynamicPredictor(model, dow_t=0)
    with pytest.raises(ValueError, match="ratio"):
        StaticPredictor(model, ratio=1.5)
    with pytest.raises(ValueError, match="likelihood"):
        DynamicPredictor(model, likelihood="nope")


def test_incremental_statistics_give_the_same_predictions(model):
    demo = synth.replay(2, 2.3, noise=0.003, rng=np.random.default_rng(9))
    fast = _stream(DynamicPredictor(model, dow_t=0.3), demo)
    cold = _stream(DynamicPredictor(model, dow_t=0.3, incremental=False), demo)
    for a, b in zip(fast.updates, cold.updates):
        np.testing.assert_allclose(a.log_likelihood, b.log_likelihood, rtol=1e-9)
        np.testing.assert_allclose(a.durations, b.durations, rtol=1e-9)
    np.testing.assert_allclose(fast.plan()[1], cold.plan()[1], atol=1e-9)


def test_horizon_extends_the_plan_past_the_update(model):
    demo = synth.replay(0, 2.0)
    pred = DynamicPredictor(model, dow_t=0.5, horizon=2.0)
    for t, y in zip(demo.times, demo.human):
        if t > 0.6:
            break
        pred.observe(t, y)
    times, _, _ = pred.plan()
    assert times[-1] >= 0.5 + 2.0 - 1e-9


def test_update_on_a_plan_knot_keeps_knots_strictly_increasing(model):
    """Regression: an update exactly on a knot used to duplicate it (division by zero)."""
    pred = DynamicPredictor(model, dow_t=0.1)
    demo = synth.replay(0, 2.0)
    with np.errstate(divide="raise", invalid="raise"):
        for t, y in zip(np.round(demo.times, 2), demo.human):
            pred.observe(t, y)
            mean, _ = pred.command(t)
            assert np.isfinite(mean).all()
    times, means, _ = pred.plan()
    assert np.all(np.diff(times) > 0)
    assert np.isfinite(pred.commands(times)[0]).all()


def _with_tail(task: int, other: int, duration: float = 2.0):
    """Task ``task`` replayed, then the hand wanders to ``other``'s end over 1 s and stays:
    motion after the handover that looks like another task's."""
    demo = synth.replay(task, duration, noise=0.003, rng=np.random.default_rng(3))
    end_other = synth.shape(other, np.ones(1))[0][0]
    s = np.linspace(0, 1, 100)[:, None]
    tail = demo.human[-1] + (end_other - demo.human[-1]) * (3 * s**2 - 2 * s**3)
    tail = np.vstack([tail, np.repeat(tail[-1:], 300, axis=0)])
    times = np.r_[demo.times, demo.times[-1] + 0.01 * np.arange(1, tail.shape[0] + 1)]
    return times, np.vstack([demo.human, tail])


def test_the_task_is_held_once_the_motion_is_over(model):
    """Regression (late decay): motion after the handover is no evidence about the task."""
    times, human = _with_tail(0, 1)
    held = DynamicPredictor(model, dow_t=0.2)
    free = DynamicPredictor(model, dow_t=0.2, until_end=False)
    for t, y in zip(times, human):
        held.observe(t, y)
        free.observe(t, y)
    assert free.task == "task1"                      # the tail drags an open decision away
    assert held.ended and held.task == "task0"
    first = next(i for i, u in enumerate(held.updates) if u.after_end)
    assert held.updates[first - 1].time < 2.0 + 0.45 and first < len(held.updates) - 3
    for u in held.updates[first:]:
        assert u.task == "task0"
        np.testing.assert_array_equal(u.task_posterior, held.updates[first - 1].task_posterior)
    held.reset()
    assert not held.ended and not held.updates


def test_until_end_options(model):
    with pytest.raises(ValueError, match="end_prob"):
        DynamicPredictor(model, end_prob=0.0)
    times, human = _with_tail(2, 0)
    pred = DynamicPredictor(model, dow_t=0.2, likelihood="marginal", until_end=True)
    for t, y in zip(times, human):
        pred.observe(t, y)
    assert pred.ended and pred.task == "task2"       # marginal: the plan just holds
    assert not any(u.after_end for u in pred.updates)


def test_an_update_after_the_predicted_end_takes_over_the_plan(model):
    """Regression: a plan used to end one knot after an update past the predicted end, so
    the blend never completed and the command kept the old plan."""
    times, human = _with_tail(1, 2)
    pred = DynamicPredictor(model, dow_t=1.0, until_end=False)
    for t, y in zip(times, human):
        pred.observe(t, y)
    last = pred.updates[-1]
    assert last.time > last.duration + 0.5                    # past the predicted end
    plan_t, _, _ = pred.plan()
    assert plan_t[-1] >= last.time + pred.blend_delay + 10 / pred.blend_rate - 1e-9
    mean, _ = pred.command(last.time + 0.5)
    new, _ = pred.prediction(np.array([last.time + 0.5]))
    np.testing.assert_allclose(mean, new[0], atol=1e-3)


def _drift_back(task: int, duration: float = 2.0, back: float = 0.6):
    """Task ``task`` replayed; after the meeting the hand waits 0.2 s, then drifts ``back``
    of the way to its start over 0.6 s and stays there (a tail every task explains badly)."""
    demo = synth.replay(task, duration, noise=0.003, rng=np.random.default_rng(5))
    start, end = demo.human[0], demo.human[-1]
    x = np.clip((np.arange(1, 131) * 0.01 - 0.2) / 0.6, 0, 1)[:, None]
    tail = end + back * (start - end) * x**3 * (10 - 15 * x + 6 * x**2)
    times = np.r_[demo.times, demo.times[-1] + 0.01 * np.arange(1, 131)]
    return times, np.vstack([demo.human, tail])


@pytest.mark.parametrize("task", [0, 1, 2])
def test_a_drift_back_after_the_meeting_does_not_move_the_task_posterior(model, task):
    """Known answer: the motion ends at 2 s; the right task, recognised by then, is the one
    held, with the posterior of an update made at most 0.4 s after the meeting, before the
    drift is under way (``end_prob`` 0.5: a duration posterior that puts half its mass before
    the update's time already means that the motion is over)."""
    times, human = _drift_back(task)
    pred = DynamicPredictor(model, dow_t=0.2)
    late = DynamicPredictor(model, dow_t=0.2, end_prob=0.9)
    for t, y in zip(times, human):
        pred.observe(t, y)
        late.observe(t, y)
    at_meeting = [u for u in pred.updates if u.time <= 2.0 + 1e-9][-1]
    assert at_meeting.task == f"task{task}"
    assert pred.ended and pred.task == f"task{task}"
    assert pred.task_posterior[f"task{task}"] >= 0.9
    decided = next(i for i, u in enumerate(pred.updates) if u.after_end) - 1
    assert pred.updates[decided].time <= 2.0 + 0.4 + 1e-9
    assert decided <= next(i for i, u in enumerate(late.updates) if u.after_end) - 1


def test_with_window_predicts_as_a_new_predictor_and_shares_only_the_model_parts(model):
    demo = synth.replay(1, 2.0, noise=0.003, rng=np.random.default_rng(3))
    first = DynamicPredictor(model, dow_t=0.2, subsample=2)
    _stream(first, demo)
    copy = first.with_window(0.5)
    assert copy.dow_t == 0.5 and not copy.updates and copy.observations()[0].size == 0
    assert copy.scorer is first.scorer and copy.subsample == 2
    fresh = _stream(DynamicPredictor(model, dow_t=0.5, subsample=2), demo)
    _stream(copy, demo)
    assert [u.time for u in copy.updates] == [u.time for u in fresh.updates] == [0.5, 1.0, 1.5,
                                                                                  2.0]
    for a, b in zip(copy.updates, fresh.updates):
        np.testing.assert_array_equal(a.task_posterior, b.task_posterior)
    for a, b in zip(copy.plan(), fresh.plan()):
        np.testing.assert_array_equal(a, b)
    assert len(first.updates) == 10 and first.observations()[0].size == fresh.observations()[0].size
    with pytest.raises(ValueError, match="dow_t"):
        first.with_window(0.0)

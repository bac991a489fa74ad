import numpy as np
import pytest

from sandbox.core import DynamicPredictor, IProMP
from sandbox.data.synthetic import make_dataset
from sandbox.eval.loocv import EvalConfig, evaluate_trial, kept_observations, run_loocv
from sandbox.robot import BaxterKinematics


@pytest.fixture(scope="module")
def setup():
    demos = make_dataset("diverging", 6, np.random.default_rng(0))
    demos = [d for d in demos if d.task in ("left", "right")]
    model = IProMP(n_basis=15).fit(demos[1:])
    return model, demos


def test_shared_estimates_equal_a_streamed_predictor(setup):
    """The evaluation's shortcut (one estimate per update time) equals streaming each window;
    its goal errors (forward kinematics of all updates at once) equal one call per update."""
    from sandbox.eval.metrics import time_to_correct

    model, demos = setup
    test = demos[0]
    config = EvalConfig(windows=(0.5, 0.2), ratios=(0.5,), subsample=2, n_basis=15,
                        goal_tol=0.2)
    fk = BaxterKinematics().fk
    res = evaluate_trial(model, test, config, fk)
    t = test.times - test.times[0]
    goal = fk(test.robot[-1])
    for w in (0.5, 0.2):
        pred = DynamicPredictor(model, dow_t=w, **config.predictor_options())
        at, errors = [], []
        for ti, yi in zip(t, test.human):
            if pred.observe(ti, yi) is not None:
                at.append(ti / t[-1])
                errors.append(np.linalg.norm(fk(pred.plan()[1][-1]) - goal))
        mean, _ = pred.commands(t)
        rms = np.sqrt(np.mean((mean - test.robot) ** 2))
        got = res["dynamic"][f"{w:.1f}"]
        assert got["e_q"] == pytest.approx(rms, rel=1e-9)
        assert got["n_updates"] == len(pred.updates)
        assert got["e_p"] == pytest.approx(np.linalg.norm(fk(mean[-1]) - goal), rel=1e-9)
        assert got["time_to_correct"] == time_to_correct(np.array(at), np.array(errors), 0.2)


def test_kept_observations_skip_nan_and_subsample(setup):
    model, _ = setup
    t = np.arange(10.0)
    y = np.ones((10, 3))
    y[[1, 4]] = np.nan
    kt, _ = kept_observations(model, t, y, 2)
    np.testing.assert_array_equal(kt, [0, 3, 6, 8])


def test_kept_observations_from_a_predictors_stream_equal_a_new_streams(setup):
    """``like=`` feeds a reset copy of a predictor's stream: the same observations, and the
    predictor's own stream keeps what it had; a stream of another subsample is refused."""
    model, demos = setup
    test = demos[0]
    t = test.times - test.times[0]
    pred = DynamicPredictor(model, subsample=2)
    pred.observe(t[0], test.human[0])
    want = kept_observations(model, t, test.human, 2)
    got = kept_observations(model, t, test.human, 2, like=pred.stream)
    for a, b in zip(got, want):
        np.testing.assert_array_equal(a, b)
    assert len(pred.stream) == 1 and pred.stream.observations()[0][0] == t[0]
    with pytest.raises(ValueError, match="subsample=3"):
        kept_observations(model, t, test.human, 3, like=pred.stream)


def _multimodal(n_per_task=5):
    from sandbox.data import Demonstration
    from tests.core import synth

    demos = synth.multimodal(np.random.default_rng(7), n_per_task=n_per_task)
    return [Demonstration(d.times, d.human, d.robot, d.task, modalities=d.modalities,
                          source=f"demo{i}") for i, d in enumerate(demos)]


def test_the_normaliser_never_sees_the_held_out_trial(monkeypatch):
    """Each fold's signal scale comes from the other trials only: a held-out trial with
    a hundred times the muscle activity must not move it."""
    import sandbox.eval.loocv as loocv

    demos = _multimodal()
    loud = demos[0].human.copy()
    loud[:, 9:] *= 100.0
    demos[0] = demos[0].replace(human=loud)
    seen = {}

    def capture(model, test, config, fk, truth=None):
        seen[test.source] = model.scale.copy()
        return {}

    monkeypatch.setattr(loocv, "evaluate_trial", capture)
    config = EvalConfig(windows=(0.5,), ratios=(0.5,), n_basis=9)
    run_loocv(demos, demos, config)
    others = config.model().fit(demos[1:])
    np.testing.assert_allclose(seen["demo0"], others.scale, rtol=1e-12)
    everyone = config.model().fit(demos)
    assert np.all(everyone.scale[9:] > 10 * others.scale[9:])     # it would have shown
    for i in (1, 5):
        alone = config.model().fit(demos[:i] + demos[i + 1:])
        np.testing.assert_allclose(seen[f"demo{i}"], alone.scale, rtol=1e-12)


def test_observe_selects_modalities_of_the_demonstrations():
    demos = _multimodal(4)
    config = EvalConfig(windows=(0.5,), ratios=(0.5,), n_basis=9, observe=("emg",))
    results, _ = run_loocv(demos, demos, config)
    assert all(r["dynamic"]["0.5"]["recognition"] == 1.0 for r in results)


def test_loocv_runs_every_trial_and_checks_alignment(setup):
    _, demos = setup
    config = EvalConfig(windows=(0.5,), ratios=(0.3, 0.9), n_basis=15)
    results, wall = run_loocv(demos, demos, config)
    assert len(results) == len(demos) and wall > 0
    assert {r["task"] for r in results} == {"left", "right"}
    with pytest.raises(ValueError, match="same trials"):
        run_loocv(demos, demos[::-1], config)


def _blas_threads() -> set[int]:
    from threadpoolctl import threadpool_info

    return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


def test_folds_run_on_one_blas_thread_and_the_limit_is_lifted_after(setup, monkeypatch):
    from sandbox.eval import loocv

    _, demos = setup
    seen = []
    real = loocv.evaluate_trial
    monkeypatch.setattr(loocv, "evaluate_trial",
                        lambda *a, **k: (seen.append(_blas_threads()), real(*a, **k))[1])
    before = _blas_threads()
    run_loocv(demos[:4], demos[:4], EvalConfig(windows=(0.5,), ratios=(0.5,), n_basis=15))
    assert seen and all(s == {1} for s in seen)
    assert _blas_threads() == before


def test_two_workers_give_the_results_of_one(setup):
    _, demos = setup
    config = EvalConfig(windows=(0.5,), ratios=(0.5,), n_basis=15)
    one, _ = run_loocv(demos, demos, config, workers=1)
    two, _ = run_loocv(demos, demos, config, workers=2)
    assert one == two


def _square(i: int) -> tuple[int, int]:
    return i, i * i


def test_map_trials_with_costs_returns_the_results_in_index_order():
    """Costliest first across two workers, one item at a time: the results still come back
    by index, as without costs and in one process."""
    from sandbox.eval.runner import map_trials

    cost = [3.0, 9.0, 1.0, 7.0, 7.0, 0.5]
    want = [(i, i * i) for i in range(6)]
    for workers in (1, 2):
        assert map_trials(_square, 6, lambda: None, (), workers=workers, cost=cost) == want
    assert map_trials(_square, 6, lambda: None, (), workers=2) == want


@pytest.mark.parametrize("options", [{}, {"shrinkage": "robot"}, {"condition_floor": 0.05}])
def test_oracle_is_the_robot_predict_conditions_at_the_true_task_and_duration(setup, options):
    """The oracle skips predict's phase estimate: the same robot and trajectory, bit for bit,
    also when the robot has a scorer of its own (shrinkage, condition floor)."""
    from sandbox.core import predict
    from sandbox.core.inference import conditioned_robot, held_trajectory
    from sandbox.core.likelihood import Scorer

    _, demos = setup
    model = IProMP(n_basis=15, **options).fit(demos[1:])
    test = demos[0]
    t = test.times - test.times[0]
    t_obs, y_obs = kept_observations(model, t, test.human, 2)
    scorer, k = Scorer(model), model.task_index(test.task)
    for T in (0.8 * t[-1], 1.3 * t[-1]):      # the hold after the end, and none
        robot = conditioned_robot(model, scorer, t_obs, y_obs, k, T)
        expected = predict(model, scorer, t_obs, y_obs, task=k, duration=T)
        np.testing.assert_array_equal(robot.mean, expected.robot.mean)
        np.testing.assert_array_equal(robot.factor, expected.robot.factor)
        for got, want in zip(held_trajectory(robot, T, model.basis, t),
                             expected.trajectory(model.basis, t)):
            np.testing.assert_array_equal(got, want)


def test_times_with_the_same_observations_share_one_prediction(setup, monkeypatch):
    """predictions_at makes one prediction per distinct count of kept observations (a time
    between two kept observations asks what the earlier one did), each equal, bit for bit,
    to what predicting again at every time from the same growing statistics gives."""
    from sandbox.core import predict
    from sandbox.core.likelihood import Scorer
    from sandbox.core.phase import Lattice
    from sandbox.core.statistics import StreamStatistics
    from sandbox.eval import loocv

    model, demos = setup
    test = demos[0]
    t_obs, y_obs = kept_observations(model, test.times - test.times[0], test.human, 2)
    between = [0.5 * (t_obs[i] + t_obs[i + 1]) for i in (3, 8)]
    times = [float(t_obs[3]), between[0], float(t_obs[8]), between[1], float(t_obs[12])]
    config = EvalConfig(n_basis=15)
    opts = dict(likelihood="joint", n_candidates=config.n_candidates, refine_steps=1)
    calls = []
    monkeypatch.setattr(loocv, "predict", lambda *a, **k: (calls.append(a[2].size),
                                                           predict(*a, **k))[1])
    scorer = Scorer(model)
    got = loocv.predictions_at(model, scorer, t_obs, y_obs, times, config, opts)
    assert calls == [4, 9, 13]
    assert got[times[0]] is got[times[1]] and got[times[2]] is got[times[3]]
    stats, fed = StreamStatistics(scorer, Lattice.for_tasks(model.task_models, 50)), 0
    for tau, n in zip(times, (4, 4, 9, 9, 13)):      # a prediction at every time
        for j in range(fed, n):
            stats.add(t_obs[j], y_obs[j])
        fed = n
        want = predict(model, scorer, t_obs[:n], y_obs[:n], stats=stats, **opts)
        np.testing.assert_array_equal(got[tau].task_posterior, want.task_posterior)
        np.testing.assert_array_equal(got[tau].durations, want.durations)
        np.testing.assert_array_equal(got[tau].robot.mean, want.robot.mean)
        np.testing.assert_array_equal(got[tau].robot.factor, want.robot.factor)

import numpy as np
import pytest

from sandbox.core.factor import condition_robot
from sandbox.core.interaction import condition, log_marginal_likelihood, observation_matrix
from sandbox.core.likelihood import Scorer
from sandbox.core.model import IProMP

from . import synth


@pytest.fixture(scope="module")
def fitted():
    return synth.fitted_case()


def _dense(model, k, t, y, T):
    P, Q = model.n_human, model.n_robot
    w = model.task_models[k].weights
    H = observation_matrix(model.basis, t / T, P, Q)
    obs = np.hstack([y, np.full((t.size, Q), np.nan)]).ravel()
    noise = np.tile(np.r_[model.noise, np.ones(Q)], t.size)
    return w, H, obs, noise


def test_joint_matches_dense_likelihood_and_conditioning(fitted):
    model, t, y = fitted
    scorer = Scorer(model)
    durations = np.array([1.6, 2.0, 2.4, 3.0])
    spans = np.array([[0, 4], [1, 3]])
    scores = scorer.joint(t, y, durations, spans)
    P, N = model.n_human, model.basis.n_basis
    for k in range(2):
        for j, c in enumerate(range(*spans[k])):
            w, H, obs, noise = _dense(model, k, t, y, durations[c])
            ll = log_marginal_likelihood(w.mean, w.cov(), H, obs, noise)
            assert scores.loglik[k][j] == pytest.approx(ll, abs=1e-8 * max(1, abs(ll)))
            mean, cov = condition(w.mean, w.cov(), H, obs, noise)
            post = condition_robot(w, scores.factors[k][j], P, scorer.rank[k])
            np.testing.assert_allclose(post.mean, mean[P * N:], atol=1e-10)
            np.testing.assert_allclose(post.cov(), cov[P * N:, P * N:], atol=1e-12)


def test_marginal_matches_sum_of_dense_per_step(fitted):
    model, t, y = fitted
    scores = Scorer(model).marginal(t, y, np.array([2.2]), np.array([[0, 1], [0, 1]]))
    for k in range(2):
        total = 0.0
        for i in range(t.size):
            w, H, obs, noise = _dense(model, k, t[i:i + 1], y[i:i + 1], 2.2)
            total += log_marginal_likelihood(w.mean, w.cov(), H, obs, noise)
        assert scores.loglik[k][0] == pytest.approx(total, rel=1e-10)


def test_distinct_kappas_fall_back_to_groups(fitted):
    """A hand-edited model whose regularisers break the shared ratio still scores exactly."""
    model, t, y = fitted
    import copy

    from sandbox.core.promp import WeightDistribution

    odd = copy.copy(model)
    w = model.task_models[1].weights
    reg = w.reg.copy()
    reg[:3] *= np.array([2.0, 0.5, 3.0])
    tm = model.task_models[1]
    odd.task_models = (model.task_models[0], type(tm)(tm.name, WeightDistribution(
        w.mean, w.factor, reg, w.n_basis), tm.nominal_duration, tm.alpha_mean,
        tm.alpha_std, tm.n_demos))
    scorer = Scorer(odd)
    assert len(scorer.kappas) == 4
    scores = scorer.joint(t, y, np.array([2.0]), np.array([[0, 1], [0, 1]]))
    for k in range(2):
        wk, H, obs, noise = _dense(odd, k, t, y, 2.0)
        ll = log_marginal_likelihood(wk.mean, wk.cov(), H, obs, noise)
        assert scores.loglik[k][0] == pytest.approx(ll, rel=1e-9)


def test_stream_statistics_equal_the_batch_computation(fitted):
    from sandbox.core.phase import Lattice
    from sandbox.core.statistics import StreamStatistics

    model, t, y = fitted
    scorer = Scorer(model)
    lattice = Lattice.for_tasks(model.task_models, n_candidates=12)
    stats = StreamStatistics(scorer, lattice, flush_every=4)
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    spans = lattice.spans()
    streamed = stats.scores(spans)
    batch = scorer.joint(t, y, lattice.durations, spans)
    for k in range(2):
        np.testing.assert_allclose(streamed.loglik[k], batch.loglik[k], rtol=1e-10)
        np.testing.assert_allclose(streamed.factors[k][:, -1, -1], batch.factors[k][:, -1, -1],
                                   rtol=1e-6)
    stats.reset()                       # forgets everything: the same stream, the same numbers
    assert stats.count == 0
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    again = stats.scores(spans)
    for k in range(2):
        np.testing.assert_array_equal(again.loglik[k], streamed.loglik[k])
        np.testing.assert_array_equal(again.factors[k], streamed.factors[k])


def test_past_the_end_the_motion_holds_its_final_state(fitted):
    """Observations after a candidate's end see the phase clipped at 1 (dense reference)."""
    model, t, y = fitted
    durations = np.array([0.8, 1.1])                      # shorter than the observations
    scorer = Scorer(model)
    scores = scorer.joint(t, y, durations, np.array([[0, 2], [0, 2]]))
    marginal = scorer.marginal(t, y, durations, np.array([[0, 2], [0, 2]]))
    P, Q = model.n_human, model.n_robot
    for k in range(2):
        w = model.task_models[k].weights
        for j, T in enumerate(durations):
            H = observation_matrix(model.basis, np.minimum(t / T, 1.0), P, Q)
            obs = np.hstack([y, np.full((t.size, Q), np.nan)]).ravel()
            noise = np.tile(np.r_[model.noise, np.ones(Q)], t.size)
            ll = log_marginal_likelihood(w.mean, w.cov(), H, obs, noise)
            assert scores.loglik[k][j] == pytest.approx(ll, rel=1e-9)
            D = P + Q
            steps = sum(log_marginal_likelihood(w.mean, w.cov(), H[i * D:(i + 1) * D],
                                                obs[i * D:(i + 1) * D], noise[i * D:(i + 1) * D])
                        for i in range(t.size))
            assert marginal.loglik[k][j] == pytest.approx(steps, rel=1e-9)


def test_stream_statistics_past_every_end_equal_the_batch(fitted):
    from sandbox.core.phase import Lattice
    from sandbox.core.statistics import StreamStatistics

    model, t, y = fitted
    scorer = Scorer(model)
    lattice = Lattice.for_tasks(model.task_models, n_candidates=12)
    stats = StreamStatistics(scorer, lattice, flush_every=5)
    tt = np.r_[t, t[-1] + np.arange(1, 30) * 0.05]           # well past every candidate
    yy = np.vstack([y, np.repeat(y[-1:], 29, axis=0)])
    for ti, yi in zip(tt, yy):
        stats.add(ti, yi)
    streamed = stats.scores(lattice.spans())
    batch = scorer.joint(tt, yy, lattice.durations, lattice.spans())
    for k in range(2):
        np.testing.assert_allclose(streamed.loglik[k], batch.loglik[k], rtol=1e-9)


@pytest.fixture(scope="module")
def multi():
    demos = synth.multimodal(np.random.default_rng(5), n_per_task=6)
    model = IProMP(n_basis=9).fit(demos[1:])
    test = demos[0]
    t, y = test.times[:160:4], test.human[:160:4] / model.scale
    y[5:9, 3:9] = np.nan
    y[::3, 9:] = np.nan
    return model, t, y


def test_stream_statistics_with_masked_modalities_equal_the_batch(multi):
    from sandbox.core.phase import Lattice
    from sandbox.core.statistics import StreamStatistics

    model, t, y = multi
    scorer = Scorer(model)
    lattice = Lattice.for_tasks(model.task_models, n_candidates=10)
    stats = StreamStatistics(scorer, lattice, flush_every=3)
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    streamed = stats.scores(lattice.spans())
    batch = scorer.joint(t, y, lattice.durations, lattice.spans())
    for k in range(2):
        np.testing.assert_allclose(streamed.loglik[k], batch.loglik[k], rtol=1e-9)


def test_pairs_equal_the_grid_for_several_groups(multi):
    model, t, y = multi
    scorer = Scorer(model)
    durations = np.array([1.8, 2.1, 2.4])
    grid = scorer.joint(t, y, durations, np.array([[0, 3], [0, 3]]))
    ll, factors = scorer.joint_pairs(t, y, durations[[2, 0, 1]], np.array([0, 1, 1]))
    np.testing.assert_allclose(ll, [grid.loglik[0][2], grid.loglik[1][0], grid.loglik[1][1]],
                               rtol=1e-10)
    np.testing.assert_allclose(factors[1], grid.factors[1][0], rtol=1e-8, atol=1e-12)


def test_marginal_mode_scores_each_row_on_what_it_observes(multi):
    model, t, y = multi
    scores = Scorer(model).marginal(t, y, np.array([2.0]), np.array([[0, 1], [0, 1]]))
    P, Q = model.n_human, model.n_robot
    for k in range(2):
        w = model.task_models[k].weights
        total = 0.0
        for i in range(t.size):
            H = observation_matrix(model.basis, np.minimum(t[i:i + 1] / 2.0, 1), P, Q)
            obs = np.r_[y[i], np.full(Q, np.nan)]
            total += log_marginal_likelihood(w.mean, w.cov(), H, obs, np.r_[model.noise,
                                                                             np.ones(Q)])
        assert scores.loglik[k][0] == pytest.approx(total, rel=1e-9)


def test_a_task_with_no_candidates_gets_none(fitted):
    model, t, y = fitted
    scores = Scorer(model).joint(t, y, np.array([2.0, 2.2]), np.array([[0, 2], [1, 1]]))
    assert scores.loglik[0].size == 2 and scores.loglik[1].size == 0
    assert scores.factors[1].shape == (0, Scorer(model).R + 1, Scorer(model).R + 1)

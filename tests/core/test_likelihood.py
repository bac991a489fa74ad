import numpy as np
import pytest

from sandbox.core.interaction import condition, log_marginal_likelihood, observation_matrix
from sandbox.core.likelihood import Scorer, condition_robot
from sandbox.core.model import IProMP

from . import synth


@pytest.fixture(scope="module")
def fitted():
    rng = np.random.default_rng(0)
    model = IProMP(n_basis=11).fit(synth.demos(rng, n_per_task=6, n_tasks=2, noise=0.003))
    test = synth.replay(0, 2.1, noise=0.003, rng=rng)
    return model, test.times[:150:5], test.human[:150:5]


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
    spans = lattice.spans(t[-1])
    streamed = stats.scores(spans)
    batch = scorer.joint(t, y, lattice.durations, spans)
    for k in range(2):
        np.testing.assert_allclose(streamed.loglik[k], batch.loglik[k], rtol=1e-10)
        np.testing.assert_allclose(streamed.factors[k][:, -1, -1], batch.factors[k][:, -1, -1],
                                   rtol=1e-6)
    stats.reset()
    assert stats.count == 0 and not stats.Kt.any()

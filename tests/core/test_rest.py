"""The rest hypothesis: a hand that has not started leaves the task posterior at the prior."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal, norm

from sandbox.core import DynamicPredictor, IProMP
from sandbox.core.inference import predict
from sandbox.core.likelihood import Scorer
from sandbox.core.rest import (
    chosen_task,
    motion_probability,
    rest_log_likelihood,
    start_distribution,
    with_rest,
)
from sandbox.data.synthetic import diverging_demos


@pytest.fixture(scope="module")
def diverging():
    demos = diverging_demos(8, np.random.default_rng(3))
    return IProMP(n_basis=15).fit(demos), diverging_demos(2, np.random.default_rng(40))


def _still_stream(model, seconds=2.0, rate=30.0, jitter=0.002, seed=0):
    """A hand held at the tasks' common start, with tracker jitter (m)."""
    rng = np.random.default_rng(seed)
    start, _ = start_distribution(model)
    times = np.arange(0.0, seconds + 1e-9, 1.0 / rate)
    return times, start + rng.normal(0.0, jitter, (times.size, start.size))


@pytest.mark.parametrize("likelihood", ["joint", "marginal"])
def test_a_motionless_hand_leaves_the_posterior_near_the_prior(diverging, likelihood):
    """Issue 27's target: 2 s of a still hand never gives a task more than max prior + 0.2."""
    model, _ = diverging
    pred = DynamicPredictor(model, dow_t=0.2, likelihood=likelihood)
    times, values = _still_stream(model)
    for t, y in zip(times, values):
        pred.observe(t, y)
    assert len(pred.updates) >= 9
    top = max(float(np.max(u.task_posterior)) for u in pred.updates)
    assert top <= model.priors.max() + 0.2
    assert pred.updates[-1].motion_probability < 0.01


def test_without_the_rest_the_still_hand_locks_on_a_task(diverging):
    """What the rest hypothesis fixes: the task models alone are sure of a task."""
    model, _ = diverging
    times, values = _still_stream(model)
    scorer = Scorer(model)
    post = predict(model, scorer, times, values, rest=False).task_posterior
    assert post.max() > model.priors.max() + 0.2
    mixed = predict(model, scorer, times, values).task_posterior
    assert mixed.max() <= model.priors.max() + 0.2


def test_a_real_motion_is_a_motion_and_keeps_its_task(diverging):
    model, tests = diverging
    scorer = Scorer(model)
    for demo in tests:
        t = demo.times - demo.times[0]
        n = int(np.searchsorted(t, 0.5 * t[-1]))
        with_ = predict(model, scorer, t[:n], demo.human[:n])
        without = predict(model, scorer, t[:n], demo.human[:n], rest=False)
        assert with_.motion_probability > 0.999
        assert with_.task_index == without.task_index       # uniform prior: same choice
        np.testing.assert_allclose(with_.task_posterior, without.task_posterior, atol=1e-3)
        np.testing.assert_allclose(with_.task_posterior.sum(), 1.0)


def test_rest_likelihood_matches_scipy():
    """Closed form (Sherman-Morrison) against a dense Gaussian per dim, NaN skipped."""
    rng = np.random.default_rng(1)
    y = rng.normal(0.3, 0.05, (7, 3))
    y[2, 1] = np.nan
    sigma2, mean, var = np.array([1e-3, 4e-4, 2e-3]), np.array([0.3, 0.25, 0.4]), \
        np.array([5e-4, 1e-3, 2e-4])
    expect = 0.0
    for j in range(3):
        yj = y[np.isfinite(y[:, j]), j]
        cov = sigma2[j] * np.eye(yj.size) + var[j] * np.ones((yj.size, yj.size))
        expect += multivariate_normal(np.full(yj.size, mean[j]), cov).logpdf(yj)
    assert rest_log_likelihood(y, sigma2, mean, var) == pytest.approx(expect, rel=1e-10)
    marginal = np.nansum(norm(mean, np.sqrt(var + sigma2)).logpdf(y))
    assert rest_log_likelihood(y, sigma2, mean, var, joint=False) == pytest.approx(marginal)
    assert rest_log_likelihood(np.full((3, 3), np.nan), sigma2, mean, var) == 0.0


def test_motion_probability_and_mixture():
    priors = np.array([0.5, 0.25, 0.25])
    ll = np.array([-10.0, -12.0, -30.0])
    evidence = np.log(np.exp(ll) @ priors)
    assert motion_probability(ll, priors, evidence) == pytest.approx(0.5)
    assert motion_probability(ll, priors, evidence + 50) < 1e-20
    assert motion_probability(ll, priors, -1e6) == 1.0
    post = np.array([0.1, 0.9, 0.0])
    mixed = with_rest(post, priors, 0.0)
    np.testing.assert_allclose(mixed, priors)
    assert chosen_task(mixed, post) == 0                # the prior's favourite
    flat = np.full(3, 1 / 3)
    assert chosen_task(with_rest(post, flat, 0.0), post) == 1   # exact tie: the models' choice


def test_start_distribution_is_the_tasks_start(diverging):
    model, _ = diverging
    demos = diverging_demos(8, np.random.default_rng(3))
    mean, var = start_distribution(model)
    starts = np.array([d.human[0] for d in demos])
    np.testing.assert_allclose(mean, starts.mean(axis=0), atol=0.01)
    assert np.all(var > 0) and np.all(np.sqrt(var) < 0.05)

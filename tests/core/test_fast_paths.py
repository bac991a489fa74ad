"""The update's fast paths (issue 25) against the straightforward computations they replace.

Each test keeps the simple reference implementation it checks against: the per-task loop
of the phase grid, one b_part per group, the trajectory at every step, the blend with the
whole old plan interpolated, and the dense likelihood and conditioning of a model with
more demos than human weights (compressed to the human block's rank).
"""

import numpy as np
import pytest

from sandbox.core.blending import blend_unchecked
from sandbox.core.factor import b_part, b_parts, condition_robot
from sandbox.core.inference import predict
from sandbox.core.interaction import condition, log_marginal_likelihood, observation_matrix
from sandbox.core.likelihood import Scorer, compress_human
from sandbox.core.model import IProMP
from sandbox.core.phase import Lattice, _refine, estimate_phase, log_alpha_prior
from sandbox.core.plan import Blending, Plan, _activations
from sandbox.core.predictor import DynamicPredictor
from sandbox.core.promp import trajectory_distribution
from sandbox.core.statistics import StreamStatistics

from . import synth


@pytest.fixture(scope="module")
def fitted():
    rng = np.random.default_rng(0)
    model = IProMP(n_basis=11).fit(synth.demos(rng, n_per_task=8, n_tasks=3, noise=0.003))
    test = synth.replay(0, 2.1, noise=0.003, rng=rng)
    return model, test.times[:150:5], test.human[:150:5]


@pytest.fixture(scope="module")
def many():
    """More demos (30) than human weights (N P = 5 x 2 = 10): the human block is compressed."""
    rng = np.random.default_rng(3)
    model = IProMP(n_basis=5).fit(synth.demos(rng, n_per_task=30, n_tasks=2, noise=0.003))
    test = synth.replay(1, 2.0, noise=0.003, rng=rng)
    return model, test.times[:140:5], test.human[:140:5]


def _reference_grid(scorer, tasks, times, values, stats):
    """The phase grid one task at a time (the code before the grid was vectorised)."""
    nominal = np.array([t.nominal_duration for t in tasks])
    a_mean = np.array([t.alpha_mean for t in tasks])
    a_std = np.array([t.alpha_std for t in tasks])
    spans = stats.lattice.spans()
    scores = stats.scores(spans)
    out = []
    for k in range(len(tasks)):
        T = stats.durations[spans[k, 0]:spans[k, 1]]
        lp = log_alpha_prior(T / nominal[k], a_mean[k], a_std[k])
        f = scores.loglik[k] + lp
        i = int(np.argmax(f))
        w = np.exp(f - f[i])
        out.append((T[i], scores.loglik[k][i], lp[i], scores.factors[k][i], w / w.sum(),
                    None if i in (0, T.size - 1) else
                    (T[i - 1], T[i], T[i + 1], f[i - 1], f[i], f[i + 1])))
    return nominal, a_mean, a_std, out


@pytest.mark.parametrize("refine_steps", [0, 1, 2])
def test_vectorised_phase_grid_matches_the_per_task_loop(fitted, refine_steps):
    model, t, y = fitted
    scorer = Scorer(model)
    stats = StreamStatistics(scorer, Lattice.for_tasks(model.task_models, 20))
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    est = estimate_phase(scorer, model.task_models, t, y, refine_steps=refine_steps, stats=stats)
    nominal, a_mean, a_std, ref = _reference_grid(scorer, model.task_models, t, y, stats)
    best_T = np.array([r[0] for r in ref])
    best_ll = np.array([r[1] for r in ref])
    best_lp = np.array([r[2] for r in ref])
    factors = np.array([r[3] for r in ref])
    brackets = [r[5] for r in ref]
    for _ in range(refine_steps):
        brackets = _refine(scorer.joint_pairs, t, y, model.task_models, brackets, nominal,
                           a_mean, a_std, best_T, best_ll, best_lp, factors)
    np.testing.assert_allclose(est.durations, best_T, rtol=1e-12)
    np.testing.assert_allclose(est.log_likelihood, best_ll, rtol=1e-12)
    np.testing.assert_allclose(est.log_prior, best_lp, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(est.factors, factors, rtol=1e-12, atol=1e-14)
    for (_, w), r in zip(est.grid, ref):
        np.testing.assert_allclose(w, r[4], rtol=1e-10, atol=1e-300)
        assert w.sum() == pytest.approx(1.0, rel=1e-12)


def test_stream_statistics_refuse_spans_they_do_not_keep(fitted):
    model, t, y = fitted
    stats = StreamStatistics(Scorer(model), Lattice.for_tasks(model.task_models, 12))
    with pytest.raises(ValueError, match="spans"):
        stats.scores(np.array([[0, 1]] * len(model.tasks)))


def test_groups_sharing_rows_match_one_b_part_each():
    rng = np.random.default_rng(1)
    psi = rng.random((4, 25, 9))
    G = psi.transpose(0, 2, 1) @ psi
    ys = [rng.standard_normal((25, p)) for p in (3, 6, 8)]
    betas = [psi.transpose(0, 2, 1) @ y for y in ys]
    yys = [(y * y).sum(axis=0) for y in ys]
    kappas = [0.05, 2.0, 40.0]
    for together, beta, yy, kappa in zip(b_parts(G, betas, yys, kappas), betas, yys, kappas):
        for a, b in zip(together, b_part(G, beta, yy, kappa)):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)


def test_compressed_human_block_is_the_same_distribution(many):
    model, _, _ = many
    P, N = model.n_human, model.basis.n_basis
    for task in model.task_models:
        w = task.weights
        turned, m = compress_human(w, P)
        assert w.factor.shape[1] > P * N >= m and turned.factor.shape == w.factor.shape
        np.testing.assert_allclose(turned.cov(), w.cov(), rtol=1e-10,
                                   atol=1e-12 * np.abs(w.cov()).max())
        assert not turned.factor[: P * N, m:].any()
    small, _ = compress_human(model.task_models[0].weights, P + 10)
    assert small is model.task_models[0].weights       # nothing to gain: unchanged


def test_compressed_likelihood_and_conditioning_match_the_dense_ones(many):
    model, t, y = many
    scorer = Scorer(model)
    P, Q, N = model.n_human, model.n_robot, model.basis.n_basis
    assert scorer.R <= P * N
    durations = np.array([1.7, 2.0, 2.6])
    scores = scorer.joint(t, y, durations, np.array([[0, 3], [0, 3]]))
    obs = np.hstack([y, np.full((t.size, Q), np.nan)]).ravel()
    noise = np.tile(np.r_[model.noise, np.ones(Q)], t.size)
    for k, task in enumerate(model.task_models):
        w = task.weights
        for j, T in enumerate(durations):
            H = observation_matrix(model.basis, np.minimum(t / T, 1.0), P, Q)
            ll = log_marginal_likelihood(w.mean, w.cov(), H, obs, noise)
            assert scores.loglik[k][j] == pytest.approx(ll, rel=1e-10)
            mean, cov = condition(w.mean, w.cov(), H, obs, noise)
            post = condition_robot(scorer.weights[k], scores.factors[k][j], P, scorer.rank[k])
            np.testing.assert_allclose(post.mean, mean[P * N:], rtol=1e-10,
                                       atol=1e-10 * np.abs(mean).max())
            dense = cov[P * N:, P * N:]
            np.testing.assert_allclose(post.cov(), dense, rtol=1e-8,
                                       atol=1e-10 * np.abs(dense).max())
            assert np.linalg.eigvalsh(post.cov()).min() > 0          # SPD


def test_many_demos_predictor_plans_symmetric_positive_definite(many):
    model, t, y = many
    pred = DynamicPredictor(model, dow_t=0.4)
    for ti, yi in zip(t, y):
        pred.observe(ti, yi)
    assert pred.updates
    _, _, cov = pred.plan()
    np.testing.assert_allclose(cov, cov.transpose(0, 2, 1), atol=1e-14)
    assert np.linalg.eigvalsh(cov).min() > 0


def test_held_trajectory_matches_every_step_computed(fitted):
    model, t, y = fitted
    pred = predict(model, Scorer(model), t, y)
    times = np.arange(0.0, pred.duration + 1.5, 0.01)
    mean, cov = pred.trajectory(model.basis, times)
    z = np.clip(times / pred.duration, 0.0, 1.0)
    ref_mean, ref_cov = trajectory_distribution(pred.robot, model.basis, z)
    np.testing.assert_allclose(mean, ref_mean, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(cov, ref_cov, rtol=1e-12, atol=1e-16)


def _reference_blended(plan, t, new, duration, how):
    """Plan.blended with the whole old plan interpolated (before the old plan was cut)."""
    keep = plan.times < t
    end = max(duration, plan.times[-1], t + how.horizon, t + how.delay + 10.0 / how.rate)
    first = (np.floor(t / how.dt + 1e-9) + 1.0) * how.dt
    new_t = np.arange(first, end + how.dt, how.dt)
    new_t = new_t[new_t > t + 1e-9]
    old_mean, old_cov = plan.interpolate(np.concatenate([[t], new_t]))
    mean, cov = new(new_t)
    fall, rise, n = _activations(new_t, t + how.delay, how.rate)
    head = blend_unchecked(np.stack([old_mean[1:][:n], mean[:n]]),
                           np.stack([old_cov[1:][:n], cov[:n]]), np.stack([fall[:n], rise[:n]]))
    mean = np.concatenate([head[0], mean[n:]])
    cov = np.concatenate([head[1], cov[n:] / rise[n:, None, None]])
    return (np.concatenate([plan.times[keep], [t], new_t]),
            np.concatenate([plan.mean[keep], old_mean[:1], mean]),
            np.concatenate([plan.cov[keep], old_cov[:1], cov]))


@pytest.mark.parametrize("t", [0.35, 1.2, 2.9])
def test_blend_with_the_old_plan_cut_matches_the_whole_interpolation(fitted, t):
    model, times, y = fitted
    pred = predict(model, Scorer(model), times, y)
    how = Blending(0.01, 50.0, 0.1, True, 2.0)
    plan = Plan.prior(model, 0.01)
    new = lambda ts: pred.trajectory(model.basis, ts)  # noqa: E731
    got, _ = plan.blended(t, new, pred.duration, how)
    ref = _reference_blended(plan, t, new, pred.duration, how)
    for a, b in zip((got.times, got.mean, got.cov), ref):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)

"""Post-end observations scored with a held offset (sandbox.core.posthold, issue 21 item 4)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from sandbox.core.factor import condition_robot
from sandbox.core.interaction import observation_matrix
from sandbox.core.likelihood import Scorer
from sandbox.core.model import IProMP
from sandbox.core.posthold import (
    check_post_end,
    demo_offsets,
    end_span_variance,
    post_end_variance,
)

from . import synth


@pytest.fixture(scope="module")
def fitted():
    return synth.fitted_case()


def _dense(model, k, t, y, T, s2):
    """Log density and robot posterior of every observation, the post-end rows (t > T)
    sharing one offset of variance s2 per human dim (a dense covariance)."""
    P, Q = model.n_human, model.n_robot
    w = model.task_models[k].weights
    H = observation_matrix(model.basis, np.minimum(t / T, 1.0), P, Q)
    obs = np.hstack([y, np.full((t.size, Q), np.nan)]).ravel()
    noise = np.diag(np.tile(np.r_[model.noise, np.ones(Q)], t.size))
    post = np.repeat(t > T, P + Q) & np.tile(np.r_[np.ones(P), np.zeros(Q)] > 0, t.size)
    dim = np.tile(np.arange(P + Q), t.size)
    noise += s2 * (post[:, None] & post[None, :] & (dim[:, None] == dim[None, :]))
    keep = np.isfinite(obs)
    H, obs, noise = H[keep], obs[keep], noise[np.ix_(keep, keep)]
    cov = H @ w.cov() @ H.T + noise
    ll = multivariate_normal(H @ w.mean, cov).logpdf(obs)
    gain = w.cov() @ H.T @ np.linalg.inv(cov)
    return ll, w.mean + gain @ (obs - H @ w.mean), w.cov() - gain @ H @ w.cov()


def test_the_held_offset_matches_the_dense_likelihood_and_conditioning(fitted):
    model, t, y = fitted
    held = copy.copy(model)
    held.post_var = np.array([0.02**2])
    scorer = Scorer(held)
    durations = np.array([0.9, 1.3, 2.0, 3.0])               # 3.0: no row past its end
    scores = scorer.joint(t, y, durations, np.array([[0, 4], [0, 4]]))
    P, N = model.n_human, model.basis.n_basis
    for k in range(2):
        ll_pairs, factors = scorer.joint_pairs(t, y, durations, np.full(4, k))
        for c, T in enumerate(durations):
            ll, mean, cov = _dense(model, k, t, y, T, 0.02**2)
            assert scores.loglik[k][c] == pytest.approx(ll, rel=1e-9)
            assert ll_pairs[c] == pytest.approx(ll, rel=1e-9)
            w = scorer.weights[k]
            post = condition_robot(w, scores.factors[k][c], P, scorer.rank[k])
            np.testing.assert_allclose(post.mean, mean[P * N:], atol=1e-9)
            np.testing.assert_allclose(post.cov(), cov[P * N:, P * N:], atol=1e-11)


def test_no_offset_is_todays_likelihood_and_an_offset_weakens_the_tail(fitted):
    model, t, y = fitted
    durations = np.array([0.9, 1.3])
    spans = np.array([[0, 2], [0, 2]])
    today = Scorer(model).joint(t, y, durations, spans)
    zero, wide = copy.copy(model), copy.copy(model)
    zero.post_var, wide.post_var = np.zeros(1), np.array([1.0])
    assert Scorer(zero).post_var is None           # today's paths, compiled and incremental
    same = Scorer(zero).joint(t, y, durations, spans)
    loose = Scorer(wide).joint(t, y, durations, spans)
    for k in range(2):
        np.testing.assert_array_equal(same.loglik[k], today.loglik[k])
    # the wrong task's tail costs it less once the tail is one observation, not 20
    gap_today = today.loglik[0] - today.loglik[1]
    gap_loose = loose.loglik[0] - loose.loglik[1]
    assert np.all(np.abs(gap_loose) < np.abs(gap_today))


def test_the_offsets_of_a_recording_after_its_motion():
    human = np.array([[0.0, 1.0], [1.0, np.nan], [2.0, 3.0], [4.0, 5.0], [np.nan, 7.0]])
    offset, n = demo_offsets(human, 1)                      # motion: rows 0, 1
    np.testing.assert_allclose(offset, [3.0 - 1.0, 5.0 - 1.0])
    assert n == 3
    none, n = demo_offsets(human, 4)
    assert n == 0 and np.isnan(none).all()


def test_the_variance_pools_a_modalitys_dims_and_demos_in_normalised_units():
    offsets = [np.array([0.1, 0.0, 0.2]), None, np.array([0.1, np.nan, 4.0])]
    v = post_end_variance(offsets, np.array([1.0, 1.0, 2.0]), [2, 1])
    np.testing.assert_allclose(v, [(0.01 + 0 + 0.01) / 3, (0.01 + 4.0) / 2])
    np.testing.assert_array_equal(post_end_variance([None], np.ones(3), [3]), [0.0])


def test_the_end_states_out_of_span_variance_has_its_known_answer():
    """Three demos of one dim, two weights, phi(1) = (0, 1): left out in turn, each one's
    deviation from the other two's mean off their span is (-.5, -.5), (1, 0) and (0, 1),
    whose end states are -.5, 0 and 1 (raw weights twice these, scale 2)."""
    from types import SimpleNamespace

    raw = 2.0 * np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    fits = [SimpleNamespace(task="a", weights=np.r_[w, 7.0], duration=1.0) for w in raw]
    fits += [SimpleNamespace(task="b", weights=np.r_[w, 7.0], duration=1.0) for w in raw[:2]]
    u = end_span_variance(fits, np.array([2.0]), np.array([0.0, 1.0]), [1])
    np.testing.assert_allclose(u, [(0.25 + 0.0 + 1.0) / 3])       # task b: too few demos
    assert end_span_variance(fits[3:], np.array([2.0]), np.array([0.0, 1.0]), [1]) == [0.0]


def test_span_adds_the_end_states_variance_to_the_tails():
    rng = np.random.default_rng(1)
    demos = synth.demos(rng, n_per_task=5, n_tasks=2, noise=0.003)
    tail = IProMP(n_basis=9, post_end=1.0).fit(demos)
    span = IProMP(n_basis=9, post_end="span").fit(demos)
    fits = [IProMP(n_basis=9).demo_fit(d) for d in demos]
    end = span.basis.evaluate(np.array([1.0]))[0]
    u = end_span_variance(fits, span.scale, end, [m.size for m in span.modalities])
    assert u[0] > 0
    np.testing.assert_allclose(span.post_var, tail.post_var + u)


def test_the_fit_learns_it_from_the_training_tails_only():
    rng = np.random.default_rng(1)
    demos = synth.demos(rng, n_per_task=5, n_tasks=2, noise=0.003)
    assert IProMP(n_basis=9).fit(demos).post_var is None
    model = IProMP(n_basis=9, post_end=2.0).fit(demos)
    fits = [IProMP(n_basis=9).demo_fit(d) for d in demos]
    tails = [f.tail for f in fits]
    assert any(x is not None for x in tails)
    expect = 2.0 * post_end_variance(tails, model.scale, [m.size for m in model.modalities])
    np.testing.assert_allclose(model.post_var, expect)
    assert model.post_var[0] > 0


@pytest.mark.parametrize("bad", [-0.1, 11.0, "auto", True, [1.0]])
def test_a_bad_post_end_is_refused(bad):
    with pytest.raises(ValueError, match="post_end"):
        check_post_end(bad)
    with pytest.raises(ValueError, match="post_end"):
        IProMP(post_end=bad)


def test_the_file_keeps_it_and_an_older_file_has_none(tmp_path):
    rng = np.random.default_rng(2)
    demos = synth.demos(rng, n_per_task=4, n_tasks=2, noise=0.003)
    for value in (0.5, "span"):
        model = IProMP(n_basis=9, post_end=value).fit(demos)
        model.save(tmp_path / "m.npz")
        back = IProMP.load(tmp_path / "m.npz")
        assert back.post_end == value
        np.testing.assert_array_equal(back.post_var, model.post_var)
    plain = IProMP(n_basis=9).fit(demos)
    plain.save(tmp_path / "p.npz")
    again = IProMP.load(tmp_path / "p.npz")
    assert again.post_end is None and again.post_var is None


def test_a_streams_statistics_give_the_held_offsets_grid_not_todays(fitted):
    """The phase grid of a model with ``post_var`` is the batch one (Scorer.joint) even when
    a stream's incremental statistics, which score every row alone, are at hand."""
    from sandbox.core.phase import Lattice, estimate_phase
    from sandbox.core.statistics import StreamStatistics

    model, t, y = fitted
    held = copy.copy(model)
    held.post_var = np.array([0.03**2])
    tasks = model.task_models
    for m in (held, model):
        scorer = Scorer(m)
        stats = StreamStatistics(scorer, Lattice.for_tasks(tasks, 20))
        for ti, yi in zip(t, y):
            stats.add(ti, yi)
        a = estimate_phase(scorer, tasks, t, y, n_candidates=20, stats=stats, refine_steps=0)
        b = estimate_phase(scorer, tasks, t, y, n_candidates=20, refine_steps=0)
        np.testing.assert_allclose(a.log_likelihood, b.log_likelihood, rtol=1e-9)
    today = estimate_phase(Scorer(model), tasks, t, y, n_candidates=20, refine_steps=0)
    mine = estimate_phase(Scorer(held), tasks, t, y, n_candidates=20, refine_steps=0)
    short = [T < t[-1] for T, _ in today.grid]                  # candidates with a tail
    assert any(s.any() for s in short)
    assert any(not np.allclose(wm[s], wt[s], rtol=1e-6)
               for (_, wm), (_, wt), s in zip(mine.grid, today.grid, short) if s.any())


def test_a_settings_file_takes_post_end_and_the_eval_config_passes_it_on(tmp_path):
    from sandbox.commands._settings import eval_fields, load
    from sandbox.eval.loocv import EvalConfig

    path = tmp_path / "s.yaml"
    for text, value in (("null", None), ("1", 1.0), ("0.25", 0.25), ("'2'", 2.0),
                        ("span", "span")):
        path.write_text(f"post_end: {text}\n")
        settings = load(path)
        assert settings == {"post_end": value}
        assert EvalConfig(**eval_fields(settings)).model().post_end == value
    for text in ("auto", "-1", "11", ".nan", "true", "[]"):
        path.write_text(f"post_end: {text}\n")
        expected = r"post_end: expected a factor in \[0, 10\], span or null"
        with pytest.raises(ValueError, match=expected):
            load(path)

"""Timing evidence of the familiarity (sandbox.core.evidence): known answers, synthetic motions."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from sandbox.core import IProMP
from sandbox.core.evidence import (
    COMPONENTS,
    chi2_log_survival,
    components,
    goal,
    goal_frame,
    not_arrived,
    phase_spread,
    position,
    position_frame,
    speed_change,
)
from sandbox.core.inference import predict
from sandbox.core.likelihood import Scorer

from . import synth


@pytest.fixture(scope="module")
def model():
    return IProMP(n_basis=9).fit(synth.demos(np.random.default_rng(0), n_per_task=8, n_tasks=2))


def prediction_of(model, demo, until: float):
    keep = demo.times <= until
    t, y = demo.times[keep][::5], demo.human[keep][::5]
    return predict(model, Scorer(model), t, y, n_candidates=20), t, y


def with_grid(prediction, k: int, alphas, weights, model):
    """The prediction with task k's duration posterior replaced (alphas in prior units)."""
    task = model.task_models[k]
    grid = list(prediction.grid)
    grid[k] = (np.asarray(alphas) * task.nominal_duration, np.asarray(weights, dtype=float))
    return replace(prediction, grid=grid)


def test_not_arrived_is_the_prior_survival_while_the_motion_goes_on(model):
    pred, _, _ = prediction_of(model, synth.replay(0, 2.0), 1.0)
    task = model.task_models[0]
    t = 1.3 * task.nominal_duration
    going = with_grid(pred, 0, [1.5, 1.6], [0.5, 0.5], model)          # all mass after t
    u = (t / task.nominal_duration - task.alpha_mean) / task.alpha_std
    assert not_arrived(model, going, t, 0) == pytest.approx(-stats.norm.logsf(u), rel=1e-9)
    ended = with_grid(pred, 0, [1.0, 1.1], [0.5, 0.5], model)           # all mass before t
    assert not_arrived(model, ended, t, 0) == 0.0
    half = with_grid(pred, 0, [1.0, 1.6], [0.5, 0.5], model)
    assert not_arrived(model, half, t, 0) == pytest.approx(-0.5 * stats.norm.logsf(u))


def test_not_arrived_grows_with_elapsed_time(model):
    pred, _, _ = prediction_of(model, synth.replay(0, 2.0), 1.0)
    going = with_grid(pred, 0, [9.0], [1.0], model)
    values = [not_arrived(model, going, t, 0) for t in np.linspace(0.1, 6.0, 30)]
    assert np.all(np.diff(values) > 0)


def test_phase_spread_is_the_expected_squared_standard_speed(model):
    pred, _, _ = prediction_of(model, synth.replay(0, 2.0), 1.0)
    task = model.task_models[1]
    z = np.array([-1.0, 2.0])
    spread = with_grid(pred, 1, task.alpha_mean + z * task.alpha_std, [0.25, 0.75], model)
    assert phase_spread(model, spread, 1) == pytest.approx(0.25 * 1 + 0.75 * 4)


def test_a_hand_moving_as_predicted_has_a_small_speed_change(model):
    demo = synth.replay(0, model.task_models[0].nominal_duration)
    pred, t, y = prediction_of(model, demo, 0.5 * demo.times[-1])
    assert speed_change(model, pred, 0, t, y) < 0.3


def test_a_hand_stopped_mid_reach_has_a_large_speed_change(model):
    demo = synth.replay(0, model.task_models[0].nominal_duration)
    pred, t, y = prediction_of(model, demo, 0.5 * demo.times[-1])
    held = y.copy()
    held[t > t[-1] - 0.35] = y[np.searchsorted(t, t[-1] - 0.35)]        # stopped 0.35 s ago
    assert speed_change(model, pred, 0, t, held) > 1.0
    assert speed_change(model, pred, 0, t[:1], y[:1]) == 0.0             # one row: no evidence


def test_components_are_in_order_and_inputs_are_not_mutated(model):
    demo = synth.replay(1, 2.0)
    pred, t, y = prediction_of(model, demo, 1.2)
    before = (t.copy(), y.copy())
    out = components(model, pred, 1.2, t, y, 1, 0.7)
    assert out.shape == (len(COMPONENTS),) == (6,) and out[0] == 0.7 and np.all(out >= 0)
    assert out[COMPONENTS.index("goal")] == goal(model, pred, 1, y)
    assert out[COMPONENTS.index("position")] == position(model, pred, 1, t, y)
    some = components(model, pred, 1.2, t, y, 1, 0.7, names=("position", "mahalanobis"))
    np.testing.assert_array_equal(some, out[[5, 0]])
    np.testing.assert_array_equal(t, before[0])
    np.testing.assert_array_equal(y, before[1])


def veered(demo, shift) -> synth.Demo:
    """``demo`` heading for an end moved by ``shift`` (m), gradually over the whole reach."""
    z = demo.times / demo.times[-1]
    s = z**3 * (10 - 15 * z + 6 * z**2)
    return synth.Demo(demo.times, demo.human + s[:, None] * np.asarray(shift), demo.robot,
                      demo.task)


def test_a_hand_heading_for_another_end_has_a_large_goal_before_it_arrives(model):
    """The task's ends vary by 5 % of 0.5 m; an end 0.15 m beyond (6 of those stds)
    scores p < e^-5 at 85 % of the motion, the task's own mean motion p > 0.9."""
    demo = synth.replay(0, model.task_models[0].nominal_duration)
    pred, _, y = prediction_of(model, demo, 0.85 * demo.times[-1])
    assert goal(model, pred, 0, y) < 0.1
    odd = veered(demo, [0.0, 0.15, 0.0])
    pred, _, y = prediction_of(model, odd, 0.85 * odd.times[-1])
    assert goal(model, pred, 0, y) > 5.0
    early, _, y = prediction_of(model, odd, 0.3 * odd.times[-1])       # not heading off yet
    assert goal(model, early, 0, y) < 0.1


def test_the_goal_is_a_valid_p_value_bound_for_motions_of_the_model(model):
    """Motions drawn from task 0's own prior (weights, noise): e^-s_G < 0.1 in at most
    10 % of them (binomial 99.9 % bound for 100 draws: 20)."""
    rng = np.random.default_rng(3)
    task, P, N = model.task_models[0], model.n_human, model.basis.n_basis
    w = task.weights
    t = np.arange(0.0, 0.7 * task.nominal_duration, 0.05)
    psi = model.basis.evaluate(t / task.nominal_duration)
    scorer, small = Scorer(model), 0
    for _ in range(100):
        draw = (w.mean + w.factor @ rng.standard_normal(w.factor.shape[1])
                + np.repeat(np.sqrt(w.reg), N) * rng.standard_normal(w.mean.size))
        y = psi @ draw[:P * N].reshape(P, N).T + np.sqrt(model.noise) * rng.standard_normal(
            (t.size, P))
        pred = predict(model, scorer, t, y, n_candidates=20)
        small += np.exp(-goal(model, pred, 0, y)) < 0.1
    assert small <= 20


def test_the_goal_tests_the_observed_dims_and_needs_factors(model):
    demo = veered(synth.replay(0, 2.0), [0.0, 0.15, 0.0])
    pred, _, y = prediction_of(model, demo, 1.7)
    assert goal(model, pred, 0, np.full_like(y, np.nan)) == 0.0       # nothing observed
    assert goal(model, replace(pred, factors=None), 0, y) == 0.0      # marginal likelihood
    loads, cov = goal_frame(model, 0)
    assert loads.shape[0] == cov.shape[0] == model.n_human
    np.testing.assert_allclose(cov, cov.T)
    assert goal_frame(model, 0)[1] is cov                              # cached per weights


def test_chi2_log_survival_is_scipys_and_finite_far_out():
    for x, d in [(0.0, 3), (1.0, 3), (30.0, 3), (3.0, 1), (200.0, 9)]:
        assert chi2_log_survival(x, d) == pytest.approx(-stats.chi2.logsf(x, d), rel=1e-9)
    # past the doubles' range (scipy's logsf is inf there): the asymptote, continuous
    assert chi2_log_survival(1390.0, 3) == pytest.approx(-stats.chi2.logsf(1390.0, 3), rel=1e-5)
    far = [chi2_log_survival(x, 3) for x in (1500.0, 5000.0, 1e6)]
    assert np.all(np.isfinite(far)) and np.all(np.diff(far) > 0)


def prior_row(model, k: int, z: float):
    """Task k's prior predictive of one row at phase z, built densely: mean (P,), cov (P, P)."""
    w, P, N = model.task_models[k].weights, model.n_human, model.basis.n_basis
    phi = np.kron(np.eye(P), model.basis.evaluate(np.array([z])))          # (P, P N)
    full = w.factor[:P * N] @ w.factor[:P * N].T + np.diag(np.repeat(w.reg[:P], N))
    return phi @ w.mean[:P * N], phi @ full @ phi.T + np.diag(model.noise)


def test_the_position_is_each_rows_prior_mahalanobis_at_its_phase(model):
    """Rows on the prior mean score 0; one row, offset, scores -log P(chi2_3 >= D) with D
    from the dense predictive (known answer); a window of rows takes their median."""
    pred, t, y = prediction_of(model, synth.replay(0, 2.0), 1.0)
    T = pred.durations[0]
    on = np.array([prior_row(model, 0, min(ti / T, 1.0))[0] for ti in t])
    assert position(model, pred, 0, t, on) == pytest.approx(0.0, abs=1e-9)
    mean, cov = prior_row(model, 0, min(t[-1] / T, 1.0))
    off = on.copy()
    off[-1] += [0.05, -0.02, 0.01]
    r = off[-1] - mean
    D = float(r @ np.linalg.solve(cov, r))
    assert position(model, pred, 0, t[-1:], off[-1:]) == pytest.approx(
        -stats.chi2.logsf(D, 3), rel=1e-8)
    window = t >= t[-1] - 0.2 - 1e-9
    assert window.sum() >= 3
    assert position(model, pred, 0, t, off) == pytest.approx(0.0, abs=1e-9)   # one of 3+ rows
    shift = np.array([0.05, -0.02, 0.01])
    shifted = on + np.where(window[:, None], shift, 0.0)
    each = [-stats.chi2.logsf(shift @ np.linalg.solve(prior_row(model, 0, min(ti / T, 1.0))[1],
                                                      shift), 3) for ti in t[window]]
    assert position(model, pred, 0, t, shifted) == pytest.approx(np.median(each), rel=1e-8)
    assert np.median(each) > position(model, pred, 0, t, off)
    frame = position_frame(model, 0)
    assert position_frame(model, 0)[0] is frame[0]                     # cached per weights


def test_the_position_tests_the_observed_dims_and_needs_a_row(model):
    pred, t, y = prediction_of(model, synth.replay(0, 2.0), 1.0)
    before = y.copy()
    assert position(model, pred, 0, t[:0], y[:0]) == 0.0
    assert position(model, pred, 0, t, np.full_like(y, np.nan)) == 0.0
    T = pred.durations[0]
    mean, cov = prior_row(model, 0, min(t[-1] / T, 1.0))
    row = mean + [0.05, 0.0, 0.0]
    row[2] = np.nan
    D = float(np.array([0.05, 0.0]) @ np.linalg.solve(cov[:2, :2], [0.05, 0.0]))
    assert position(model, pred, 0, t[-1:], row[None]) == pytest.approx(
        -stats.chi2.logsf(D, 2), rel=1e-8)
    np.testing.assert_array_equal(y, before)

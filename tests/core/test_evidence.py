"""Timing evidence of the familiarity (sandbox.core.evidence): known answers, synthetic motions."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from sandbox.core import IProMP
from sandbox.core.evidence import COMPONENTS, components, not_arrived, phase_spread, speed_change
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
    assert out.shape == (len(COMPONENTS),) and out[0] == 0.7 and np.all(out >= 0)
    np.testing.assert_array_equal(t, before[0])
    np.testing.assert_array_equal(y, before[1])

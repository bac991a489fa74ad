"""The four methods: known answers (BIP = the core's conditioning at a fixed phase, eBIP's
mean -> the conditioned mean, DTW of a demo against itself, nearest finds its demo),
positive-definite covariances, the predictor interface and bad input."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.core.inference import predict
from sandbox.core.likelihood import Scorer
from sandbox.methods import (
    METHODS,
    DemoLibrary,
    check_methods,
    check_observable,
    make_predictor,
)
from sandbox.methods.bip import BipFilter
from sandbox.methods.dtw import dtw_distance
from sandbox.methods.ebip import EnsembleFilter
from tests.core import synth

N_BASIS = 9


@pytest.fixture(scope="module")
def fitted():
    demos = synth.demos(np.random.default_rng(0), n_per_task=6, rate=30.0)
    train, test = demos[1:], demos[0]
    model = IProMP(n_basis=N_BASIS).fit(train)
    return model, DemoLibrary.from_demos(model, train), test


def _stream(test, until: float | None = None):
    keep = test.times <= (np.inf if until is None else until)
    return test.times[keep], test.human[keep]


def test_bip_with_the_phase_held_fixed_is_the_cores_gaussian_conditioning(fitted):
    model, _, test = fitted
    times, values = _stream(test, 1.2)
    T, k = 2.0, model.task_index(test.task)
    core = predict(model, Scorer(model), times, values, task=k, duration=T).robot
    w = model.task_models[k].weights
    f = BipFilter(w.mean, w.cov(), N_BASIS, model.noise, 1 / T, 0.0, 0.0, 0.0, model.basis)
    for t, y in zip(times, values):
        f.predict(t)
        f.correct(y)
    PN = model.n_human * N_BASIS
    np.testing.assert_allclose(f.x[2 + PN:], core.mean, atol=1e-9)
    np.testing.assert_allclose(f.P[2 + PN:, 2 + PN:], core.cov(), atol=1e-12)
    assert f.x[0] == pytest.approx(times[-1] / T)


def _ensemble_error(model, k, times, values, T, size, seed) -> float:
    w = model.task_models[k].weights
    rng = np.random.default_rng(seed)
    draws = rng.multivariate_normal(w.mean, w.cov(), size=size, method="cholesky")
    members = np.c_[np.zeros(size), np.full(size, 1 / T), draws]
    f = EnsembleFilter(members, N_BASIS, model.noise, 0.0, model.basis, rng)
    for t, y in zip(times, values):
        f.predict(t)
        f.correct(y)
    core = predict(model, Scorer(model), times, values, task=k, duration=T).robot
    PN = model.n_human * N_BASIS
    return float(np.abs(f.X[:, 2 + PN:].mean(axis=0) - core.mean).max())


def test_ebip_ensemble_mean_approaches_the_conditioned_mean_as_the_ensemble_grows(fitted):
    model, _, test = fitted
    times, values = _stream(test, 1.0)
    k = model.task_index(test.task)
    errors = [np.mean([_ensemble_error(model, k, times, values, 2.0, size, seed)
                       for seed in range(3)]) for size in (20, 200, 2000)]
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 0.35 * errors[0]


def test_dtw_of_a_demo_against_itself_is_zero(fitted):
    _, lib, _ = fitted
    ref = lib.human(0, np.linspace(0, 1, 40))[2]
    distance, end = dtw_distance(ref, ref, np.ones(ref.shape[1]))
    assert distance == 0.0 and end == ref.shape[0] - 1
    other, _ = dtw_distance(ref, lib.human(1, np.linspace(0, 1, 40))[0], np.ones(3))
    assert other > 0.0


def test_dtw_of_a_prefix_ends_where_the_prefix_does(fitted):
    _, lib, _ = fitted
    ref = lib.human(0, np.linspace(0, 1, 41))[1]
    distance, end = dtw_distance(ref[:21], ref, np.ones(3))
    assert distance == 0.0 and end == 20


@pytest.mark.parametrize("name", ["nearest", "dtw"])
def test_nearest_and_dtw_recover_the_demo_they_were_given(fitted, name):
    model, lib, _ = fitted
    k, i = 1, 3
    T = float(lib.durations[k][i])
    times = np.linspace(0, T, 60)
    human = lib.human(k, times / T)[i] * model.scale
    pred = make_predictor(name, lib, dow_t=0.25, subsample=1)
    for t, y in zip(times, human):
        pred.observe(t, y)
    last = pred.last_prediction
    assert model.tasks[last.task_index] == model.tasks[k]
    np.testing.assert_allclose(last.robot.mean, lib.robot_weights(k)[i], atol=1e-12)
    assert last.duration == pytest.approx(T, rel=0.05)


@pytest.mark.parametrize("name", METHODS)
def test_every_method_drives_the_predictor_interface_with_definite_covariances(fitted, name):
    model, lib, test = fitted
    pred = make_predictor(name, lib, dow_t=0.2, expected_duration=float(test.times[-1]),
                          subsample=1)
    for t, y in zip(test.times, test.human):
        pred.observe(t, y)
    assert pred.updates and pred.task == test.task
    assert sum(pred.task_posterior.values()) == pytest.approx(1.0)
    _, mean, cov = pred.plan()
    assert np.isfinite(mean).all()
    np.testing.assert_allclose(cov, np.swapaxes(cov, 1, 2), atol=1e-12)
    assert np.linalg.eigvalsh(cov).min() > 0
    goal = pred.command(float(test.times[-1]))[0]
    assert np.abs(goal - test.robot[-1]).max() < 0.2


def test_ebip_is_reproducible_with_its_seed_and_varies_with_it(fitted):
    _, lib, test = fitted

    def goal(seed):
        pred = make_predictor("ebip", lib, dow_t=0.3, seed=seed, subsample=1)
        for t, y in zip(test.times, test.human):
            pred.observe(t, y)
        return pred.plan()[1][-1]

    np.testing.assert_array_equal(goal(1), goal(1))
    assert not np.array_equal(goal(1), goal(2))


def test_library_from_a_model_alone_matches_the_models_moments(fitted):
    model, _, _ = fitted
    lib = DemoLibrary.from_model(model)
    for k, task in enumerate(model.task_models):
        w = lib.weights[k]
        np.testing.assert_allclose(w.mean(axis=0), task.weights.mean, atol=1e-10)
        U = task.weights.factor
        np.testing.assert_allclose(np.cov(w.T), U @ U.T, atol=1e-10)
        assert lib.durations[k].mean() == pytest.approx(task.mean_duration)


@dataclass(frozen=True)
class _Modality:
    name: str
    kind: str


def test_bad_input_is_one_line_naming_the_valid_choices(fitted):
    _, lib, _ = fitted
    with pytest.raises(ValueError, match=r"^methods: expected distinct names among dynamic, "
                                         r"static, bip, ebip, dtw, nearest, got bip,foo "
                                         r"\(unknown: foo\)$"):
        check_methods("bip,foo")
    with pytest.raises(ValueError, match="distinct"):
        check_methods(["bip", "bip"])
    with pytest.raises(ValueError, match=r"^observe: method 'dtw' cannot observe 'gaze' \(a "
                                         r"direction modality\); it observes position, signal"):
        check_observable(["bip", "dtw"], [_Modality("hand", "position"),
                                          _Modality("gaze", "direction")],
                         kinds={"bip": ("position", "signal", "direction"),
                                "dtw": ("position", "signal")})
    with pytest.raises(ValueError, match="library: expected a DemoLibrary"):
        make_predictor("bip", lib.model)

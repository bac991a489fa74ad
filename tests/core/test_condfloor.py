"""A second floor for conditioning the robot (issue 28 item 4, issue 21 item 5,
``condition_floor``): the point score against a dense conditional, the floor it picks,
the predictions it changes (and those it leaves), the model file and the settings."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.core.basis import GaussianBasis
from sandbox.core.condfloor import GRID_M
from sandbox.core.floorscore import HeldOut
from sandbox.core.inference import predict
from sandbox.core.likelihood import Scorer
from sandbox.core.promp import WeightDistribution
from tests.core.test_floorsearch import demos


def dense_goal_error(own, w, P, psi, goal, sigma2) -> float:
    """||E[goal | y] - goal||^2, y = H w_h, by the dense Gaussian conditional (eq. 7-9)."""
    N = own.n_basis
    H = np.kron(np.eye(P), psi)
    Q = own.n_dims - P
    G = np.kron(np.eye(Q), goal[None])
    cov = own.cov()
    C = H @ cov[:P * N, :P * N] @ H.T + np.diag(np.repeat(sigma2, psi.shape[0]))
    cross = G @ cov[P * N:, :P * N] @ H.T
    mean = G @ own.mean[P * N:] + cross @ np.linalg.solve(C, H @ (w[:P * N] - own.mean[:P * N]))
    return float(((mean - G @ w[P * N:]) ** 2).sum())


def test_the_goal_error_equals_the_dense_conditional():
    rng = np.random.default_rng(1)
    P, Q, N, M = 2, 3, 5, 9
    basis = GaussianBasis(N)
    own = WeightDistribution.from_weights(rng.normal(size=(6, (P + Q) * N)), 0.1, N)
    w = rng.normal(size=(P + Q) * N)
    psi = basis.evaluate(np.linspace(0.0, 0.6, M))
    goal = basis.evaluate(np.array([1.0]))[0]
    held = HeldOut(own, {}, "a", w, P, psi, goal, np.zeros(P), {"a": 0.0})
    sigma2 = np.array([[0.05, 0.08], [0.3, 0.3], [1e-4, 1e-4]])   # general and equal paths
    expected = [dense_goal_error(own, w, P, psi, goal, s) for s in sigma2]
    assert held.goal_error(sigma2) == pytest.approx(expected, rel=1e-7)


def test_the_chosen_floor_is_the_least_error_and_inside_the_grid():
    model = IProMP(n_basis=9, condition_floor="auto", settle_tol=None,
                   arrive_tol=None).fit(demos(0.05))
    scores = model.condition_scores["hand"]
    chosen = float(np.sqrt(model.condition_noise).max())
    assert chosen == min(scores, key=scores.get)
    assert GRID_M[0] < chosen < GRID_M[-1]             # neither overfit nor the prior mean
    assert np.allclose(model.noise, 0.02**2)           # recognition keeps noise_floor


def test_a_given_condition_floor_floors_the_conditioning_noise_only():
    plain = IProMP(n_basis=9, settle_tol=None, arrive_tol=None).fit(demos(0.05))
    model = IProMP(n_basis=9, condition_floor=0.07, settle_tol=None,
                   arrive_tol=None).fit(demos(0.05))
    assert plain.condition_noise is None and model.condition_scores == {}
    assert np.allclose(model.condition_noise, 0.07**2)
    assert np.array_equal(model.noise, plain.noise)


def test_the_robot_is_conditioned_under_the_second_noise_and_the_task_is_not():
    train = demos(0.05)
    model = IProMP(n_basis=9, condition_floor=0.07, settle_tol=None,
                   arrive_tol=None).fit(train)
    swapped = copy.deepcopy(model)                     # the same model, Sigma_y = Sigma_c
    swapped.noise, swapped.condition_noise = model.condition_noise, None
    plain = copy.deepcopy(model)
    plain.condition_noise = None
    test = demos(0.05, n=2, seed=5)[0]
    times, values = test.times[:25], test.human[:25]
    got = predict(model, Scorer(model), times, values)
    same_task = predict(plain, Scorer(plain), times, values)
    same_robot = predict(swapped, Scorer(swapped), times, values, task=got.task_index,
                         duration=got.duration)
    assert np.array_equal(got.task_posterior, same_task.task_posterior)
    assert np.allclose(got.robot.mean, same_robot.robot.mean, atol=1e-9)
    assert np.allclose(got.robot.cov(), same_robot.robot.cov(), atol=1e-9)
    assert not np.allclose(got.robot.mean, same_task.robot.mean, atol=1e-6)
    other = 1 - got.task_index                         # a held task: conditioned alike
    held = got.for_task(model, other)
    again = predict(swapped, Scorer(swapped), times, values, task=other,
                    duration=float(got.durations[other]))
    assert np.allclose(held.robot.mean, again.robot.mean, atol=1e-9)


def test_the_condition_noise_is_stored_and_old_files_load_without_it(tmp_path):
    model = IProMP(n_basis=9, condition_floor="auto", settle_tol=None,
                   arrive_tol=None).fit(demos(0.05))
    model.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    assert loaded.condition_floor == "auto"
    assert np.array_equal(loaded.condition_noise, model.condition_noise)
    IProMP(n_basis=9, settle_tol=None, arrive_tol=None).fit(demos(0.05)).save(tmp_path / "o.npz")
    old = IProMP.load(tmp_path / "o.npz")
    assert old.condition_floor is None and old.condition_noise is None
    scorer = Scorer(old)
    assert scorer.conditioner is scorer                # conditions with Sigma_y, as before


def test_a_wrong_condition_floor_is_refused():
    with pytest.raises(ValueError, match=r"condition_floor: expected a number \(m\), 'auto' "
                                         r"or None, got 'automatic'"):
        IProMP(condition_floor="automatic")
    with pytest.raises(ValueError, match="condition_floor"):
        IProMP(condition_floor=-0.01)


def test_a_settings_file_takes_the_condition_floor(tmp_path):
    from sandbox.commands._settings import load

    path = tmp_path / "s.yaml"
    for text, value in (("auto", "auto"), ("null", None), ("0.05", 0.05)):
        path.write_text(f"condition_floor: {text}\n")
        assert load(path) == {"condition_floor": value}
    path.write_text("condition_floor: automatic\n")
    with pytest.raises(ValueError, match=r"condition_floor: expected a number \(m\), auto or "
                                         r"null, got 'automatic'"):
        load(path)


def test_fit_prints_the_conditioning_noise_and_the_file_keeps_it(tmp_path, capsys):
    from sandbox.cli import main

    settings = tmp_path / "s.yaml"
    settings.write_text("condition_floor: 0.05\n")
    out = tmp_path / "m.npz"
    assert main(["fit", "--data", "synthetic:two_task", "--n-per-task", "3", "--n-basis", "9",
                 "--config", str(settings), "--out", str(out)]) == 0
    assert "hand conditioning noise (mm, the robot's, eq. 7-9): 50.0, 50.0, 50.0" in (
        capsys.readouterr().out)
    assert np.allclose(IProMP.load(out).condition_noise, 0.05**2)

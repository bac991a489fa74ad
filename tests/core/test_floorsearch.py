"""The noise floor learned from the training demos (issue 28 item 4, ``noise_floor="auto"``):
the held-out score against a dense computation, the grid, which floor it picks on demos
whose departure from the model is known, and the model file."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from sandbox.core import IProMP
from sandbox.core.basis import GaussianBasis
from sandbox.core.floorscore import HeldOut
from sandbox.core.floorsearch import GRID_M, candidates
from sandbox.core.promp import WeightDistribution
from sandbox.data.demonstration import Demonstration


def test_candidates_are_the_grid_raised_to_the_jitter():
    assert candidates(None) == GRID_M
    assert candidates(0.004) == (0.004, 0.005, 0.007, 0.01, 0.014, 0.02, 0.028, 0.04)
    assert candidates(0.05) == (0.05,)                  # above the grid: the jitter itself


def dense_score(own, other, w, P, psi, goal, sigma2, r) -> float:
    """log p(task | y) + log N(goal | y), y = H w_h, by dense Gaussians (no Woodbury)."""
    N = own.n_basis
    H = np.kron(np.eye(P), psi)
    y = H @ w[:P * N]
    logs = []
    for dist in (own, other):
        S = dist.cov()[:P * N, :P * N]
        C = H @ S @ H.T + np.diag(np.repeat(sigma2, psi.shape[0]))
        expected = -0.5 * np.trace(np.linalg.solve(C, np.diag(np.repeat(r, psi.shape[0]))))
        logs.append(scipy.stats.multivariate_normal(H @ dist.mean[:P * N], C).logpdf(y)
                    + expected + np.log(0.5))
    Q = own.n_dims - P
    G = np.kron(np.eye(Q), goal[None])
    cov = own.cov()
    C = H @ cov[:P * N, :P * N] @ H.T + np.diag(np.repeat(sigma2, psi.shape[0]))
    cross = G @ cov[P * N:, :P * N] @ H.T
    mean = G @ own.mean[P * N:] + cross @ np.linalg.solve(C, y - H @ own.mean[:P * N])
    gcov = G @ cov[P * N:, P * N:] @ G.T - cross @ np.linalg.solve(C, cross.T)
    log_goal = scipy.stats.multivariate_normal(mean, gcov).logpdf(G @ w[P * N:])
    return float(logs[0] - np.logaddexp(*logs) + log_goal)


def test_the_score_equals_the_dense_gaussians():
    rng = np.random.default_rng(0)
    P, Q, N, M = 2, 3, 5, 9
    basis = GaussianBasis(N)
    dists = [WeightDistribution.from_weights(rng.normal(size=(6, (P + Q) * N)), 0.1, N)
             for _ in range(2)]
    w = rng.normal(size=(P + Q) * N)
    psi = basis.evaluate(np.linspace(0.0, 0.6, M))
    goal = basis.evaluate(np.array([1.0]))[0]
    r = np.array([0.01, 0.02])
    held = HeldOut(dists[0], {"b": dists[1]}, "a", w, P, psi, goal, r,
                   {"a": np.log(0.5), "b": np.log(0.5)})
    sigma2 = np.array([[0.05, 0.08], [0.3, 0.3]])
    expected = [dense_score(dists[0], dists[1], w, P, psi, goal, s, r) for s in sigma2]
    assert held.score(sigma2) == pytest.approx(expected, rel=1e-7)


def demos(departure: float, n: int = 8, seed: int = 0) -> list[Demonstration]:
    """Two tasks of reaches that vary along one direction only (their spread), each with a
    smooth wiggle of ``departure`` (m) of its own in 18 directions: what the n - 1 others
    cannot explain; the robot follows the spread, not the wiggle."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.5, 60)
    s = t / t[-1]
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    out = []
    for task, goal in (("left", [0.6, 0.3, 0.2]), ("right", [0.6, -0.3, 0.2])):
        for _ in range(n):
            end = np.array(goal) + rng.normal(0.0, 0.05) * np.array([0.0, 1.0, 0.0])
            modes = np.sin(np.pi * np.outer(s, np.arange(1, 7)))      # (T, 6): more than
            wiggle = departure * modes @ rng.normal(size=(6, 3)) / 6    # n - 1 can span
            hand = np.array([0.3, 0.0, 0.0]) + p[:, None] * (end - [0.3, 0.0, 0.0]) + wiggle
            robot = np.column_stack([p * e for e in (*end, *end[:2], 0.5, -0.5)])
            out.append(Demonstration(t, hand, robot, task))
    return out


def test_demos_the_model_explains_get_a_low_floor_and_others_a_high_one():
    low = IProMP(n_basis=9, noise_floor="auto", settle_tol=None, arrive_tol=None)
    low.fit(demos(0.0005))
    high = IProMP(n_basis=9, noise_floor="auto", settle_tol=None, arrive_tol=None)
    high.fit(demos(0.05))
    assert low.floors_used.max() <= 0.005 < 0.02 <= high.floors_used.min()
    assert set(low.floor_scores) == {"hand"} and len(low.floor_scores["hand"]) == len(GRID_M)
    assert np.all(np.sqrt(high.noise) >= high.floors_used - 1e-12)


def test_a_given_modality_floor_is_not_searched():
    model = IProMP(n_basis=9, noise_floor="auto", noise_floors={"hand": 0.011},
                   settle_tol=None, arrive_tol=None).fit(demos(0.05))
    assert np.allclose(model.floors_used, 0.011) and model.floor_scores == {}


def test_the_learned_floors_are_stored_in_the_model_file(tmp_path):
    model = IProMP(n_basis=9, noise_floor="auto", settle_tol=None,
                   arrive_tol=None).fit(demos(0.05))
    model.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    assert loaded.noise_floor == "auto"
    assert np.array_equal(loaded.floors_used, model.floors_used)
    assert np.array_equal(loaded.noise, model.noise)


def test_a_wrong_noise_floor_is_refused():
    with pytest.raises(ValueError, match=r"noise_floor: expected a number \(m\) or 'auto', "
                                         r"got 'automatic'"):
        IProMP(noise_floor="automatic")


def test_a_settings_file_takes_auto_and_names_it_when_wrong(tmp_path):
    from sandbox.commands._settings import load

    path = tmp_path / "s.yaml"
    path.write_text("noise_floor: auto\n")
    assert load(path) == {"noise_floor": "auto"}
    path.write_text("noise_floor: automatic\n")
    with pytest.raises(ValueError, match=r"noise_floor: expected a number \(m\) or auto, "
                                         r"got 'automatic'"):
        load(path)

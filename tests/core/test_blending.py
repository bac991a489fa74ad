import numpy as np
import pytest

from sandbox.core.blending import blend, sigmoid_activations


def _spd(rng, T, Q):
    A = rng.normal(size=(T, Q, Q))
    return A @ A.transpose(0, 2, 1) + 0.1 * np.eye(Q)


def _two(rng, T=6, Q=3):
    means = rng.normal(size=(2, T, Q))
    covs = np.stack([_spd(rng, T, Q), _spd(rng, T, Q)])
    return means, covs


def test_activation_one_zero_returns_one_distribution():
    rng = np.random.default_rng(0)
    means, covs = _two(rng)
    m, c = blend(means, covs, np.stack([np.ones(6), np.zeros(6)]))
    np.testing.assert_allclose(m, means[0])
    np.testing.assert_allclose(c, covs[0])
    m, c = blend(means, covs, np.stack([np.zeros(6), np.ones(6)]))
    np.testing.assert_allclose(m, means[1])
    np.testing.assert_allclose(c, covs[1])


def test_matches_information_form():
    rng = np.random.default_rng(1)
    means = rng.normal(size=(3, 4, 2))
    covs = np.stack([_spd(rng, 4, 2) for _ in range(3)])
    act = rng.uniform(0.05, 1, size=(3, 4))
    m, c = blend(means, covs, act)
    for t in range(4):
        prec = sum(act[i, t] * np.linalg.inv(covs[i, t]) for i in range(3))
        cov = np.linalg.inv(prec)
        mean = cov @ sum(act[i, t] * np.linalg.inv(covs[i, t]) @ means[i, t] for i in range(3))
        np.testing.assert_allclose(c[t], cov, rtol=1e-9)
        np.testing.assert_allclose(m[t], mean, rtol=1e-9, atol=1e-12)


def test_result_is_spd_and_symmetric():
    rng = np.random.default_rng(2)
    means, covs = _two(rng, T=50, Q=7)
    fall, rise = sigmoid_activations(np.linspace(0, 1, 50), 0.5, 20.0)
    _, c = blend(means, covs, np.stack([fall, rise]))
    np.testing.assert_array_equal(c, c.transpose(0, 2, 1))
    assert np.linalg.eigvalsh(c).min() > 0


def test_sigmoids_sum_to_one_and_cross_at_centre():
    fall, rise = sigmoid_activations(np.array([0.0, 1.0, 2.0]), 1.0, 50.0)
    np.testing.assert_allclose(fall + rise, 1.0)
    assert rise[1] == pytest.approx(0.5)
    assert rise[0] < 1e-20 and fall[2] < 1e-20


def test_errors():
    rng = np.random.default_rng(3)
    means, covs = _two(rng)
    with pytest.raises(ValueError, match="at least one positive"):
        blend(means, covs, np.zeros((2, 6)))
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        blend(means, covs, np.full((2, 6), 1.5))
    with pytest.raises(ValueError, match="shape"):
        blend(means, covs[:, :5], np.ones((2, 6)))

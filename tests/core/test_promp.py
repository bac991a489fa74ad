import numpy as np
import pytest

from sandbox.core.basis import GaussianBasis
from sandbox.core.promp import WeightDistribution, fit_weights, trajectory_distribution


def test_fit_weights_reproduces_a_basis_trajectory():
    basis = GaussianBasis(9)
    rng = np.random.default_rng(0)
    w = rng.normal(size=(2, 9))
    z = np.linspace(0, 1, 200)
    y = basis(z) @ w.T
    np.testing.assert_allclose(fit_weights(z, y, basis, ridge=0.0), w, atol=1e-6)


def test_fit_weights_skips_nan_and_does_not_mutate():
    basis = GaussianBasis(7, normalized=True)
    z = np.linspace(0, 1, 100)
    y = np.stack([np.sin(3 * z), np.cos(2 * z)], axis=1)
    y_nan = y.copy()
    y_nan[10:20, 0] = np.nan
    before = y_nan.copy()
    w_full = fit_weights(z, y, basis)
    w_nan = fit_weights(z, y_nan, basis)
    np.testing.assert_array_equal(y_nan, before)
    np.testing.assert_allclose(basis(z) @ w_nan.T, basis(z) @ w_full.T, atol=2e-3)


def test_distribution_is_positive_definite_with_few_demos():
    rng = np.random.default_rng(1)
    w = rng.normal(size=(3, 4 * 10))          # 3 demos, 40 weights
    dist = WeightDistribution.from_weights(w, 1e-3, 10)
    assert dist.factor.shape[1] == 2          # rank n - 1
    eig = np.linalg.eigvalsh(dist.cov())
    assert eig.min() > 0
    np.testing.assert_allclose(dist.mean, w.mean(axis=0))
    sample_cov = np.cov(w.T)
    np.testing.assert_allclose(dist.factor @ dist.factor.T, sample_cov, atol=1e-12)


def test_trajectory_distribution_matches_dense():
    rng = np.random.default_rng(2)
    basis = GaussianBasis(6)
    dist = WeightDistribution.from_weights(rng.normal(size=(5, 18)), 0.1, 6)
    z = np.array([0.0, 0.4, 1.0])
    mean, cov = trajectory_distribution(dist, basis, z)
    psi = basis(z)
    for i in range(3):
        H = np.kron(np.eye(3), psi[i:i + 1])
        np.testing.assert_allclose(mean[i], H @ dist.mean)
        np.testing.assert_allclose(cov[i], H @ dist.cov() @ H.T, atol=1e-12)


def test_bad_distribution():
    with pytest.raises(ValueError, match="reg"):
        WeightDistribution(np.zeros(4), np.zeros((4, 1)), np.array([1.0, 0.0]), 2)
    with pytest.raises(ValueError, match="entries"):
        WeightDistribution(np.zeros(5), np.zeros((5, 1)), np.array([1.0, 1.0]), 2)


def test_a_derived_distribution_is_the_checked_one_and_refuses_non_finite_values():
    """WeightDistribution._derived (an update's posterior, no shape checks): the same arrays as
    the public constructor, read-only; NaN or infinity is still a ValueError."""
    rng = np.random.default_rng(0)
    mean, factor, reg = rng.normal(size=10), rng.normal(size=(10, 3)), np.array([0.1, 0.2])
    reg.setflags(write=False)
    ref = WeightDistribution(mean.copy(), factor.copy(), reg, 5)
    got = WeightDistribution._derived(mean.copy(), factor.copy(), reg, 5)
    for name in ("mean", "factor", "reg"):
        np.testing.assert_array_equal(getattr(got, name), getattr(ref, name))
        assert not getattr(got, name).flags.writeable
    assert got.n_basis == 5 and got.n_dims == 2
    bad = factor.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        WeightDistribution._derived(mean.copy(), bad, reg, 5)
    with pytest.raises(ValueError, match="finite"):
        WeightDistribution._derived(np.full(10, np.inf), factor.copy(), reg, 5)

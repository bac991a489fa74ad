import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from sandbox.core.basis import GaussianBasis
from sandbox.core.interaction import condition, log_marginal_likelihood, observation_matrix


def _prior(rng, D):
    A = rng.normal(size=(D, 4))
    return rng.normal(size=D), A @ A.T + 0.05 * np.eye(D)


def _setup(rng, s=4, P=2, Q=1, N=5):
    basis = GaussianBasis(N)
    z = np.sort(rng.uniform(0, 1, s))
    H = observation_matrix(basis, z, P, Q)
    mean, cov = _prior(rng, (P + Q) * N)
    y = np.full((s, P + Q), np.nan)
    y[:, :P] = rng.normal(size=(s, P))
    noise = np.tile(np.r_[np.full(P, 0.01), np.ones(Q)], s)
    return mean, cov, H, y.ravel(), noise


def test_observation_matrix_robot_rows_are_zero():
    H = observation_matrix(GaussianBasis(4), np.array([0.2, 0.7]), 2, 3)
    assert H.shape == (2 * 5, 5 * 4)
    rows = H.reshape(2, 5, -1)
    assert np.all(rows[:, 2:] == 0)
    np.testing.assert_allclose(rows[0, 1, 4:8], GaussianBasis(4)(np.array([0.2]))[0])


def test_matches_filterpy_update():
    rng = np.random.default_rng(0)
    mean, cov, H, y, noise = _setup(rng)
    keep = np.isfinite(y)
    kf = KalmanFilter(dim_x=mean.size, dim_z=int(keep.sum()))
    kf.x, kf.P = mean.copy(), cov.copy()
    kf.H, kf.R = H[keep], np.diag(noise[keep])
    kf.update(y[keep])
    m, c = condition(mean, cov, H, y, noise)
    np.testing.assert_allclose(m, kf.x, atol=1e-8)
    np.testing.assert_allclose(c, kf.P, atol=1e-8)


def test_batch_equals_sequential():
    rng = np.random.default_rng(1)
    mean, cov, H, y, noise = _setup(rng, s=5)
    m_batch, c_batch = condition(mean, cov, H, y, noise)
    m, c = mean, cov
    for i in np.flatnonzero(np.isfinite(y)):
        m, c = condition(m, c, H[i:i + 1], y[i:i + 1], noise[i:i + 1])
    np.testing.assert_allclose(m, m_batch, atol=1e-8)
    np.testing.assert_allclose(c, c_batch, atol=1e-8)


def test_noise_free_via_point_is_passed_through():
    rng = np.random.default_rng(2)
    basis = GaussianBasis(8)
    mean, cov = _prior(rng, 8)
    H = basis(np.array([0.6]))
    target = np.array([1.234])
    m, c = condition(mean, cov, H, target, np.array([1e-12]))
    assert (H @ m)[0] == pytest.approx(1.234, abs=1e-6)
    assert (H @ c @ H.T)[0, 0] < 1e-9


def test_posterior_is_spd_and_never_wider():
    rng = np.random.default_rng(3)
    mean, cov, H, y, noise = _setup(rng, s=6)
    _, c = condition(mean, cov, H, y, noise)
    np.testing.assert_array_equal(c, c.T)
    assert np.linalg.eigvalsh(c).min() > 0
    assert np.linalg.eigvalsh(cov - c).min() > -1e-10
    assert np.all(np.diag(c) <= np.diag(cov) + 1e-12)


def test_log_likelihood_matches_scipy():
    from scipy.stats import multivariate_normal

    rng = np.random.default_rng(4)
    mean, cov, H, y, noise = _setup(rng)
    keep = np.isfinite(y)
    Hm = H[keep]
    expect = multivariate_normal(Hm @ mean, Hm @ cov @ Hm.T + np.diag(noise[keep])).logpdf(y[keep])
    assert log_marginal_likelihood(mean, cov, H, y, noise) == pytest.approx(expect, rel=1e-10)


def test_errors():
    rng = np.random.default_rng(5)
    mean, cov, H, y, noise = _setup(rng)
    with pytest.raises(ValueError, match="shape"):
        condition(mean, cov[:-1], H, y, noise)
    with pytest.raises(ValueError, match="columns"):
        condition(mean[:-1], cov[:-1, :-1], H, y, noise)
    with pytest.raises(ValueError, match="shape"):
        condition(mean, cov, H, y[:-1], noise)
    with pytest.raises(ValueError, match="infinity"):
        condition(mean, cov, H, np.where(np.isnan(y), np.inf, y), noise)

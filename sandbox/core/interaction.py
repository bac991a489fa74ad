"""Dense reference implementation of the interaction model (paper eq. 5-9, 12).

The state is the concatenated weight vector of P human and Q robot dims,
D = (P+Q)*N. An observation at phase z of the human dims is
:math:`y = H \\omega + \\epsilon`, :math:`\\epsilon \\sim \\mathcal{N}(0, \\Sigma_y)`,
where H holds :math:`\\psi(z)^T` blocks for the human dims and zero rows for the
robot dims (eq. 7, 9). Unobserved rows (NaN in ``y``, e.g. every robot row) are
masked out, which is exactly equivalent to zero rows with unbounded noise.

These functions work on dense covariances and are the ground truth the fast
path (:mod:`sandbox.core.likelihood`) is tested against; they are also the
public API for conditioning on arbitrary via-points. Everything uses Cholesky
solves; no matrix is inverted explicitly.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from sandbox.core.basis import GaussianBasis
from sandbox.validation import FloatArray, check_array

LOG_2PI = float(np.log(2.0 * np.pi))


def observation_matrix(
    basis: GaussianBasis, z: FloatArray, n_human: int, n_robot: int
) -> FloatArray:
    """H for observations at phases ``z`` (eq. 7, 9), rows ordered time-major.

    The blocks of eq. 7 for the human dims; the robot rows stay zero (eq. 9).

    Parameters
    ----------
    basis : GaussianBasis
    z : ndarray, shape (s,)
        Phases of the observations.
    n_human, n_robot : int
        P and Q.

    Returns
    -------
    H : ndarray, shape (s*(P+Q), (P+Q)*N)
        Row ``j*(P+Q) + d`` observes dim d at ``z[j]``; robot rows are zero.
    """
    z = check_array(z, "z", 1)
    psi = basis.evaluate(z)
    n, dims = basis.n_basis, n_human + n_robot
    H = np.zeros((z.size, dims, dims * n))
    for d in range(n_human):
        H[:, d, d * n : (d + 1) * n] = psi          # eq. 7; robot rows stay zero: eq. 9
    return H.reshape(z.size * dims, dims * n)


def _masked(H: FloatArray, y: FloatArray, noise: FloatArray):
    H = check_array(H, "H", 2)
    y = check_array(y, "y", 1, shape=(H.shape[0],), allow_nan=True)
    noise = np.asarray(noise, dtype=np.float64)
    R = np.diag(noise) if noise.ndim == 1 else noise
    R = check_array(R, "noise", 2, shape=(y.size, y.size))
    keep = np.isfinite(y)                          # eq. 9: unobserved rows masked
    return H[keep], y[keep], R[np.ix_(keep, keep)]


def _innovation(mean, cov, H, R):
    S = H @ cov @ H.T + R
    return scipy.linalg.cho_factor(0.5 * (S + S.T), lower=True)


def condition(
    mean: FloatArray, cov: FloatArray, H: FloatArray, y: FloatArray, noise: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Kalman update of a weight distribution on observations (eq. 8).

    .. math::  K = \\Sigma H^T (\\Sigma_y + H\\Sigma H^T)^{-1}, \\quad
               \\mu' = \\mu + K(y - H\\mu), \\quad \\Sigma' = \\Sigma - K H \\Sigma

    Parameters
    ----------
    mean : ndarray, shape (D,)
    cov : ndarray, shape (D, D)
    H : ndarray, shape (m, D)
    y : ndarray, shape (m,)
        Observations; NaN entries are unobserved (masked rows).
    noise : ndarray, shape (m,) or (m, m)
        Observation noise variances (or covariance).

    Returns
    -------
    mean, cov : ndarray, shapes (D,) and (D, D)
        The posterior; the covariance is exactly symmetric.
    """
    mean = check_array(mean, "mean", 1)
    cov = check_array(cov, "cov", 2, shape=(mean.size, mean.size))
    Hm, ym, R = _masked(H, y, noise)
    if Hm.shape[1] != mean.size:
        raise ValueError(f"H: expected {mean.size} columns, got {Hm.shape[1]}")
    if ym.size == 0:
        return mean, cov
    factor = _innovation(mean, cov, Hm, R)
    HS = Hm @ cov
    gain_t = scipy.linalg.cho_solve(factor, HS)          # S^{-1} H Sigma = K^T
    new_mean = mean + gain_t.T @ (ym - Hm @ mean)        # eq. 8
    half = scipy.linalg.solve_triangular(factor[0], HS, lower=True)
    new_cov = cov - half.T @ half                         # eq. 8: Sigma - K H Sigma
    return new_mean, 0.5 * (new_cov + new_cov.T)


def log_marginal_likelihood(
    mean: FloatArray, cov: FloatArray, H: FloatArray, y: FloatArray, noise: FloatArray
) -> float:
    """Joint log-likelihood of all observations.

    :math:`\\log\\mathcal{N}(y | H\\mu, H\\Sigma H^T + \\Sigma_y)`.

    This is the integral of eq. 12 (and of the task likelihood, eq. 15)
    evaluated for all observations together. Arguments as in :func:`condition`.
    """
    mean = check_array(mean, "mean", 1)
    cov = check_array(cov, "cov", 2, shape=(mean.size, mean.size))
    Hm, ym, R = _masked(H, y, noise)
    if ym.size == 0:
        return 0.0
    factor = _innovation(mean, cov, Hm, R)
    white = scipy.linalg.solve_triangular(factor[0], ym - Hm @ mean, lower=True)
    logdet = 2.0 * np.log(np.diag(factor[0])).sum()
    return float(-0.5 * (ym.size * LOG_2PI + logdet + white @ white))   # eq. 12, 15

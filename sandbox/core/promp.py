"""Weights of single demonstrations and the weight distribution across them (eq. 1-4, 6).

A demonstration with D dims is represented by D weight vectors of N entries,
concatenated dim after dim: :math:`\\omega = [\\omega_1^T, \\ldots, \\omega_D^T]^T`
(eq. 6). Across demonstrations the weights are modelled as
:math:`\\omega \\sim \\mathcal{N}(\\mu_\\omega, \\Sigma_\\omega)` with

.. math::  \\Sigma_\\omega = U U^T + \\Lambda, \\qquad
           \\Lambda = \\mathrm{diag}(\\lambda_1 I_N, \\ldots, \\lambda_D I_N),

where :math:`U U^T` is the sample covariance (rank <= n_demos - 1) and
:math:`\\Lambda` a per-dim diagonal regulariser that keeps
:math:`\\Sigma_\\omega` positive definite with few demonstrations. Keeping the
low-rank factor :math:`U` (instead of the dense D x D matrix) is what makes
phase estimation fast (see :mod:`sandbox.core.likelihood`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from sandbox.core.basis import GaussianBasis
from sandbox.core.limits import MAX_KAPPA, MIN_REGULARIZER
from sandbox.validation import FloatArray, check_array, check_positive


def fit_weights(
    z: FloatArray, values: FloatArray, basis: GaussianBasis, ridge: float = 1e-8
) -> FloatArray:
    """Ridge least-squares weights of one trajectory (eq. 2).

    Parameters
    ----------
    z : ndarray, shape (T,)
        Phase of each sample.
    values : ndarray, shape (T, D)
        Samples; NaN entries are left out of their dim's fit.
    basis : GaussianBasis
    ridge : float
        Ridge added to :math:`\\Psi^T\\Psi` relative to its mean diagonal.

    Returns
    -------
    weights : ndarray, shape (D, N)
    """
    z = check_array(z, "z", 1)
    values = check_array(values, "values", 2, shape=(z.size, None), allow_nan=True)
    check_positive(ridge, "ridge", allow_zero=True)
    psi = basis.evaluate(z)
    out = np.empty((values.shape[1], basis.n_basis))
    ok_all = np.isfinite(values).all(axis=1)
    if ok_all.all():
        out[:] = _ridge_solve(psi, values, ridge).T
        return out
    for d in range(values.shape[1]):
        ok = np.isfinite(values[:, d])
        if ok.sum() < 2:
            raise ValueError(f"values: dim {d} has fewer than 2 valid samples")
        out[d] = _ridge_solve(psi[ok], values[ok, d : d + 1], ridge)[:, 0]
    return out


def _ridge_solve(psi: FloatArray, y: FloatArray, ridge: float) -> FloatArray:
    gram = psi.T @ psi
    gram[np.diag_indices_from(gram)] += ridge * max(np.trace(gram) / gram.shape[0], 1e-300)
    return scipy.linalg.solve(gram, psi.T @ y, assume_a="pos")   # eq. 2 (with a ridge)


@dataclass(frozen=True, eq=False)
class WeightDistribution:
    """Gaussian over concatenated weights, :math:`\\mathcal{N}(\\mu, UU^T + \\Lambda)`.

    Attributes
    ----------
    mean : ndarray, shape (D*N,)
    factor : ndarray, shape (D*N, r)
        Low-rank factor U of the sample covariance.
    reg : ndarray, shape (D,)
        Per-dim regulariser :math:`\\lambda_d` (> 0).
    n_basis : int
    """

    mean: FloatArray
    factor: FloatArray
    reg: FloatArray
    n_basis: int

    def __post_init__(self) -> None:
        n = int(self.n_basis)
        mean = check_array(self.mean, "mean", 1)
        reg = check_array(self.reg, "reg", 1)
        if mean.size != reg.size * n:
            raise ValueError(
                f"mean: expected {reg.size} dims x {n} basis = {reg.size * n} entries, "
                f"got {mean.size}"
            )
        factor = check_array(self.factor, "factor", 2, shape=(mean.size, None))
        if np.any(reg <= 0):
            raise ValueError(f"reg: expected every regulariser > 0, got {reg.tolist()}")
        for a in (mean, factor, reg):
            a.setflags(write=False)
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "factor", factor)
        object.__setattr__(self, "reg", reg)
        object.__setattr__(self, "n_basis", n)

    @classmethod
    def _derived(cls, mean: FloatArray, factor: FloatArray, reg: FloatArray,
                 n_basis: int) -> WeightDistribution:
        """A distribution computed from checked ones (a posterior: the inner loop of an
        update), without the constructor's checks of shapes and signs; infinite or NaN
        entries are still a ``ValueError``. ``mean`` and ``factor`` must be new arrays (they
        are made read-only, not copied); ``reg`` a read-only one."""
        if not (np.isfinite(mean).all() and np.isfinite(factor).all()):
            raise ValueError("mean, factor: expected finite values, got infinity or NaN")
        out = object.__new__(cls)
        for name, a in (("mean", mean), ("factor", factor), ("reg", reg)):
            a = np.asarray(a, dtype=np.float64)
            a.setflags(write=False)
            object.__setattr__(out, name, a)
        object.__setattr__(out, "n_basis", int(n_basis))
        return out

    @property
    def n_dims(self) -> int:
        """Number of trajectory dims D."""
        return int(self.reg.size)

    @property
    def reg_diag(self) -> FloatArray:
        """Diagonal of :math:`\\Lambda`, shape (D*N,)."""
        return np.repeat(self.reg, self.n_basis)

    def cov(self) -> FloatArray:
        """Dense covariance :math:`UU^T + \\Lambda`, shape (D*N, D*N)."""
        cov = self.factor @ self.factor.T
        cov[np.diag_indices_from(cov)] += self.reg_diag
        return cov

    def dims(self, index: slice) -> WeightDistribution:
        """The marginal over a contiguous range of dims."""
        d = np.arange(self.n_dims)[index]
        rows = (d[:, None] * self.n_basis + np.arange(self.n_basis)).ravel()
        return WeightDistribution(self.mean[rows], self.factor[rows], self.reg[d], self.n_basis)

    @classmethod
    def from_weights(
        cls, weights: FloatArray, regularizer: float, n_basis: int, *, floor: float = 1e-12
    ) -> WeightDistribution:
        """Fit mean, factor and a relative regulariser from stacked weights.

        Parameters
        ----------
        weights : ndarray, shape (n_demos, D*N)
        regularizer : float
            :math:`\\lambda_d` = ``regularizer`` x (mean variance of dim d's weights),
            floored at ``floor`` x the largest such variance (and 1e-300).
        n_basis : int
        """
        w = check_array(weights, "weights", 2, min_len=1)
        check_positive(regularizer, "regularizer")
        n = w.shape[0]
        mean = w.mean(axis=0)
        factor = (w - mean).T / np.sqrt(max(n - 1, 1))
        var = (factor**2).sum(axis=1).reshape(-1, n_basis).mean(axis=1)
        reg = regularizer * np.maximum(var, max(floor * var.max(), 1e-300))
        return cls(mean, thin(factor), reg, n_basis)


def thin(factor: FloatArray) -> FloatArray:
    """Drop numerically empty directions of a factor (keeps U U^T exactly)."""
    if factor.shape[1] == 0:
        return factor
    u, s, _ = np.linalg.svd(factor, full_matrices=False)
    keep = s > s.max() * 1e-12 if s.size and s.max() > 0 else np.zeros(s.size, bool)
    return u[:, keep] * s[keep]


def trajectory_distribution(
    dist: WeightDistribution, basis: GaussianBasis, z: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Per-step mean and covariance of the trajectory at phases ``z`` (eq. 4, without the noise).

    Parameters
    ----------
    dist : WeightDistribution
        Over D dims.
    basis : GaussianBasis
    z : ndarray, shape (T,)

    Returns
    -------
    mean : ndarray, shape (T, D)
    cov : ndarray, shape (T, D, D)
        :math:`\\Psi_t (UU^T + \\Lambda) \\Psi_t^T` per step.
    """
    psi = basis.evaluate(np.asarray(z, dtype=np.float64))
    D, N = dist.n_dims, dist.n_basis
    mean = psi @ dist.mean.reshape(D, N).T                 # eq. 1, 4: psi_t^T mu
    r = dist.factor.shape[1]
    A = (psi @ dist.factor.reshape(D, N, r).transpose(1, 0, 2).reshape(N, D * r))
    A = A.reshape(-1, D, r)
    cov = A @ A.transpose(0, 2, 1)                         # eq. 4: psi_t^T Sigma psi_t
    diagonal = cov.reshape(-1, D * D)[:, ::D + 1]          # a view of every step's diagonal
    diagonal += dist.reg[None, :] * (psi**2).sum(axis=1)[:, None]
    return mean, cov


def held_trajectory(robot: WeightDistribution, duration: float, basis: GaussianBasis,
                    times) -> tuple[FloatArray, FloatArray]:
    """Robot mean (T, Q) and covariance (T, Q, Q) at ``times`` (s) of ``robot`` played over
    ``duration`` (s), held after its end (:meth:`Prediction.trajectory
    <sandbox.core.inference.Prediction.trajectory>`): eq. 4 at :math:`z = \\min(t / T, 1)`."""
    z = np.asarray(times, dtype=np.float64) / duration
    np.minimum(np.maximum(z, 0.0, out=z), 1.0, out=z)           # clip to [0, 1]
    held = int(np.count_nonzero(z >= 1.0))
    if held < 2 or not np.all(z[z.size - held:] >= 1.0):
        return trajectory_distribution(robot, basis, z)
    # After the end the motion holds (z = 1): one step of it, repeated
    moving = z.size - held + 1
    mean, cov = trajectory_distribution(robot, basis, z[:moving])
    out_mean = np.empty((z.size,) + mean.shape[1:])
    out_cov = np.empty((z.size,) + cov.shape[1:])
    out_mean[:moving], out_cov[:moving] = mean, cov
    out_mean[moving:], out_cov[moving:] = mean[-1], cov[-1]
    return out_mean, out_cov


def check_robot_definite(dist: WeightDistribution, P: int, task: str) -> None:
    """Each robot dim's regulariser at least MIN_REGULARIZER / 2 x its weights' variance.

    :math:`UU^T + \\Lambda` is positive definite for any positive :math:`\\Lambda`;
    this keeps it so in floating point, where the predictors blend the robot's.
    """
    N = dist.n_basis
    U = dist.factor[P * N:].reshape(dist.n_dims - P, N, -1)
    var = (U**2).sum(axis=2).mean(axis=1)
    ratio = dist.reg[P:] / np.maximum(var, 1e-300)
    if np.any(ratio < MIN_REGULARIZER / 2):
        raise ValueError(f"task {task!r}: robot regularisers of {ratio.min():.3g} x the weights' "
                         f"variance leave its covariance numerically singular; expected at "
                         f"least {MIN_REGULARIZER / 2:g} (limits.MIN_REGULARIZER / 2)")


def check_human_conditioning(dist: WeightDistribution, noise: FloatArray, task: str) -> None:
    """Each human dim's :math:`\\kappa = \\lambda_p/\\sigma_p^2` at most MAX_KAPPA.

    The likelihood factors :math:`I + \\kappa\\Psi^T\\Psi` per speed candidate
    (:mod:`sandbox.core.likelihood`); past the limit it is no longer positive
    definite in floating point.

    Parameters
    ----------
    dist : WeightDistribution
        Over the P human dims first, then the robot's.
    noise : ndarray, shape (P,)
        Observation noise variances :math:`\\sigma_p^2` (> 0).
    task : str
        Named in the message.
    """
    kappa = dist.reg[: noise.size] / noise
    if np.any(kappa > MAX_KAPPA):
        raise ValueError(f"task {task!r}: human regularisers of up to {kappa.max():.3g} x the "
                         f"observation noise; expected at most {MAX_KAPPA:g} "
                         f"(limits.MAX_KAPPA: the likelihood's factorisation fails beyond)")

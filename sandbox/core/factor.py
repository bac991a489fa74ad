"""The linear algebra of one likelihood evaluation (:mod:`sandbox.core.likelihood`).

:func:`b_part` factors the block-diagonal part B of one modality for every
speed candidate (step 1 of the likelihood's module docstring); :func:`factor_scores`
takes one batched Cholesky of the augmented matrices (step 3) and returns the
log-likelihoods with the factors (compiled with numba when installed:
``sandbox/core/_kernels.py``); :func:`condition_robot` reuses a factor to
condition the robot weights (eq. 8). Only numpy and scipy.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from scipy.linalg import lapack

from sandbox.core import _kernels
from sandbox.core.promp import WeightDistribution
from sandbox.validation import FloatArray


def b_part(G: FloatArray, beta: FloatArray, yy: FloatArray, kappa: float):
    """Per candidate: log|A|, W = G - kappa G A^-1 G, A^-1 beta, y^T(I+kappa Psi Psi^T)^-1 y.

    Parameters
    ----------
    G : ndarray, shape (C, N, N)
        :math:`\\Psi^T\\Psi` of the rows observing the group, per candidate.
    beta : ndarray, shape (C, N, Pg)
        :math:`\\Psi^T y_p` per dim of the group.
    yy : ndarray, shape (Pg,)
        :math:`y_p^T y_p`.
    kappa : float
        The group's :math:`\\kappa`; :math:`A = I + \\kappa G`.
    """
    return b_parts(G, [beta], [yy], [kappa])[0]


def b_parts(G: FloatArray, betas, yys, kappas) -> list:
    """:func:`b_part` of several groups observed on the same rows (one G): one batched
    Cholesky of every group's :math:`A = I + \\kappa_g G` instead of one per group."""
    C, N, _ = G.shape
    n = len(kappas)
    Gs = G if n == 1 else np.concatenate([G] * n)
    kap = np.repeat(np.asarray(kappas, dtype=np.float64), C)[:, None, None]
    A = kap * Gs
    A[:, np.arange(N), np.arange(N)] += 1.0
    L = np.linalg.cholesky(A)
    ld = 2.0 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1)
    Li = np.empty_like(L)
    for c in range(n * C):   # triangular inverse of a factor of A >= I: backward stable
        Li[c] = lapack.dtrtri(L[c], lower=1)[0]
    Q = Li @ Gs
    W = Gs - kap * (Q.transpose(0, 2, 1) @ Q)
    out = []
    for i in range(n):
        part = slice(i * C, (i + 1) * C)
        Lb = Li[part] @ betas[i]
        ab = Li[part].transpose(0, 2, 1) @ Lb
        gamma = yys[i] - kappas[i] * (Lb**2).sum(axis=1)
        out.append((ld[part], W[part], ab, gamma))
    return out


def factor_scores(Kt: FloatArray, eps: FloatArray, gamma_term: FloatArray,
                  offset: FloatArray, *, work: FloatArray | None = None
                  ) -> tuple[FloatArray, FloatArray]:
    """Log-likelihoods and augmented Cholesky factors from a pair's statistics.

    Parameters
    ----------
    Kt : ndarray, shape (M, R+1, R+1)
        :math:`\\tilde K` in the padded layout (U in the first r rows/columns,
        zeros up to R, :math:`\\mu` at R). Overwritten with the augmented matrix on the
        numpy path unless ``work`` is given (the compiled kernel of
        ``sandbox/core/_kernels.py``, when numba is installed, leaves it unchanged).
    eps : ndarray, shape (M, R+1)
        :math:`\\epsilon`, same layout.
    gamma_term : ndarray, shape (M,)
        :math:`y^T B^{-1} y = \\sum_p \\gamma_p / \\sigma_p^2`.
    offset : ndarray, shape (M,)
        :math:`sP\\log 2\\pi + \\log|B|`.
    work : ndarray, shape (M, R+1, R+1), optional
        A buffer the numpy path builds the augmented matrix in, leaving ``Kt`` unchanged
        (a kept buffer: allocating megabytes per update costs more than copying them).

    Returns
    -------
    loglik : ndarray, shape (M,)
    factors : ndarray, shape (M, R+1, R+1)
    """
    done = _compiled(Kt, eps, gamma_term, offset, True)
    return done if done is not None else _numpy_scores(Kt, eps, gamma_term, offset, work)


def factor_loglik(Kt: FloatArray, eps: FloatArray, gamma_term: FloatArray,
                  offset: FloatArray, *, work: FloatArray | None = None) -> FloatArray:
    """The log-likelihoods (M,) of :func:`factor_scores` alone, the same numbers: the
    compiled kernel writes no factors (the phase grid needs those of a few pairs only)."""
    done = _compiled(Kt, eps, gamma_term, offset, False)
    return (done if done is not None else _numpy_scores(Kt, eps, gamma_term, offset, work))[0]


#: Matrices larger than this (rows) go to LAPACK when fewer than :data:`FEW_LANES` of them
#: come together: the compiled kernel lays a batch's matrices side by side, and a few lanes
#: of large matrices run slower than LAPACK's one matrix at a time (the refinement's 4
#: pairs of 94 rows, 160 demos per task: 0.60 ms against 0.20 ms; of 40 rows 0.05 against
#: 0.07 ms; measured at load 8-11).
LARGE_ROWS = 48
#: See :data:`LARGE_ROWS`.
FEW_LANES = 16


def _compiled(Kt, eps, gamma_term, offset, factors: bool):
    """(loglik, factors) from the compiled kernel (``factors``: written, else an empty
    array); None when there is no kernel for this size, a few large matrices
    (:data:`LARGE_ROWS`) or a block failed (numpy's turn)."""
    M, n = Kt.shape[:2]
    if n > LARGE_ROWS and M < FEW_LANES:
        return None
    kernel = _kernels.factor_kernel(n)
    if kernel is None or not M:
        return None
    loglik, L = np.empty(M), np.empty((M if factors else 0, n, n))
    if kernel(np.ascontiguousarray(Kt, dtype=np.float64), np.ascontiguousarray(eps),
              np.ascontiguousarray(gamma_term, dtype=np.float64),
              np.ascontiguousarray(offset, dtype=np.float64), L, loglik,
              _kernels.block_size(n)):
        return loglik, L
    return None


def _numpy_scores(Kt, eps, gamma_term, offset, work):
    """:func:`factor_scores` on the numpy path."""
    if work is not None:
        np.copyto(work, Kt)
        Kt = work
    R = Kt.shape[1] - 1
    e = eps[:, :R] - Kt[:, :R, R]                                  # U^T Phi^T B^-1 d
    dbd = gamma_term - 2.0 * eps[:, R] + Kt[:, R, R]               # d^T B^-1 d
    idx = np.arange(R)
    Kt[:, idx, idx] += 1.0                                         # K = I + J
    Kt[:, R, :R] = e
    Kt[:, :R, R] = e
    Kt[:, R, R] = dbd
    return _factored_scores(Kt, offset)


def augmented_scores(aug: FloatArray, offset: FloatArray, *,
                     work: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:
    """Log-likelihoods (M,) and factors (M, R+1, R+1) of augmented matrices themselves.

    ``aug`` (M, R+1, R+1) holds each pair's
    :math:`\\begin{bmatrix} K & e \\\\ e^T & d^T B^{-1} d\\end{bmatrix}` (the matrix
    :func:`factor_scores` assembles from the statistics; a stream keeps it,
    :mod:`sandbox.core.statistics`), ``offset`` (M,) :math:`sP\\log 2\\pi + \\log|B|`.
    ``aug`` is left unchanged (factored in ``work`` when given, else in a copy); a lost
    last pivot is clamped as in :func:`factor_scores`.
    """
    if work is None:
        work = aug.copy()
    else:
        np.copyto(work, aug)
    return _factored_scores(work, offset)


def _factored_scores(aug: FloatArray, offset: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Log-likelihoods (M,) (eq. 12) and factors of augmented matrices (M, R+1, R+1),
    from their Cholesky factors: half log|K| from the first R pivots, the Mahalanobis term
    the last (shared by both numpy paths)."""
    R = aug.shape[1] - 1
    L = _cholesky(aug)
    diag = np.diagonal(L, axis1=1, axis2=2)
    logdet_k = 2.0 * np.log(diag[:, :R]).sum(axis=1)
    return -0.5 * (offset + logdet_k + diag[:, R] ** 2), L


def _cholesky(aug: FloatArray) -> FloatArray:
    try:
        return np.asarray(np.linalg.cholesky(aug), dtype=np.float64)
    except np.linalg.LinAlgError:
        return np.stack([_cholesky_one(m) for m in aug])


def _cholesky_one(m: FloatArray) -> FloatArray:
    """Cholesky of one augmented matrix whose last pivot may be lost to round-off."""
    try:
        return np.asarray(np.linalg.cholesky(m), dtype=np.float64)
    except np.linalg.LinAlgError:
        R = m.shape[0] - 1
        L = np.zeros_like(m)
        L[:R, :R] = np.linalg.cholesky(m[:R, :R])
        g = scipy.linalg.solve_triangular(L[:R, :R], m[:R, R], lower=True)
        L[R, :R] = g
        L[R, R] = np.sqrt(max(m[R, R] - g @ g, 1e-300))
        return L


def _lower_solve(L: FloatArray, b: FloatArray, trans: int = 0) -> FloatArray:
    """:math:`L^{-1} b` (or :math:`L^{-T} b`) for a lower-triangular factor with a positive
    diagonal: LAPACK's trtrs directly (scipy's checks cost more than these small solves)."""
    if L.shape[0] == 0:
        return np.zeros(b.shape)
    x, info = lapack.dtrtrs(L, b, lower=1, trans=trans)
    assert info == 0, info          # a Cholesky factor's diagonal is positive
    return np.asarray(x, dtype=np.float64)


def condition_robot(weights: WeightDistribution, factor: FloatArray, n_human: int,
                    rank: int) -> WeightDistribution:
    """Posterior of the robot weights given the observations scored with ``factor``.

    Parameters
    ----------
    weights : WeightDistribution
        The task's prior over human + robot weights.
    factor : ndarray, shape (R+1, R+1)
        The augmented Cholesky factor of the chosen (candidate, task) pair.
    n_human : int
        P.
    rank : int
        r of this task (the factor is padded to R >= r). Columns of the weights'
        factor past ``rank`` must have a zero human block
        (:func:`~sandbox.core.likelihood.compress_human`): they pass unchanged.

    Returns
    -------
    WeightDistribution
        Over the Q robot dims: mean :math:`\\mu_r + U_r K^{-1} e`, factor
        :math:`U_r L_K^{-T}`, regulariser :math:`\\Lambda_r` (eq. 8 restricted to the
        robot block).
    """
    N = weights.n_basis
    R = factor.shape[0] - 1
    LK = factor[:rank, :rank]
    g = factor[R, :rank]
    U_r = weights.factor[n_human * N:, :rank]
    kinv_e = _lower_solve(LK, g, trans=1)
    new_factor = _lower_solve(LK, U_r.T).T
    if weights.factor.shape[1] > rank:     # columns the observations do not see (compress_human)
        new_factor = np.hstack([new_factor, weights.factor[n_human * N:, rank:]])
    mean = weights.mean[n_human * N:] + U_r @ kinv_e          # eq. 8
    return WeightDistribution._derived(mean, new_factor, weights.reg[n_human:], N)

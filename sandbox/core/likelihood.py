"""Fast exact likelihoods of partial human observations for many speeds and tasks.

For task k and a candidate duration T (phase :math:`z_j = t_j / T`), the human
observations :math:`y \\in \\mathbb{R}^{sP}` have the marginal (eq. 12, 16)

.. math::  y \\sim \\mathcal{N}(\\Phi\\mu_h, \\; \\Phi(\\Lambda_h + U_hU_h^T)\\Phi^T + R),
           \\quad \\Phi = I_P \\otimes \\Psi, \\; R = \\Sigma_y \\otimes I_s .

Computed densely this is an sP x sP Cholesky per (candidate, task) pair. Here:

1. :math:`B = \\Phi\\Lambda_h\\Phi^T + R` is block diagonal with blocks
   :math:`\\sigma_p^2 (I + \\kappa\\Psi\\Psi^T)`; with the model's shared
   :math:`\\kappa = \\lambda_p/\\sigma_p^2`, one N x N Cholesky of
   :math:`A = I + \\kappa G`, :math:`G = \\Psi^T\\Psi`, per candidate serves every
   human dim and every task (push-through identity:
   :math:`\\Psi^T B_p^{-1}\\Psi = (G - \\kappa G A^{-1} G)/\\sigma_p^2`).
2. The low-rank part :math:`U_h` (rank r = n_demos - 1) enters through the
   r x r matrix :math:`K = I + U_h^T\\Phi^T B^{-1}\\Phi U_h` (Woodbury and the
   determinant lemma); its entries for all candidates of a task come out of two
   large matrix products.
3. One batched Cholesky of the augmented matrix
   :math:`\\begin{bmatrix} K & e \\\\ e^T & d^T B^{-1} d\\end{bmatrix}`,
   :math:`d = y - \\Phi\\mu_h`, :math:`e = U_h^T\\Phi^T B^{-1} d`, gives
   :math:`\\log|K|` from its first r pivots and the Mahalanobis term
   :math:`d^T S^{-1} d = d^TB^{-1}d - e^T K^{-1} e` from the last.

The same factor conditions the robot weights for free (see
:func:`condition_robot`): :math:`\\mu_r' = \\mu_r + U_r K^{-1} e`,
:math:`\\Sigma_r' = \\Lambda_r + U_r K^{-1} U_r^T`.

The per-step alternative (``mode="marginal"``) multiplies the marginals of each
observation instead, as older public code does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.linalg import lapack

from sandbox.core.interaction import LOG_2PI
from sandbox.core.promp import WeightDistribution
from sandbox.core.validation import FloatArray


@dataclass(frozen=True, eq=False)
class Scores:
    """Log-likelihoods of (candidate, task) pairs.

    Attributes
    ----------
    loglik : list of ndarray
        ``loglik[k]`` has one entry per candidate in task k's span.
    factors : list of ndarray or None
        ``factors[k]`` (C_k, R+1, R+1): Cholesky factors of the augmented matrix
        (joint mode only), for :func:`condition_robot`.
    """

    loglik: list
    factors: list | None


class Scorer:
    """Precomputed, per fitted model, everything the likelihood needs.

    Parameters
    ----------
    model : IProMP
        A fitted model.
    """

    def __init__(self, model) -> None:
        model._require_fit()
        self.basis = model.basis
        P, N = model.n_human, model.basis.n_basis
        self.P, self.N, self.K = P, N, len(model.task_models)
        self.sigma2 = np.asarray(model.noise, dtype=np.float64)
        kappa = np.array([t.weights.reg[:P] / self.sigma2 for t in model.task_models])
        self.kappas, self.group = _groups(kappa)
        self.rank = [t.weights.factor.shape[1] for t in model.task_models]
        self.R = max(self.rank)
        self.reg_h = np.array([t.weights.reg[:P] for t in model.task_models])  # (K, P)
        blocks, raw, self.cols = [], [], []
        start = 0
        for t in model.task_models:
            ut = _human_block(t.weights, P, N)                    # (P, N, r+1): [U_h, mu_h]
            raw.append(ut.transpose(1, 0, 2).reshape(N, -1))
            blocks.append((ut / np.sqrt(self.sigma2)[:, None, None]).transpose(1, 0, 2))
            self.cols.append(slice(start, start + P * ut.shape[2]))
            start += P * ut.shape[2]
        self.V = [b.reshape(N * P, -1) for b in blocks]          # (N*P, r+1) per task
        pad = np.zeros((N, self.K, P, self.R + 1))
        for k, b in enumerate(blocks):                             # U in [:r], mu at R
            pad[:, k, :, : self.rank[k]] = b[..., :-1]
            pad[:, k, :, self.R] = b[..., -1]
        self.V_pad = pad.reshape(N, -1)                           # (N, K*P*(R+1))
        self.V_all = np.hstack([b.reshape(N, -1) for b in blocks])  # (N, sum P(r+1))
        self.U_raw = np.hstack(raw)

    # --------------------------------------------------------------- joint
    def joint(self, times: FloatArray, values: FloatArray, durations: FloatArray,
              spans: np.ndarray) -> Scores:
        """Joint log-likelihood of all observations for every pair.

        Parameters
        ----------
        times : ndarray, shape (s,)
            Observation times (s) since the motion started.
        values : ndarray, shape (s, P)
            Observed human dims (no NaN).
        durations : ndarray, shape (C,)
            Candidate durations T (s), each >= ``times[-1]``.
        spans : ndarray of int, shape (K, 2)
            Task k scores candidates ``durations[spans[k,0]:spans[k,1]]``.
        """
        s, P, N = times.size, self.P, self.N
        psi = self.basis.evaluate(times[None, :] / durations[:, None])      # (C, s, N)
        psi_t = psi.transpose(0, 2, 1)
        G = psi_t @ psi                                                      # (C, N, N)
        beta = psi_t @ values                                                # (C, N, P)
        yy = np.einsum("sp,sp->p", values, values)
        per_group = [_b_part(G, beta, yy, kap) for kap in self.kappas]
        C = durations.size
        T_all = [(g[1].reshape(C * N, N) @ self.V_all).reshape(C, N, -1) for g in per_group]
        log_sigma = s * np.log(self.sigma2).sum()
        loglik, factors = [], []
        for k in range(self.K):
            a, b = int(spans[k, 0]), int(spans[k, 1])
            if b <= a:
                loglik.append(np.empty(0))
                factors.append(np.empty((0, self.R + 1, self.R + 1)))
                continue
            Kt, eps, gamma_term, logdet_b = self._gram(k, a, b, per_group, T_all)
            ll, L = factor_scores(Kt, eps, gamma_term, s * P * LOG_2PI + log_sigma + logdet_b)
            loglik.append(ll)
            factors.append(L)
        return Scores(loglik, factors)

    def _gram(self, k, a, b, per_group, T_all):
        """Task k's padded statistics (as :func:`factor_scores` takes them) for candidates a:b."""
        P, N, R, r = self.P, self.N, self.R, self.rank[k]
        C = b - a
        groups = self.group[k]
        Kt = np.zeros((C, r + 1, r + 1))
        eps = np.zeros((C, r + 1))
        gamma_term = np.zeros(C)
        logdet_b = np.zeros(C)
        V = self.V[k].reshape(N, P, r + 1)
        for g in np.unique(groups):
            dims = np.flatnonzero(groups == g)
            ld_a, _, ab, gamma = per_group[g]
            T = T_all[g][a:b, :, self.cols[k]].reshape(C, N, P, r + 1)[:, :, dims]
            Vg = V[:, dims].reshape(-1, r + 1)                                  # (N*Pg, r+1)
            Tg = T.transpose(1, 2, 0, 3).reshape(Vg.shape[0], C * (r + 1))
            Kt += (Vg.T @ Tg).reshape(r + 1, C, r + 1).transpose(1, 0, 2)
            x = (ab[a:b][:, :, dims] / np.sqrt(self.sigma2[dims])).reshape(C, -1)
            eps += x @ Vg
            gamma_term += (gamma[a:b][:, dims] / self.sigma2[dims]).sum(axis=1)
            logdet_b += dims.size * ld_a[a:b]
        pos = np.r_[np.arange(r), R]          # U in [:r], mu at R, zeros in between
        padded = np.zeros((C, R + 1, R + 1))
        padded[:, pos[:, None], pos] = Kt
        eps_padded = np.zeros((C, R + 1))
        eps_padded[:, pos] = eps
        return padded, eps_padded, gamma_term, logdet_b

    def joint_pairs(self, times: FloatArray, values: FloatArray, durations: FloatArray,
                    tasks: np.ndarray) -> tuple[FloatArray, FloatArray]:
        """Joint log-likelihood of a few (duration, task) pairs, vectorised over pairs.

        Parameters
        ----------
        times, values : as for :meth:`joint`.
        durations : ndarray, shape (M,)
        tasks : ndarray of int, shape (M,)

        Returns
        -------
        loglik : ndarray, shape (M,)
        factors : ndarray, shape (M, R+1, R+1)
            Augmented Cholesky factors (same layout as :meth:`joint`).
        """
        if len(self.kappas) != 1:
            out = [self.joint(times, values, durations[i:i + 1], self._one_span(k))
                   for i, k in enumerate(tasks)]
            return (np.array([o.loglik[k][0] for o, k in zip(out, tasks)]),
                    np.array([o.factors[k][0] for o, k in zip(out, tasks)]))
        s, P, N, R1, M = times.size, self.P, self.N, self.R + 1, durations.size
        psi = self.basis.evaluate(times[None, :] / durations[:, None])
        psi_t = psi.transpose(0, 2, 1)
        G, beta = psi_t @ psi, psi_t @ values
        ld_a, W, ab, gamma = _b_part(G, beta, np.einsum("sp,sp->p", values, values),
                                     self.kappas[0])
        V = self.V_pad.reshape(N, self.K, P, R1).transpose(1, 0, 2, 3)[tasks]   # (M, N, P, R1)
        WV = (W @ V.reshape(M, N, P * R1)).reshape(M, N * P, R1)
        Vf = V.reshape(M, N * P, R1)
        Kt = Vf.transpose(0, 2, 1) @ WV
        x = (ab / np.sqrt(self.sigma2)).reshape(M, 1, N * P)
        eps = (x @ Vf)[:, 0]
        const = s * P * LOG_2PI + s * np.log(self.sigma2).sum()
        return factor_scores(Kt, eps, (gamma / self.sigma2).sum(axis=1), const + P * ld_a)

    def _one_span(self, k: int) -> np.ndarray:
        spans = np.zeros((self.K, 2), dtype=int)
        spans[k] = (0, 1)
        return spans

    # ------------------------------------------------------------ marginal
    def marginal(self, times: FloatArray, values: FloatArray, durations: FloatArray,
                 spans: np.ndarray) -> Scores:
        """Sum over observations of per-step marginal log-likelihoods.

        Arguments as for :meth:`joint`.
        """
        P = self.P
        psi = self.basis.evaluate(times[None, :] / durations[:, None])      # (C, s, N)
        sq = (psi**2).sum(axis=2)                                           # (C, s)
        proj = psi @ self.U_raw                                             # (C, s, cols)
        loglik = []
        for k in range(self.K):
            a, b = int(spans[k, 0]), int(spans[k, 1])
            r = self.rank[k]
            blk = proj[a:b, :, self.cols[k]].reshape(b - a, times.size, P, r + 1)
            low, mean = blk[..., :r], blk[..., r]
            S = low @ low.transpose(0, 1, 3, 2)
            idx = np.arange(P)
            S[..., idx, idx] += self.sigma2 + self.reg_h[k] * sq[a:b, :, None]
            L = np.linalg.cholesky(S)
            d = (values - mean)[..., None]
            w = np.linalg.solve(L, d)[..., 0]
            logdet = 2.0 * np.log(np.diagonal(L, axis1=2, axis2=3)).sum(axis=2)
            ll = -0.5 * (P * LOG_2PI + logdet + (w**2).sum(axis=2))
            loglik.append(ll.sum(axis=1))
        return Scores(loglik, None)


def _human_block(weights: WeightDistribution, P: int, N: int) -> FloatArray:
    U = weights.factor[: P * N].reshape(P, N, -1)
    mu = weights.mean[: P * N].reshape(P, N, 1)
    return np.concatenate([U, mu], axis=2)


def _groups(kappa: FloatArray):
    """Distinct values of kappa (K, P) up to 1e-9 relative, and each entry's group."""
    flat = kappa.ravel()
    values: list[float] = []
    group = np.empty(flat.size, dtype=int)
    for i, v in enumerate(flat):
        for j, u in enumerate(values):
            if abs(v - u) <= 1e-9 * max(abs(u), 1e-300):
                group[i] = j
                break
        else:
            values.append(float(v))
            group[i] = len(values) - 1
    return values, group.reshape(kappa.shape)


def _b_part(G: FloatArray, beta: FloatArray, yy: FloatArray, kappa: float):
    """Per candidate: log|A|, W = G - kappa G A^-1 G, A^-1 beta, y^T(I+kappa Psi Psi^T)^-1 y."""
    C, N, _ = G.shape
    A = kappa * G
    A[:, np.arange(N), np.arange(N)] += 1.0
    L = np.linalg.cholesky(A)
    ld = 2.0 * np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1)
    Li = np.empty_like(L)
    for c in range(C):   # triangular inverse of a factor of A >= I: backward stable
        Li[c] = lapack.dtrtri(L[c], lower=1)[0]
    Q = Li @ G
    W = G - kappa * (Q.transpose(0, 2, 1) @ Q)
    Lb = Li @ beta
    ab = Li.transpose(0, 2, 1) @ Lb
    gamma = yy - kappa * (Lb**2).sum(axis=1)
    return ld, W, ab, gamma


def factor_scores(Kt: FloatArray, eps: FloatArray, gamma_term: FloatArray,
                  offset: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Log-likelihoods and augmented Cholesky factors from a pair's statistics.

    Parameters
    ----------
    Kt : ndarray, shape (M, R+1, R+1)
        :math:`\\tilde K` in the padded layout (U in the first r rows/columns,
        zeros up to R, :math:`\\mu` at R). Overwritten with the augmented matrix.
    eps : ndarray, shape (M, R+1)
        :math:`\\epsilon`, same layout.
    gamma_term : ndarray, shape (M,)
        :math:`y^T B^{-1} y = \\sum_p \\gamma_p / \\sigma_p^2`.
    offset : ndarray, shape (M,)
        :math:`sP\\log 2\\pi + \\log|B|`.

    Returns
    -------
    loglik : ndarray, shape (M,)
    factors : ndarray, shape (M, R+1, R+1)
    """
    R = Kt.shape[1] - 1
    e = eps[:, :R] - Kt[:, :R, R]                                  # U^T Phi^T B^-1 d
    dbd = gamma_term - 2.0 * eps[:, R] + Kt[:, R, R]               # d^T B^-1 d
    idx = np.arange(R)
    Kt[:, idx, idx] += 1.0                                         # K = I + J
    Kt[:, R, :R] = e
    Kt[:, :R, R] = e
    Kt[:, R, R] = dbd
    L = _cholesky(Kt)
    diag = np.diagonal(L, axis1=1, axis2=2)
    logdet_k = 2.0 * np.log(diag[:, :R]).sum(axis=1)
    return -0.5 * (offset + logdet_k + diag[:, R] ** 2), L


def _cholesky(aug: FloatArray) -> FloatArray:
    try:
        return np.linalg.cholesky(aug)
    except np.linalg.LinAlgError:
        return np.stack([_cholesky_one(m) for m in aug])


def _cholesky_one(m: FloatArray) -> FloatArray:
    """Cholesky of one augmented matrix whose last pivot may be lost to round-off."""
    try:
        return np.linalg.cholesky(m)
    except np.linalg.LinAlgError:
        R = m.shape[0] - 1
        L = np.zeros_like(m)
        L[:R, :R] = np.linalg.cholesky(m[:R, :R])
        g = scipy.linalg.solve_triangular(L[:R, :R], m[:R, R], lower=True)
        L[R, :R] = g
        L[R, R] = np.sqrt(max(m[R, R] - g @ g, 1e-300))
        return L


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
        r of this task (the factor is padded to R >= r).

    Returns
    -------
    WeightDistribution
        Over the Q robot dims: mean :math:`\\mu_r + U_r K^{-1} e`, factor
        :math:`U_r L_K^{-T}`, regulariser :math:`\\Lambda_r` (eq. 9 restricted to the
        robot block).
    """
    N = weights.n_basis
    R = factor.shape[0] - 1
    LK = factor[:rank, :rank]
    g = factor[R, :rank]
    U_r = weights.factor[n_human * N:]
    kinv_e = scipy.linalg.solve_triangular(LK, g, lower=True, trans="T")
    new_factor = scipy.linalg.solve_triangular(LK, U_r.T, lower=True).T
    mean = weights.mean[n_human * N:] + U_r @ kinv_e
    return WeightDistribution(mean, new_factor, weights.reg[n_human:], N)

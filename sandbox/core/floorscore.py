"""The held-out score of :mod:`sandbox.core.floorsearch` for one demo and prefix ratio.

:class:`HeldOut` precomputes what does not depend on the observation noise, then
:meth:`HeldOut.score` evaluates many candidate noise variances at once. When every
human dim has the same variance (one position modality, its residuals below the
floor: the usual case) the matrices are diagonalised once per task
(:math:`\\sum_p A_p = V \\Lambda V^T`) and a candidate costs O(P N); otherwise each
candidate factors a P N square matrix.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from sandbox.core.promp import WeightDistribution
from sandbox.validation import FloatArray

_LOG_2PI = float(np.log(2.0 * np.pi))


class HeldOut:
    r"""What the score needs of one held-out demo and prefix ratio, precomputed.

    The prefix's M samples of the demo's smoothed human track, :math:`y = H w`, are
    sufficient through the weights: with :math:`G = H^T \Sigma_y^{-1} H` (block
    diagonal, :math:`\Psi^T\Psi / \sigma_p^2`) and :math:`\delta = w_h - \mu_h`,
    Woodbury and the determinant lemma give every term in the P N weight dims,
    whatever M: :math:`K = (\Sigma_{hh}^{-1} + G)^{-1}`,
    :math:`d^T C^{-1} d = \delta^T G \delta - \delta^T G K G \delta`,
    :math:`\log|C| = M \sum_p \log\sigma_p^2 + \log|I + L^T G L|`
    (:math:`\Sigma_{hh} = L L^T`). Built once; :meth:`score` then evaluates any
    vector of noise variances.
    """

    def __init__(self, own: WeightDistribution, others: Mapping[str, WeightDistribution],
                 task: str, weights: FloatArray, P: int, psi: FloatArray, goal: FloatArray,
                 residual_var: FloatArray, log_prior: Mapping[str, float],
                 cache: dict | None = None) -> None:
        N = own.n_basis
        self.task, self.P, self.M = task, P, psi.shape[0]
        gram = psi.T @ psi
        cache = {} if cache is None else cache
        self.r = np.asarray(residual_var, dtype=np.float64)
        self.parts = {}
        for name, dist in {**others, task: own}.items():
            key = (name, self.M)
            if name == task or key not in cache:
                cache[key] = _human_part(dist, gram, P)
            h_mean, L, gL, A, eig = cache[key]
            delta = (weights[:P * N] - h_mean).reshape(P, N)
            self.parts[name] = (A, np.einsum("pnk,pn->pk", gL, delta),         # b_p = L_p' g d_p
                                np.einsum("pn,nm,pm->p", delta, gram, delta), log_prior[name],
                                eig)
        h_mean, L, _, _, _ = cache[(task, self.M)]
        delta = (weights[:P * N] - h_mean).reshape(P, N)
        Q = own.n_dims - P
        GU = np.einsum("n,qnr->qr", goal, own.factor[P * N:].reshape(Q, N, -1))
        g_cov = GU @ GU.T + np.diag(own.reg[P:] * (goal**2).sum())
        diff = weights[P * N:].reshape(Q, N) @ goal - own.mean[P * N:].reshape(Q, N) @ goal
        cross = np.einsum("qr,pnr->pqn", GU, own.factor[:P * N].reshape(P, N, -1))
        c = np.einsum("pqn,nm->pqm", cross, gram)                            # c_p = x_p g
        self.goal = (diff, g_cov, np.einsum("pqn,pnk->pqk", c, L),          # D_p = c_p L_p
                     np.einsum("pqn,pn->pq", c, delta),                     # e_p = c_p d_p
                     np.einsum("pqn,psn->pqs", c, cross))                   # F_p = c_p x_p'

    def score(self, sigma2: FloatArray) -> FloatArray:
        """log p(task | y) + log N(goal | y), shape (C,), for observation variances
        ``sigma2`` of shape (C, P): C candidates at once."""
        inv = 1.0 / np.atleast_2d(np.asarray(sigma2, dtype=np.float64))
        logs: dict[str, FloatArray] = {}
        own: tuple = ()
        equal = bool(np.all(inv == inv[:, :1]))       # one variance for every dim: eigen path
        for name, part in self.parts.items():
            quad, logdet_b, trace, goal_terms = (_equal if equal else _general)(
                inv, part, self.goal[2] if name == self.task else None)
            logdet = -self.M * np.log(inv).sum(axis=1) + logdet_b
            logs[name] = part[3] - 0.5 * (quad + logdet + self.M * self.P * _LOG_2PI
                                          + (self.M * inv + trace) @ self.r)
            if name == self.task:
                own = (inv, *goal_terms)
        values = np.array(list(logs.values()))                     # (K, C)
        top = values.max(axis=0)
        log_task = logs[self.task] - (top + np.log(np.exp(values - top).sum(axis=0)))
        return log_task + self._goal_log(*own)

    def goal_error(self, sigma2: FloatArray) -> FloatArray:
        """Squared error of the goal's conditional mean (eq. 7-9), shape (C,), for
        observation variances ``sigma2`` (C, P): a point score no covariance can game."""
        inv = 1.0 / np.atleast_2d(np.asarray(sigma2, dtype=np.float64))
        equal = bool(np.all(inv == inv[:, :1]))
        shift = (_equal if equal else _general)(inv, self.parts[self.task], self.goal[2])[3][0]
        diff, _, _, e, _ = self.goal
        return ((diff - (inv @ e - shift)) ** 2).sum(axis=1)

    def _goal_log(self, inv: FloatArray, shift: FloatArray, xbx: FloatArray) -> FloatArray:
        """log N(goal) under the conditional (eq. 7-9), shape (C,): mean shift
        :math:`X H^T C^{-1} d`, covariance :math:`\\Sigma_{gg} - X H^T C^{-1} H X^T`
        (X the goal's cross-covariance with the human weights); ``shift`` (C, Q) and
        ``xbx`` (C, Q, Q) are the :math:`X G L B^{-1}` parts of both."""
        diff, g_cov, _, e, F = self.goal
        err = diff - (inv @ e - shift)
        cov = g_cov - np.einsum("cp,pqs->cqs", inv, F) + xbx
        cov = (cov + cov.transpose(0, 2, 1)) / 2 + 1e-12 * np.eye(cov.shape[1])
        chol = np.linalg.cholesky(cov)
        z = np.linalg.solve(chol, err[..., None])[..., 0]
        return -0.5 * ((z**2).sum(axis=1) + err.shape[1] * _LOG_2PI
                       + 2.0 * np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1))


def _human_part(dist: WeightDistribution, gram: FloatArray, P: int) -> tuple:
    """A task's human mean, the rows of each dim of :math:`L` (:math:`\\Sigma_{hh} = LL^T`,
    (P, N, PN)), :math:`g L_p`, :math:`A_p = L_p^T g L_p` for the Gram matrix g, and the
    eigendecomposition (eigenvalues, vectors) of :math:`\\sum_p A_p`."""
    h = dist.dims(slice(0, P))
    L = np.linalg.cholesky(h.cov()).reshape(P, dist.n_basis, -1)
    gL = np.einsum("nm,pmk->pnk", gram, L)
    A = np.einsum("pnk,pnl->pkl", L, gL)
    lam, V = np.linalg.eigh(A.sum(axis=0))
    return h.mean, L, gL, A, (lam, V, np.einsum("kj,pkl,lj->pj", V, A, V))


def _general(inv: FloatArray, part: tuple, D: FloatArray | None) -> tuple:
    """Quadratic form, log|B|, the trace terms :math:`-\\mathrm{tr}(A_p B^{-1})/\\sigma_p^4`
    (C, P) and, with the goal's ``D`` (P, Q, PN), its
    shift and X B^-1 X' terms, for any variances ``inv`` (C, P) (inverses)."""
    A, b, quad0 = part[:3]
    B = np.einsum("cp,pkl->ckl", inv, A)
    B += np.eye(B.shape[1])
    chol = np.linalg.cholesky(B)
    Binv = np.linalg.inv(B)
    v = inv @ b                                             # L' G delta, (C, PN)
    Bv = np.einsum("ckl,cl->ck", Binv, v)
    quad = inv @ quad0 - np.einsum("ck,ck->c", v, Bv)
    logdet = 2.0 * np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1)
    goal: tuple = ()
    if D is not None:
        XGL = np.einsum("cp,pqk->cqk", inv, D)
        goal = (np.einsum("cqk,ck->cq", XGL, Bv), XGL @ Binv @ XGL.transpose(0, 2, 1))
    return quad, logdet, -inv**2 * np.einsum("pkl,ckl->cp", A, Binv), goal


def _equal(inv: FloatArray, part: tuple, D: FloatArray | None) -> tuple:
    """:func:`_general` for variances equal over the dims (``inv[:, p]`` all alike), through
    the eigendecomposition: :math:`B^{-1} = V \\mathrm{diag}(1 / (1 + t\\lambda)) V^T`."""
    _, b, quad0, _, (lam, V, diag) = part
    t = inv[:, 0]
    w = 1.0 / (1.0 + t[:, None] * lam)                      # (C, PN)
    s = b.sum(axis=0) @ V                                   # V' L' g delta / t
    quad = t * quad0.sum() - t**2 * (w * s**2).sum(axis=1)
    logdet = -np.log(w).sum(axis=1)
    goal: tuple = ()
    if D is not None:
        DV = D.sum(axis=0) @ V                              # (Q, PN)
        goal = ((t**2)[:, None] * ((w * s) @ DV.T),
                (t**2)[:, None, None] * np.einsum("qj,cj,sj->cqs", DV, w, DV))
    return quad, logdet, -inv**2 * (w @ diag.T), goal

"""Sufficient statistics of an observation stream, grown one observation at a time.

The joint likelihood of :mod:`sandbox.core.likelihood` needs, for every speed
candidate c (a fixed :class:`~sandbox.core.phase.Lattice` of durations):

* :math:`M_c = A_c^{-1} = (I + \\kappa G_c)^{-1}` and :math:`\\log|A_c|`,
* :math:`W_c = G_c M_c`, :math:`\\rho_{c,p} = M_c \\beta_{c,p}` and
  :math:`\\gamma_{c,p} = y_p^T (I + \\kappa\\Psi_c\\Psi_c^T)^{-1} y_p`,

and, for every task k,
:math:`\\tilde K_{ck} = \\sum_p \\tilde U_{kp}^T W_c \\tilde U_{kp}/\\sigma_p^2` and
:math:`\\epsilon_{ck} = \\sum_p \\tilde U_{kp}^T \\rho_{c,p}/\\sigma_p^2`.

All of them grow with each observation :math:`(t_j, y_j)`: with
:math:`\\psi = \\psi(t_j / T_c)`, :math:`v = M\\psi`, :math:`d = 1 + \\kappa\\psi^T v`
(a scalar Kalman step of the weight-space regulariser; Sherman-Morrison),

.. math::
    M \\leftarrow M - \\kappa v v^T/d,\\quad W \\leftarrow W + v v^T/d,\\quad
    \\log|A| \\leftarrow \\log|A| + \\log d,

    \\nu_p = y_p - \\kappa\\psi^T\\rho_p,\\quad \\rho_p \\leftarrow \\rho_p + v\\nu_p/d,\\quad
    \\gamma_p \\leftarrow \\gamma_p + \\nu_p^2/d,

so :math:`\\tilde K` and :math:`\\epsilon` grow by rank-P terms of
:math:`x_{kp} = \\tilde U_{kp}^T v/(\\sqrt d\\,\\sigma_p)`. A window update then
only assembles and factors the r x r matrices. The results equal the batch
computation (:meth:`~sandbox.core.likelihood.Scorer.joint`) to round-off.
"""

from __future__ import annotations

import numpy as np

from sandbox.core.interaction import LOG_2PI
from sandbox.core.likelihood import Scorer, Scores, factor_scores
from sandbox.core.phase import Lattice


class StreamStatistics:
    """Statistics of the observations received so far, for every lattice candidate.

    Parameters
    ----------
    scorer : Scorer
        Of a model whose human regulariser ratio :math:`\\kappa` is shared by all
        human dims and tasks (true of every model :meth:`IProMP.fit` makes).
    lattice : Lattice
        The candidate durations.
    flush_every : int
        Rank-P contributions are accumulated in batches of this many observations.
    """

    def __init__(self, scorer: Scorer, lattice: Lattice, flush_every: int = 8) -> None:
        if len(scorer.kappas) != 1:
            raise ValueError("stream statistics need one shared regulariser ratio kappa; "
                             f"this model has {len(scorer.kappas)}")
        self.scorer = scorer
        self.lattice = lattice
        self.durations = lattice.durations
        self.kappa = float(scorer.kappas[0])
        self.flush_every = int(flush_every)
        self.reset()

    def reset(self) -> None:
        """Forget every observation."""
        sc, C = self.scorer, self.durations.size
        N, P, K, R1 = sc.N, sc.P, sc.K, sc.R + 1
        self.M = np.broadcast_to(np.eye(N), (C, N, N)).copy()
        self.logdet_a = np.zeros(C)
        self.rho = np.zeros((C, N, P))
        self.gamma = np.zeros((C, P))
        self.Kt = np.zeros((C, K, R1, R1))
        self.eps = np.zeros((C, K, R1))
        self.count = 0
        self._x: list[np.ndarray] = []
        self._coef: list[np.ndarray] = []

    def add(self, t: float, y: np.ndarray) -> None:
        """Add one observation: time ``t`` (s) and human values ``y`` (P,), finite."""
        sc, kap = self.scorer, self.kappa
        psi = sc.basis.evaluate(t / self.durations)                       # (C, N)
        v = (self.M @ psi[:, :, None])[:, :, 0]
        d = 1.0 + kap * np.einsum("cn,cn->c", psi, v)
        nu = y[None, :] - kap * np.einsum("cn,cnp->cp", psi, self.rho)
        vd = v / d[:, None]
        self.M -= kap * vd[:, :, None] * v[:, None, :]
        self.rho += vd[:, :, None] * nu[:, None, :]
        self.gamma += nu * nu / d[:, None]
        self.logdet_a += np.log(d)
        sqrt_d = np.sqrt(d)
        self._x.append((v / sqrt_d[:, None]) @ sc.V_pad)                 # (C, K*P*(R+1))
        self._coef.append(nu / (sqrt_d[:, None] * np.sqrt(sc.sigma2)))  # (C, P)
        self.count += 1
        if len(self._x) >= self.flush_every:
            self._flush()

    def _flush(self) -> None:
        if not self._x:
            return
        sc = self.scorer
        C, K, P, R1, n = self.durations.size, sc.K, sc.P, sc.R + 1, len(self._x)
        x = np.stack(self._x, axis=1).reshape(C, n, K, P, R1)
        x = x.transpose(0, 2, 1, 3, 4).reshape(C * K, n * P, R1)        # rows (obs, dim)
        coef = np.stack(self._coef, axis=1)                               # (C, n, P)
        coef = np.broadcast_to(coef[:, None], (C, K, n, P)).reshape(C * K, n * P, 1)
        self.Kt += (x.transpose(0, 2, 1) @ x).reshape(C, K, R1, R1)
        self.eps += (x.transpose(0, 2, 1) @ coef)[..., 0].reshape(C, K, R1)
        self._x.clear()
        self._coef.clear()

    def scores(self, spans: np.ndarray) -> Scores:
        """Joint log-likelihoods for every task's candidates (as :meth:`Scorer.joint`).

        Parameters
        ----------
        spans : ndarray of int, shape (K, 2)
            Task k scores ``durations[spans[k,0]:spans[k,1]]``.
        """
        self._flush()
        sc, s = self.scorer, self.count
        P = sc.P
        const = s * P * LOG_2PI + s * np.log(sc.sigma2).sum()
        gamma_term = (self.gamma / sc.sigma2).sum(axis=1)
        sizes = [int(b - a) for a, b in spans]
        Kt = np.concatenate([self.Kt[a:b, k] for k, (a, b) in enumerate(spans)])
        eps = np.concatenate([self.eps[a:b, k] for k, (a, b) in enumerate(spans)])
        cand = np.concatenate([np.arange(a, b) for a, b in spans])
        ll, L = factor_scores(Kt, eps, gamma_term[cand], const + P * self.logdet_a[cand])
        cuts = np.cumsum(sizes)[:-1]
        return Scores(np.split(ll, cuts), np.split(L, cuts))

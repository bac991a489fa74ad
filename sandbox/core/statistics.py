"""Sufficient statistics of an observation stream, grown one observation at a time.

The joint likelihood of :mod:`sandbox.core.likelihood` needs, for every speed
candidate c (a fixed :class:`~sandbox.core.phase.Lattice` of durations) and
every group of dims (one per modality; its :math:`\\kappa`, its rows), below
written for one group:

* :math:`M_c = A_c^{-1} = (I + \\kappa G_c)^{-1}` and :math:`\\log|A_c|`,
* :math:`W_c = G_c M_c`, :math:`\\rho_{c,p} = M_c \\beta_{c,p}` and
  :math:`\\gamma_{c,p} = y_p^T (I + \\kappa\\Psi_c\\Psi_c^T)^{-1} y_p`,

and, for every task k,
:math:`\\tilde K_{ck} = \\sum_p \\tilde U_{kp}^T W_c \\tilde U_{kp}/\\sigma_p^2` and
:math:`\\epsilon_{ck} = \\sum_p \\tilde U_{kp}^T \\rho_{c,p}/\\sigma_p^2`.

All of them grow with each observation :math:`(t_j, y_j)` of the group's
modality (a row lacking the modality leaves the group unchanged): with
:math:`\\psi = \\psi(\\min(t_j / T_c, 1))`, :math:`v = M\\psi`,
:math:`d = 1 + \\kappa\\psi^T v` (a scalar Kalman step of the weight-space
regulariser; Sherman-Morrison),

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

from sandbox.core.factor import factor_scores
from sandbox.core.interaction import LOG_2PI
from sandbox.core.likelihood import Scorer, Scores
from sandbox.core.phase import Lattice


class _GroupStats:
    """The N x N part of one :class:`~sandbox.core.likelihood.Group` for every candidate."""

    def __init__(self, C: int, N: int, n_dims: int) -> None:
        self.M = np.broadcast_to(np.eye(N), (C, N, N)).copy()
        self.logdet_a = np.zeros(C)
        self.rho = np.zeros((C, N, n_dims))
        self.gamma = np.zeros((C, n_dims))
        self.count = 0


class StreamStatistics:
    """Statistics of the observations received so far, for every lattice candidate.

    Parameters
    ----------
    scorer : Scorer
        Of the model; each of its groups (one per modality for a fitted model)
        keeps its own N x N statistics, grown only by the rows that observe it.
    lattice : Lattice
        The candidate durations.
    flush_every : int
        Rank-P contributions are accumulated in batches of this many observations.
    """

    def __init__(self, scorer: Scorer, lattice: Lattice, flush_every: int = 8) -> None:
        self.scorer = scorer
        self.lattice = lattice
        self.durations = lattice.durations
        self.flush_every = int(flush_every)
        self.reset()

    def reset(self) -> None:
        """Forget every observation."""
        sc, C = self.scorer, self.durations.size
        self.groups = [_GroupStats(C, sc.N, g.dims.size) for g in sc.groups]
        self.Kt = np.zeros((C, sc.K, sc.R + 1, sc.R + 1))
        self.eps = np.zeros((C, sc.K, sc.R + 1))
        self.count = 0
        self._x: list[np.ndarray] = []
        self._coef: list[np.ndarray] = []

    def add(self, t: float, y: np.ndarray) -> None:
        """Add one observation: time ``t`` (s) and human values ``y`` (P,).

        A modality with a NaN in ``y`` is not observed by this row.
        """
        sc = self.scorer
        psi = sc.basis.evaluate(np.minimum(t / self.durations, 1.0))      # (C, N)
        present = sc.present(y[None, :])[:, 0]
        for g, st in zip(sc.groups, self.groups):
            if present[g.modality]:
                self._add_group(g, st, psi, y[g.dims])
        self.count += 1
        if len(self._x) >= self.flush_every:
            self._flush()

    def _add_group(self, g, st: _GroupStats, psi: np.ndarray, y: np.ndarray) -> None:
        """One Sherman-Morrison step of the group's statistics (module docstring)."""
        kap = g.kappa
        v = (st.M @ psi[:, :, None])[:, :, 0]
        d = 1.0 + kap * np.einsum("cn,cn->c", psi, v)
        nu = y[None, :] - kap * np.einsum("cn,cnp->cp", psi, st.rho)
        vd = v / d[:, None]
        st.M -= kap * vd[:, :, None] * v[:, None, :]
        st.rho += vd[:, :, None] * nu[:, None, :]
        st.gamma += nu * nu / d[:, None]
        st.logdet_a += np.log(d)
        st.count += 1
        sqrt_d = np.sqrt(d)
        C, K = psi.shape[0], self.scorer.K
        x = (v / sqrt_d[:, None]) @ g.blocks.transpose(1, 0, 2, 3).reshape(psi.shape[1], -1)
        self._x.append(x.reshape(C, K, g.dims.size, -1))                   # (C, K, Pg, R+1)
        self._coef.append(nu / (sqrt_d[:, None] * np.sqrt(self.scorer.sigma2[g.dims])))

    def _flush(self) -> None:
        if not self._x:
            return
        C, K, R1 = self.durations.size, self.scorer.K, self.scorer.R + 1
        x = np.concatenate(self._x, axis=2).reshape(C * K, -1, R1)         # rows (obs, dim)
        coef = np.concatenate(self._coef, axis=1)                         # (C, rows)
        coef = np.broadcast_to(coef[:, None], (C, K, coef.shape[1])).reshape(C * K, -1, 1)
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
        sc = self.scorer
        C = self.durations.size
        const = np.zeros((sc.K, C))
        gamma_term = np.zeros((sc.K, C))
        for g, st in zip(sc.groups, self.groups):
            per_dim = st.count * (LOG_2PI + sc.log_sigma2[g.dims])                # (Pg,)
            member = g.member                                                     # (K, Pg)
            const += (member @ per_dim)[:, None] + member.sum(axis=1)[:, None] * st.logdet_a
            gamma_term += member @ (st.gamma / sc.sigma2[g.dims]).T
        pick = [(k, slice(int(a), int(b))) for k, (a, b) in enumerate(spans)]
        ll, L = factor_scores(np.concatenate([self.Kt[c, k] for k, c in pick]),   # one batch
                              np.concatenate([self.eps[c, k] for k, c in pick]),
                              np.concatenate([gamma_term[k, c] for k, c in pick]),
                              np.concatenate([const[k, c] for k, c in pick]))
        cuts = np.cumsum([c.stop - c.start for _, c in pick])[:-1]
        return Scores(np.split(ll, cuts), np.split(L, cuts))

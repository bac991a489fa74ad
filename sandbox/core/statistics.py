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
:math:`x_{kp} = \\tilde U_{kp}^T v/(\\sqrt d\\,\\sigma_p)`, and
:math:`y^T B^{-1} y` by :math:`c_p^2`, :math:`c_p = \\nu_p/(\\sqrt d\\,\\sigma_p)`. What a
pair's likelihood factors (step 3 of :mod:`sandbox.core.likelihood`) is the augmented matrix
:math:`\\begin{bmatrix} I + \\tilde K_{UU} & \\epsilon_U - \\tilde K_{UR} \\\\ \\cdot &
y^T B^{-1} y - 2\\epsilon_R + \\tilde K_{RR}\\end{bmatrix}`, which therefore grows by
:math:`z z^T` per observed dim, :math:`z = [x_{kp,U}, \\; c_p - x_{kp,R}]`. The statistics
keep that matrix of every (candidate, task) pair the lattice scores (each task's span),
packed task after task (:attr:`StreamStatistics.pairs`): on the numpy path the matrix
itself, factored at every update in one batched Cholesky; with the compiled kernels
(``sandbox.core._updates``) its Cholesky factor, brought up to date by rank-1 updates
as the rows arrive, so that an update factors nothing. Either way the results equal the
batch computation (:meth:`~sandbox.core.likelihood.Scorer.joint`) to round-off.
"""

from __future__ import annotations

import numpy as np

from sandbox.core import _updates
from sandbox.core.factor import _cholesky, augmented_scores
from sandbox.core.interaction import LOG_2PI
from sandbox.core.likelihood import Scorer, Scores
from sandbox.core.phase import GridLayout, Lattice


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
        spans = lattice.spans()
        self.spans = spans
        #: Task and candidate of every packed pair, shape (2, M): task k's candidates in order.
        self.pairs = np.array([(k, c) for k, (a, b) in enumerate(spans) for c in range(a, b)],
                              dtype=np.int64).reshape(-1, 2).T
        self.cuts = np.cumsum(spans[:, 1] - spans[:, 0])[:-1]
        self._layout: tuple[object, GridLayout] | None = None
        self._rank = np.asarray(scorer.rank, dtype=np.int64)
        self._starts = np.ascontiguousarray(spans[:, 0], dtype=np.int64)
        self._counts = np.ascontiguousarray(spans[:, 1] - spans[:, 0], dtype=np.int64)
        self._cuts = np.concatenate([[0], np.cumsum(self._counts)])     # packed, per task
        self._at = _updates.layout(self._rank, self._counts)            # the factors' store
        #: Task k's rows in the padded layout: its r_k directions and the augmented one.
        self._active = [np.r_[np.arange(r), scorer.R] for r in self._rank]
        self._members = [np.ascontiguousarray(g.member, dtype=np.float64) for g in scorer.groups]
        self.reset()

    def reset(self) -> None:
        """Forget every observation."""
        sc, C = self.scorer, self.durations.size
        self.groups = [_GroupStats(C, sc.N, g.dims.size) for g in sc.groups]
        M, n = self.pairs.shape[1], sc.R + 1
        self._factored = _updates.update_kernels(n) is not None
        if self._factored:       # each task's block of factors of [[I, 0], [0, 0]]
            self._held = np.zeros(self._at[-1])
            for k, U in enumerate(self._blocks()):
                U[np.arange(self._rank[k]), np.arange(self._rank[k])] = 1.0
        else:                    # the augmented matrices of no observation, padded
            self._held = np.zeros((M, n, n))
            self._held[:, np.arange(sc.R), np.arange(sc.R)] = 1.0
        self._work: np.ndarray | None = None    # the numpy path factors in it (kept)
        self._scratch = np.empty(0)             # the kernel's (rows grow it)
        self.count = 0
        self._terms: tuple[int, np.ndarray] | None = None
        self._x: list[np.ndarray] = []
        self._coef: list[np.ndarray] = []
        self._member: list[np.ndarray] = []

    def add(self, t: float, y: np.ndarray) -> None:
        """Add one observation: time ``t`` (s) and human values ``y`` (P,).

        A modality with a NaN in ``y`` is not observed by this row.
        """
        sc = self.scorer
        psi = sc.basis.evaluate(np.minimum(t / self.durations, 1.0))      # (C, N)
        present = sc.present(y[None, :])[:, 0]
        for g, st, member in zip(sc.groups, self.groups, self._members):
            if present[g.modality]:
                self._add_group(g, st, psi, y[g.dims])
                self._member.append(member)
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

    def _sync(self):
        """The compiled kernels (None: the numpy path), the kept matrices turned into the
        form they take (factors with the kernels, else the matrices): the choice can change
        between updates (``SANDBOX_KERNEL``)."""
        kernels = _updates.update_kernels(self.scorer.R + 1)
        if (kernels is not None) == self._factored:
            return kernels
        if kernels is None:                               # factors -> augmented matrices
            L = self._factors(np.arange(self.pairs.shape[1]))
            self._held = L @ L.transpose(0, 2, 1)
        else:                                             # and back, task by task
            aug, self._held = self._held, np.zeros(self._at[-1])
            for k, U in enumerate(self._blocks()):
                act = self._active[k]
                part = aug[self._cuts[k]:self._cuts[k + 1]][:, act[:, None], act]
                U[...] = _cholesky(part).transpose(2, 1, 0)
        self._factored = kernels is not None
        return kernels

    def _blocks(self) -> list[np.ndarray]:
        """Views of each task's block of factors (r_k+1, r_k+1, C_k) in the store."""
        return [self._held[a:b].reshape(r + 1, r + 1, n) for a, b, r, n in
                zip(self._at[:-1], self._at[1:], self._rank, self._counts)]

    def _factors(self, index: np.ndarray) -> np.ndarray:
        """Lower factors (n, R+1, R+1) of the packed pairs ``index`` from the store, padded
        (the identity on a task's padding rows, the augmented row at R): one compiled copy."""
        R = self.scorer.R
        out = np.zeros((index.size, R + 1, R + 1))
        task = self.pairs[0][index]
        _updates.copy_factors(self._held, self._at, self._rank, self._counts, task,
                              index - self._cuts[task], out)
        return out

    def _flush(self) -> None:
        """The pending rows into every pair's augmented matrix or factor (module docstring)."""
        kernels = self._sync()
        if not self._x:
            return
        pk, pc = self.pairs
        x = np.concatenate(self._x, axis=2)                              # (C, K, rows, R+1)
        coef = np.concatenate(self._coef, axis=1)                        # (C, rows)
        member = np.concatenate(self._member, axis=1)                    # (K, rows)
        if kernels is not None:
            need = (x.shape[2] + 1) * (self.scorer.R + 2) * self._counts.max() \
                + 5 * self._counts.max()
            if self._scratch.size < need:
                self._scratch = np.empty(need)
            kernels[0](self._held, self._at, self._rank, self._starts, self._counts, x,
                       coef, member, self._scratch)
        else:
            z = x[pc, pk]                                                # (M, rows, R+1)
            z[..., -1] = member[pk] * coef[pc] - z[..., -1]
            self._held += z.transpose(0, 2, 1) @ z
        self._x.clear()
        self._coef.clear()
        self._member.clear()

    def packed_scores(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint log-likelihoods (M,) and augmented factors (M, R+1, R+1) of every pair.

        Pairs are packed task after task (:attr:`pairs`); :meth:`scores` splits them.
        """
        self._flush()
        if self._factored:
            return self.packed_loglik(), self._factors(np.arange(self.pairs.shape[1]))
        self._terms = None                  # computed afresh: an update's cost, every update
        if self._work is None:
            self._work = np.empty_like(self._held)
        return augmented_scores(self._held, self._offset(), work=self._work)

    def packed_loglik(self) -> np.ndarray:
        """The log-likelihoods (M,) of :meth:`packed_scores` alone: with the compiled
        kernels, from the kept factors (the phase grid takes the few factors it needs from
        :meth:`pair_factors`)."""
        self._flush()
        if not self._factored:
            return self.packed_scores()[0]
        self._terms = None
        loglik = np.empty(self.pairs.shape[1])
        _updates.update_kernels(self.scorer.R + 1)[1](self._held, self._at, self._rank,
                                                       self._counts, self._offset(), loglik)
        return loglik

    def grid(self):
        """Log-likelihoods (M,) of every pair and ``index -> factors`` (n, R+1, R+1) of a few.

        With the compiled kernels the factors are kept: only the log-likelihoods are made,
        and the few factors asked for are copied (:meth:`pair_factors`). The numpy path
        factors every pair anyway and returns them. The same numbers either way.
        """
        if self._sync() is not None:
            return self.packed_loglik(), self.pair_factors
        ll, L = self.packed_scores()
        return ll, lambda index: L[index]

    def layout(self, tasks) -> GridLayout:
        """The phase grid's :class:`~sandbox.core.phase.GridLayout` of ``tasks`` (a sequence
        of :class:`~sandbox.core.model.TaskModel`) on this lattice, made once per sequence:
        it depends on no observation."""
        if self._layout is None or self._layout[0] is not tasks:
            self._layout = (tasks, GridLayout.of(tasks, self.durations, self.spans))
        return self._layout[1]

    def pair_factors(self, index: np.ndarray) -> np.ndarray:
        """Augmented factors (n, R+1, R+1) of the packed pairs ``index`` (n,): the same
        matrices as :meth:`packed_scores` returns for them (each is factored alone)."""
        self._flush()
        if self._factored:
            return self._factors(np.asarray(index))
        return augmented_scores(self._held[index], self._offset()[index])[1]

    def _offset(self) -> np.ndarray:
        """:math:`sP\\log 2\\pi + \\log|B|` of every packed pair (kept for
        :meth:`pair_factors` until the next observation or :meth:`packed_scores`)."""
        if self._terms is not None and self._terms[0] == self.count:
            return self._terms[1]
        sc = self.scorer
        const = np.zeros((sc.K, self.durations.size))
        for g, st in zip(sc.groups, self.groups):
            per_dim = st.count * (LOG_2PI + sc.log_sigma2[g.dims])                # (Pg,)
            member = g.member                                                     # (K, Pg)
            const += (member @ per_dim)[:, None] + member.sum(axis=1)[:, None] * st.logdet_a
        pk, pc = self.pairs
        self._terms = (self.count, const[pk, pc])
        return self._terms[1]

    def scores(self, spans: np.ndarray | None = None) -> Scores:
        """Joint log-likelihoods for every task's candidates (as :meth:`Scorer.joint`).

        Parameters
        ----------
        spans : ndarray of int, shape (K, 2), optional
            Task k scores ``durations[spans[k,0]:spans[k,1]]``: the lattice's spans
            (the statistics are kept for those pairs only; others are a ``ValueError``).
        """
        if spans is not None and not np.array_equal(spans, self.spans):
            raise ValueError(f"spans: expected the lattice's {self.spans.tolist()}, "
                             f"got {np.asarray(spans).tolist()}")
        ll, L = self.packed_scores()
        return Scores(np.split(ll, self.cuts), np.split(L, self.cuts))

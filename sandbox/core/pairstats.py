"""The statistics of a few (duration, task) pairs by the optional compiled kernel.

:meth:`~sandbox.core.likelihood.Scorer.joint_pairs` scores pairs whose durations are
off the lattice (the phase refinement of :func:`~sandbox.core.phase.estimate_phase`, an
oracle's duration): each needs its own N x N factorisation per group and the r x r
statistics of its task, built from every observation. On the numpy path that is some
sixty numpy calls per update whatever the number of pairs; with numba installed
(``sandbox/core/_kernels.py``) :func:`pair_statistics` builds them in one compiled call.
Its statistics agree with the numpy path's within 1e-13 of their largest entry; the
log-likelihood, a difference of terms a thousand times its size, within 1e-15 of those
terms (a few 1e-12 of itself; ``tests/core/test_kernels.py``).

A pair's :math:`\\tilde K` sums :math:`V_p^T W V_p` over the group's dims p (N x (r+1)
blocks :math:`V_p` of the task's loadings, :math:`W = G - \\kappa G A^{-1} G` the group's
N x N part, :func:`~sandbox.core.factor.b_part`): about N (r+1)^2 multiply-adds a dim. Seen
on n < N rows, W has rank n: :math:`W = F^T F` with F (n, N) from the rows' n x n
matrix :math:`I + \\kappa\\Psi_o\\Psi_o^T` (Woodbury), so the kernel takes
:math:`\\tilde K = X^T X`, X the dims' :math:`F V_p` stacked (n Pg x (r+1)): n (r+1)^2
multiply-adds a dim, in one product. The many-demos bench case (20 observations, N = 31,
r + 1 = 94): the refinement's four pairs' statistics 0.42-0.70 ms against 0.60-0.82 (3
alternating runs, load 12). With N rows or more the kernel takes W as before (the same
numbers, bit for bit); the log-likelihoods of the rows' space agree with the numpy path's
within 1e-12 of themselves (1.7e-13 seen).
"""

from __future__ import annotations

from math import log
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core import _kernels
from sandbox.core.interaction import LOG_2PI
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.likelihood import Group


def pack_groups(groups: list[Group], sigma2: FloatArray, log_sigma2: FloatArray) -> tuple:
    """The groups in the compiled kernel's layout (precomputed once per scorer).

    Returns
    -------
    tuple
        ``dims`` (cols,) the human dim of every group column, ``starts`` (G+1,) each group's
        columns, ``modality`` (G,), ``kappa`` (G,), ``columns`` (3, cols) each column's
        :math:`\\sigma_p`, :math:`\\sigma_p^2`, :math:`\\log 2\\pi + \\log\\sigma_p^2`,
        ``member`` (K, cols) and ``blocks`` (K, cols, N, R+1).
    """
    dims = np.concatenate([g.dims for g in groups]).astype(np.int64)
    starts = np.concatenate([[0], np.cumsum([g.dims.size for g in groups])]).astype(np.int64)
    columns = np.stack([np.sqrt(sigma2[dims]), sigma2[dims], LOG_2PI + log_sigma2[dims]])
    member = np.ascontiguousarray(np.concatenate([g.member for g in groups], axis=1))
    blocks = np.concatenate([g.blocks.transpose(0, 2, 1, 3) for g in groups], axis=1)
    return (dims, starts, np.array([g.modality for g in groups], dtype=np.int64),
            np.array([g.kappa for g in groups], dtype=np.float64), columns, member,
            np.ascontiguousarray(blocks))


def pair_statistics(packed: tuple, R: int, psi: FloatArray, values: FloatArray,
                    present: np.ndarray, tasks: np.ndarray):
    """``(Kt, eps, gamma_term, offset)`` of pairs (as ``Scorer._stats``), or None without
    the compiled kernel.

    Parameters
    ----------
    packed : tuple
        :func:`pack_groups` of the scorer.
    R : int
        The scorer's padded rank.
    psi : ndarray, shape (M, s, N)
        The basis at every pair's phases of the observations.
    values : ndarray, shape (s, P)
        The observations (NaN where a modality is not observed).
    present : ndarray of bool, shape (n_modalities, s)
        Which modalities each row observes.
    tasks : ndarray of int, shape (M,)
    """
    kernel = pair_kernel(R + 1)
    if kernel is None:
        return None
    M = psi.shape[0]
    Kt, eps = np.zeros((M, R + 1, R + 1)), np.zeros((M, R + 1))
    gamma_term, offset = np.zeros(M), np.zeros(M)
    kernel(np.ascontiguousarray(psi), np.ascontiguousarray(values, dtype=np.float64),
           np.ascontiguousarray(present), np.asarray(tasks, dtype=np.int64), *packed,
           Kt, eps, gamma_term, offset)
    return Kt, eps, gamma_term, offset


_COMPILED: list = []      # [True] once compiled (or loaded from numba's on-disk cache)


def pair_kernel(size: int):
    """The compiled :func:`_pair_stats_py` when
    ``sandbox.core._kernels.factor_kernel`` gives a kernel for augmented matrices of
    ``size`` rows; else None. The first such call compiles this module's kernels (or loads
    them from numba's cache): :class:`~sandbox.core.likelihood.Scorer` makes it when built."""
    if _kernels.factor_kernel(size) is None:
        return None
    if not _COMPILED:
        compile_with(_kernels.compiler())
        _COMPILED.append(True)
    return _pair_stats


def compile_with(jit) -> None:
    """Replace the kernels by their versions compiled by ``jit`` and load them now."""
    global _group_part, _row_factor, _pair_stats
    _group_part, _row_factor = jit(_group_part_py), jit(_row_factor_py)
    _pair_stats = jit(_pair_stats_py)     # calls the two above by their global names
    ints, yes = np.zeros(1, dtype=np.int64), np.ones((1, 1), dtype=np.bool_)
    _pair_stats(np.ones((1, 1, 1)), np.ones((1, 1)), yes, ints, ints, np.array([0, 1]), ints,
                np.ones(1), np.ones((3, 1)), yes, np.ones((1, 1, 1, 2)), np.zeros((1, 2, 2)),
                np.zeros((1, 2)), np.zeros(1), np.zeros(1))


def _group_part_py(psi, values, rows, dims, kappa: float, G, beta, yy, Li, W, ab, gamma,
                   with_w: bool):
    """One group's part of one candidate (:func:`~sandbox.core.factor.b_part`) from the
    phases ``psi`` (s, N) of the rows observing it: fills G, W (N, N; only ``with_w``),
    ab (N, Pg), gamma (Pg,) and returns log|A|, A = I + kappa G. ``beta``, ``yy``, ``Li``
    are scratch."""
    s, N = psi.shape
    Pg = dims.size
    G[:, :] = 0.0
    beta[:, :] = 0.0
    yy[:] = 0.0
    for j in range(s):
        if rows[j]:
            for a in range(N):
                x = psi[j, a]
                for b in range(a + 1):         # the lower triangle; mirrored below
                    G[a, b] += x * psi[j, b]
                for p in range(Pg):
                    beta[a, p] += x * values[j, dims[p]]
            for p in range(Pg):
                yy[p] += values[j, dims[p]] ** 2
    for a in range(N):     # the same products in the same order as the upper entries' own
        for b in range(a):
            G[b, a] = G[a, b]
    A = kappa * G
    for a in range(N):
        A[a, a] += 1.0
    L = np.linalg.cholesky(A)
    ld = 0.0
    for a in range(N):
        ld += 2.0 * log(L[a, a])
    Li[:, :] = 0.0
    for c in range(N):                     # L^-1 column by column (forward substitution)
        Li[c, c] = 1.0 / L[c, c]
        for a in range(c + 1, N):
            acc = 0.0
            for b in range(c, a):
                acc -= L[a, b] * Li[b, c]
            Li[a, c] = acc / L[a, a]
    if with_w:
        Q = Li @ G
        W[:, :] = G - kappa * (Q.T @ Q)
    Lb = Li @ beta
    ab[:, :] = Li.T @ Lb
    for p in range(Pg):
        acc = 0.0
        for a in range(N):
            acc += Lb[a, p] ** 2
        gamma[p] = yy[p] - kappa * acc
    return ld


def _pair_stats_py(psi, values, present, tasks, dims, starts, modality, kappa, columns,
                   member, blocks, Kt, eps, gamma_term, offset) -> None:
    """The statistics of :meth:`~sandbox.core.likelihood.Scorer._stats` for pairs of one
    duration and one task each, added into ``Kt`` (M, R+1, R+1), ``eps`` (M, R+1),
    ``gamma_term`` and ``offset`` (M,). ``psi`` (M, s, N); group g's columns are
    ``starts[g]:starts[g+1]`` of ``dims`` (human dims), ``member`` (K, cols) and
    ``blocks`` (K, cols, N, R+1); ``present`` (modalities, s); ``columns`` (3, cols):
    each column's :math:`\\sigma_p`, :math:`\\sigma_p^2` and
    :math:`\\log 2\\pi + \\log\\sigma_p^2`. A group seen on fewer rows than N takes
    :math:`\\tilde K` in the rows' space (:func:`_row_factor_py`, module docstring)."""
    M, s, N = psi.shape
    G, Li, W = np.empty((N, N)), np.empty((N, N)), np.empty((N, N))
    for g in range(kappa.size):
        a, b = starts[g], starts[g + 1]
        rows = present[modality[g]]
        count = 0
        for j in range(s):
            count += rows[j]
        if count == 0:
            continue
        beta, ab = np.empty((N, b - a)), np.empty((N, b - a))
        yy, gamma = np.empty(b - a), np.empty(b - a)
        few = count < N
        n = count if few else 0                    # the rows' space only when it is cheaper
        F = np.empty((n, N))
        X = np.empty(((b - a) * n, Kt.shape[1]))
        for m in range(M):
            ld = _group_part(psi[m], values, rows, dims[a:b], kappa[g], G, beta, yy, Li, W,
                             ab, gamma, not few)
            if few:
                _row_factor(psi[m], rows, kappa[g], F)
            k = tasks[m]
            for p in range(b - a):
                V = blocks[k, a + p]                                 # (N, R+1)
                if few:
                    X[p * count:(p + 1) * count] = F @ V
                else:
                    Kt[m] += V.T @ (W @ V)
                e, sp = eps[m], columns[0, a + p]
                for c in range(N):                  # eps[m] += (ab / sigma) V[c], no temporaries
                    x = ab[c, p] / sp
                    for j in range(V.shape[1]):
                        e[j] += x * V[c, j]
                if member[k, a + p]:
                    gamma_term[m] += gamma[p] / columns[1, a + p]
                    offset[m] += count * columns[2, a + p] + ld
            if few:
                Kt[m] += X.T @ X


def _row_factor_py(psi, rows, kappa: float, F) -> None:
    """``F`` (n, N) = :math:`L^{-1}\\Psi_o`: :math:`\\Psi_o` the n rows of ``psi`` (s, N)
    that ``rows`` marks, :math:`LL^T = I + \\kappa\\Psi_o\\Psi_o^T`; so
    :math:`F^TF = \\Psi_o^T(I + \\kappa\\Psi_o\\Psi_o^T)^{-1}\\Psi_o = W` (Woodbury)."""
    s, N = psi.shape
    n = 0
    for j in range(s):
        if rows[j]:
            F[n, :] = psi[j]
            n += 1
    C = kappa * (F @ F.T)
    for i in range(n):
        C[i, i] += 1.0
    L = np.linalg.cholesky(C)
    for i in range(n):                      # forward substitution, row by row
        for j in range(i):
            f = L[i, j]
            for c in range(N):
                F[i, c] -= f * F[j, c]
        d = 1.0 / L[i, i]
        for c in range(N):
            F[i, c] *= d


_group_part = _group_part_py     # replaced by their compiled versions in compile_with
_row_factor = _row_factor_py
_pair_stats = _pair_stats_py

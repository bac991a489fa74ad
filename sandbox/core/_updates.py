"""Optional compiled kernels that keep every pair's augmented factor up to date as the
observations arrive (:mod:`sandbox.core.statistics`), instead of factoring it again at
every update.

Each observed dim p of a row adds :math:`z z^T` to the augmented matrix
:math:`\\begin{bmatrix} K & e \\\\ e^T & d^T B^{-1} d\\end{bmatrix}` of every (candidate,
task) pair (step 3 of :mod:`sandbox.core.likelihood`), with
:math:`z = [x_{kp}, \\; c_p - x_{kp,R}]`: :math:`x_{kp}` the row's share of
:math:`\\tilde K` and :math:`c_p` its share of :math:`y^T B^{-1} y` (the module docstring of
:mod:`sandbox.core.statistics`). So its Cholesky factor follows by one rank-1 update per
dim: Givens rotations of :math:`[U; z^T]`, :math:`U = L^T`, about
:math:`2 (r+1)^2` operations against :math:`(r+1)^3/3` for a factorisation, and no
stored :math:`\\tilde K` to add the rows into first. The factor is the same matrix as the
factorisation's up to round-off (a rotation is backward stable; the last pivot, the
Mahalanobis term, is a sum of squares here, where the factorisation takes it as a
difference). A task of rank r < R leaves its padding rows (the identity) untouched: its
:math:`x` is zero there, so skipping them changes no number. Compiled with numba through
:func:`sandbox.core._kernels.factor_kernel` (the same switch, ``SANDBOX_KERNEL``); the
numpy path keeps the augmented matrices and factors them
(:func:`~sandbox.core.factor.augmented_scores`), ``tests/core/test_kernels.py`` checks
both.
"""

from __future__ import annotations

from math import sqrt

import numpy as np

from sandbox.core import _kernels

_COMPILED: list = []      # [True] once compiled (or loaded from numba's on-disk cache)


def update_kernels(size: int):
    """``(update, loglik)``: the compiled :func:`_update_py` and :func:`_loglik_py` for
    factors of ``size`` rows, or None when :func:`~sandbox.core._kernels.factor_kernel`
    has no kernel for that size (the numpy path)."""
    if _kernels.factor_kernel(size) is None:
        return None
    if not _COMPILED:                     # numba imports: factor_kernel found it
        compile_with(_kernels.compiler())
        _COMPILED.append(True)
    return _update, _loglik


def layout(ranks: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Where task k's factors start in the flat store, shape (K+1,): task k keeps an
    ``(r_k+1, r_k+1, C_k)`` block (its C_k candidates side by side, the last axis)."""
    return np.concatenate([[0], np.cumsum((ranks + 1) ** 2 * counts)]).astype(np.int64)


def compile_with(jit) -> None:
    """Replace the kernels by their versions compiled by ``jit`` and load them now (the
    first update should not pay it): called by :func:`update_kernels` the first time, when
    a stream's statistics are made."""
    global _update, _loglik, _fold, _log_pivots, copy_factors
    _fold = jit(_fold_py)                 # _update_py calls it by its global name
    _log_pivots = jit(_kernels._log_pivots_py)      # and _loglik_py this one
    copy_factors = jit(_copy_factors_py)
    _update, _loglik = jit(_update_py), jit(_loglik_py)
    ints = np.zeros(1, dtype=np.int64)
    store, at = np.array([1.0, 0.0, 0.0, 0.0]), np.array([0, 4])
    _update(store, at, np.ones(1, dtype=np.int64), ints, np.ones(1, dtype=np.int64),
            np.ones((1, 1, 1, 2)), np.ones((1, 1)), np.ones((1, 1)), np.empty(8))
    _loglik(store, at, np.ones(1, dtype=np.int64), np.ones(1, dtype=np.int64),
            np.zeros(1), np.empty(1))
    copy_factors(store, at, np.ones(1, dtype=np.int64), np.ones(1, dtype=np.int64), ints,
                 ints, np.zeros((1, 2, 2)))


def _update_py(store, at, ranks, starts, counts, x, coef, member, scratch) -> None:
    """Every pending row into the factors, in place.

    Parameters
    ----------
    store : ndarray, shape (at[-1],)
        Task k's upper factors :math:`U = L^T` of its pairs' augmented matrices
        (:math:`U^T U`; rows and columns: its r_k directions, then the augmented one) at
        ``store[at[k]:at[k+1]]``, an ``(r_k+1, r_k+1, C_k)`` block (:func:`layout`).
    at : ndarray of int, shape (K+1,)
    ranks, starts, counts : ndarray of int, shape (K,)
        Each task's rank, first candidate and number of candidates (its span).
    x : ndarray, shape (C, K, rows, R+1)
        Each pending dim's :math:`x_{kp}` of every candidate and task (the padded layout).
    coef : ndarray, shape (C, rows)
        Each pending dim's :math:`c_p = \\nu_p / (\\sqrt d\\,\\sigma_p)`.
    member : ndarray, shape (K, rows)
        1.0 where task k's dim is in the row's group (:attr:`Group.member`), else 0.0.
    scratch : ndarray, shape (>= (rows + 1) (R+2) max C_k + 5 max C_k,)
    """
    R = x.shape[3] - 1
    q = x.shape[2]
    for k in range(ranks.size):
        r, C, c0 = ranks[k], counts[k], starts[k]
        n = r + 1
        U = store[at[k]:at[k + 1]].reshape((n, n, C))
        Z = scratch[:q * n * C].reshape((q, n, C))
        for i in range(q):
            for j in range(r):
                for lane in range(C):
                    Z[i, j, lane] = x[c0 + lane, k, i, j]
            for lane in range(C):
                Z[i, r, lane] = member[k, i] * coef[c0 + lane, i] - x[c0 + lane, k, i, R]
        o = q * n * C
        F = scratch[o:o + q * C].reshape((q, C))
        _fold(U, Z, F, scratch[o + q * C:o + q * C + 4 * C].reshape((4, C)))


def _fold_py(U, Z, F, work) -> None:
    """The rows ``Z`` (q, n, C) folded into the factors ``U`` (n, n, C), every lane at
    once, by Householder reflections of :math:`[U; Z]` column by column (a QR update;
    Golub and Van Loan's ``house`` with a positive pivot): one square root per column
    and lane whatever the number of rows, and every inner loop a vector operation across
    the lanes (loops over whole rows from 0: numba's LLVM then vectorises them). A lane
    whose column of ``Z`` is zero is left as it is (no reflection)."""
    n, C = U.shape[0], U.shape[2]
    q = Z.shape[0]
    s, beta, w = work[0], work[1], work[2]
    for a in range(n):
        s[:] = 0.0
        for i in range(q):
            za = Z[i, a]
            for lane in range(C):
                s[lane] += za[lane] * za[lane]
        ua = U[a, a]
        for lane in range(C):
            al, sl = ua[lane], s[lane]
            beta[lane], s[lane] = 0.0, 0.0              # s: 1 / v1 from here
            if sl > 0.0:
                mu = sqrt(al * al + sl)
                v1 = al - mu if al <= 0.0 else -sl / (al + mu)
                beta[lane], s[lane] = 2.0 * v1 * v1 / (sl + v1 * v1), 1.0 / v1
                ua[lane] = mu
        for i in range(q):
            za, f = Z[i, a], F[i]
            for lane in range(C):
                za[lane] *= s[lane]                                     # u = z / v1
                f[lane] = beta[lane] * za[lane]
        for b in range(a + 1, n):
            ub = U[a, b]
            w[:] = ub
            for i in range(q):
                za, zb = Z[i, a], Z[i, b]
                for lane in range(C):
                    w[lane] += za[lane] * zb[lane]
            for lane in range(C):
                ub[lane] -= beta[lane] * w[lane]
            for i in range(q):
                zb, f = Z[i, b], F[i]
                for lane in range(C):
                    zb[lane] -= f[lane] * w[lane]


def _loglik_py(store, at, ranks, counts, offset, loglik) -> None:
    """``loglik[m] = -(offset[m] + log|K| + U_m[r, r]^2) / 2`` (eq. 12) of every packed
    pair m (task after task) from its factor: log|K| from the first r pivots as the log
    of their running product, one ``log`` per factor of 1e100 (pivots of K = I + J are 1
    or more): :func:`~sandbox.core._kernels._log_pivots_py`, the grid's own."""
    m = 0
    for k in range(ranks.size):
        r, C = ranks[k], counts[k]
        U = store[at[k]:at[k + 1]].reshape((r + 1, r + 1, C))
        for lane in range(C):
            ld = _log_pivots(U, lane, r)
            loglik[m] = -0.5 * (offset[m] + 2.0 * ld + U[r, r, lane] ** 2)
            m += 1


def _copy_factors_py(store, at, ranks, counts, tasks, lanes, out) -> None:
    """The kept factors of pairs (``tasks[i]``, candidate ``lanes[i]`` of that task) into
    ``out`` (n, R+1, R+1), padded: the identity on a task's padding rows, its augmented row
    and column at R, zeros elsewhere (``out`` comes zeroed). A copy, entry for entry, of
    the upper triangle only: the store's strictly lower part is zero (:func:`_fold_py`
    writes the upper one; the numpy path's factors are Cholesky's), and each entry read is
    a cache line of its own (the lanes lie side by side), so that halves the reads."""
    R = out.shape[1] - 1
    for i in range(tasks.size):
        k, lane = tasks[i], lanes[i]
        r = ranks[k]
        U = store[at[k]:at[k + 1]].reshape((r + 1, r + 1, counts[k]))
        for a in range(r, R):
            out[i, a, a] = 1.0
        for b in range(r + 1):          # U's upper triangle (zeros below), row by row
            ib = b if b < r else R
            for a in range(b, r + 1):
                out[i, a if a < r else R, ib] = U[b, a, lane]


_update = _update_py         # replaced by their compiled versions in compile_with
_loglik = _loglik_py
copy_factors = _copy_factors_py
_log_pivots = _kernels._log_pivots_py
_fold = _fold_py

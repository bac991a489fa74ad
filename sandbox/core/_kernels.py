"""Optional compiled kernels of the phase stage: :func:`~sandbox.core.factor.factor_scores`,
the refinement's pairs' statistics (:mod:`~sandbox.core.pairstats`), :func:`compiler`.

The likelihood of every (candidate, task) pair ends in one Cholesky factorisation of a
small augmented matrix (step 3 of :mod:`sandbox.core.likelihood`). numpy factors a
batch of them one matrix at a time through LAPACK, whose call overhead and
scalar-bound inner loops leave most of a core unused at these sizes (tens of rows).
When numba is installed (``pip install -e ".[numba]"``) this module compiles a
*batch-interleaved* kernel: blocks of :func:`block_size` matrices are laid side by side
so that every step of the factorisation is a vector operation across the block (each
entry reduced in a small vector of the block's lanes). It builds the augmented matrix,
factors it and sums the log-likelihood in one pass; it writes the factors only when
asked (the phase grid needs those of each task's best pair only).

The kernel computes the same quantities as the numpy path in another order of
floating-point operations: the results agree within 1e-12 (relative), not bit for
bit (``tests/core/test_kernels.py``). It is used automatically when numba imports;
``SANDBOX_KERNEL=numpy`` forces the numpy path, ``SANDBOX_KERNEL=numba`` asks
for the kernel (an ``ImportError`` without numba). It is used only for matrices up
to :data:`MAX_SIZE` rows (above, a block no longer fits the core's cache; at 94 rows,
the rank N x P + 1 of the bench's many-demos case, it factors 1.3x as fast as LAPACK,
measured under load). The core does not import numba at load time, only at the first
factorisation; the compiled code is cached on disk (``cache=True``), so only the
first use after an install pays the compilation (see the speed page of the docs).
"""

from __future__ import annotations

import os
from math import log, sqrt

import numpy as np

#: Environment variable choosing the kernel: "numpy", "numba" or unset (numba if installed).
ENV = "SANDBOX_KERNEL"
#: Matrices interleaved in one block above 32 rows (:func:`block_size`).
BLOCK = 32
#: Largest augmented matrix (rows) the kernel factors; larger ones go to LAPACK.
MAX_SIZE = 96

_COMPILED: list = []      # [kernel or None] once numba has been looked for


def factor_kernel(size: int):
    """The compiled kernel for augmented matrices of ``size`` rows, or None (numpy path).

    None when ``SANDBOX_KERNEL=numpy``, numba is not installed (and not asked for),
    or ``size`` > :data:`MAX_SIZE`. The first call imports numba and loads the compiled
    code (compiles it, the first time after an install): :class:`~sandbox.core.likelihood.Scorer`
    makes that call when it is built, so that an update does not pay it.
    """
    choice = os.environ.get(ENV, "")
    if choice == "numpy" or size > MAX_SIZE:
        return None
    if choice not in ("", "numba"):
        raise ValueError(f"{ENV}: expected 'numpy', 'numba' or unset, got {choice!r}")
    if not _COMPILED:
        _COMPILED.append(_compile())
    if _COMPILED[0] is None and choice == "numba":
        raise ImportError(f"{ENV}=numba: numba is not installed (pip install -e '.[numba]')")
    return _COMPILED[0]


def _compile():
    """The kernel, compiled (or loaded from numba's on-disk cache); None without numba."""
    jit = compiler()
    if jit is None:
        return None
    # _scores calls the helpers by their global names: numba resolves them when compiling.
    globals()["_factor_block"] = jit(_factor_block_py)
    globals()["_active_rows"] = jit(_active_rows_py)
    globals()["_write_factor"] = jit(_write_factor_py)
    globals()["_log_pivots"] = jit(_log_pivots_py)
    globals()["_gather"] = jit(_gather_py)
    globals()["_product"] = jit(_product_py)
    kernel = jit(_scores_py)
    one = np.ones((1, 1, 1))          # load (or compile) the machine code now, not in an update
    kernel(one, np.zeros((1, 1)), np.ones(1), np.zeros(1), np.empty((1, 1, 1)), np.empty(1), 1)
    _product(np.ones((1, 1)), np.ones((1, 1, 1)), np.ones(1), np.ones((1, 1)),
             np.ones((1, 1, 1)), np.ones(1), np.empty((1, 1)), np.empty((1, 1, 1)))
    return kernel


def compiler():
    """numba's ``njit`` as every kernel is compiled (None without numba: the core's import)."""
    try:
        import numba
    except ImportError:
        return None
    return numba.njit(cache=True, nogil=True)


def product_kernel():
    """The compiled :func:`_product_py` (the blend's product of two distributions,
    :mod:`sandbox.core.blending`) when :func:`factor_kernel` has a kernel; else None."""
    return None if factor_kernel(1) is None else _product


def block_size(size: int) -> int:
    """Matrices interleaved in one block for augmented matrices of ``size`` rows: 64 up to
    32 rows, :data:`BLOCK` above (a block of ``size`` x ``size`` x lanes stays within the
    core's level-2 cache). Lanes are independent: the block changes no result."""
    return 64 if size <= 32 else BLOCK


def _factor_block_py(buf: np.ndarray, acc: np.ndarray, n: int, w: int) -> bool:
    """In-place Cholesky of ``buf[:n, :n, :w]`` (buf (>= n, >= n, >= w)): lower triangles,
    the matrices along the last axis; ``acc`` (>= w) is scratch, so that each entry is
    reduced in one small vector rather than in ``buf``. The last pivot is clamped at
    sqrt(1e-300) as the numpy path does (a Mahalanobis term lost to round-off); returns
    False when an earlier one is not positive (or NaN)."""
    for j in range(n):
        for b in range(w):
            acc[b] = buf[j, j, b]
        for k in range(j):
            for b in range(w):
                acc[b] -= buf[j, k, b] * buf[j, k, b]
        for b in range(w):
            d = acc[b]
            if d > 0.0:
                buf[j, j, b] = sqrt(d)
            elif j == n - 1 and d <= 0.0:
                buf[j, j, b] = sqrt(1e-300)
            else:
                return False
        for i in range(j + 1, n):
            for b in range(w):
                acc[b] = buf[i, j, b]
            for k in range(j):
                for b in range(w):
                    acc[b] -= buf[i, k, b] * buf[j, k, b]
            for b in range(w):
                buf[i, j, b] = acc[b] / buf[j, j, b]
    return True


def _active_rows_py(Kt, eps, m: int) -> int:
    """Rows of pair ``m``'s K that are not trailing padding: 1 + the last row j < R with a
    nonzero in ``Kt[m, j]`` or ``eps[m, j]`` (0 if none).

    A trailing row of zeros (a task of rank r < R in the padded layout, or a
    direction no observation has reached) is an identity row of K with a zero in e:
    its factor row is the identity, it adds log 1 = 0 to the log-determinant and
    0 to the Mahalanobis term, and it comes after every other row in the elimination.
    Leaving it out gives the same numbers, bit for bit, at (r+1)^3 instead of (R+1)^3."""
    R = Kt.shape[1] - 1
    for j in range(R - 1, -1, -1):
        if eps[m, j] != 0.0:
            return j + 1
        for k in range(R + 1):
            if Kt[m, j, k] != 0.0:
                return j + 1
    return 0


def _scores_py(Kt, eps, gamma_term, offset, L, loglik, block: int) -> bool:
    """:func:`~sandbox.core.factor.factor_scores` into ``L`` (M, n, n) and ``loglik`` (M,),
    up to ``block`` matrices at a time; False (outputs unfinished) when a block cannot be
    factored: the caller then takes the numpy path, which says why. An ``L`` with no
    matrices (shape (0, n, n)) asks for the log-likelihoods only (the factors are not
    written: the phase grid needs those of a few pairs only). A block holds
    consecutive pairs with the same active rows (:func:`_active_rows`: one task's pairs),
    and factors only those rows and the augmented row, in as many lanes as it has
    pairs; the lanes are independent, so none of this changes a result."""
    M, n, _ = Kt.shape
    buf = np.empty((n, n, min(block, M)))
    acc = np.empty(min(block, M))
    write = L.shape[0] == M
    active = np.empty(M, dtype=np.int64)
    for m in range(M):
        active[m] = _active_rows(Kt, eps, m)
    s = 0
    while s < M:
        r = active[s]
        w = 1
        while w < block and s + w < M and active[s + w] == r:
            w += 1
        _gather(Kt, eps, gamma_term, buf, s, w, r)
        if not _factor_block(buf, acc, r + 1, w):
            return False
        for b in range(w):
            if write:
                _write_factor(buf, b, r, L[s + b])
            ld = _log_pivots(buf, b, r)
            loglik[s + b] = -0.5 * (offset[s + b] + 2.0 * ld + buf[r, r, b] ** 2)
        s += w
    return True


def _gather_py(Kt, eps, gamma_term, buf, s: int, w: int, r: int) -> None:
    """The augmented matrices of pairs ``s .. s+w-1`` (active rows ``r``) into the lanes of
    ``buf``: K = I + J from the lower triangle of ``Kt``, e and d^T B^-1 d in row r. One
    pair after another, so that each pair's statistics are read in order (the grid's
    ``Kt`` is megabytes: read lane by lane, every read of a row was a cache miss)."""
    R = Kt.shape[1] - 1
    for b in range(w):
        K = Kt[s + b]
        for i in range(r):
            for j in range(i + 1):
                buf[i, j, b] = K[i, j]
            buf[i, i, b] += 1.0                                       # K = I + J
        for j in range(r):
            buf[r, j, b] = eps[s + b, j] - K[j, R]                    # e
        buf[r, r, b] = gamma_term[s + b] - 2.0 * eps[s + b, R] + K[R, R]


def _log_pivots_py(buf, b: int, r: int) -> float:
    """:math:`\\sum_{j<r} \\log` ``buf[j, j, b]`` (half of log|K|) as the log of the pivots'
    running product, one ``log`` per factor of 1e100 (pivots of K = I + J are about 1 or
    more): a ``log`` costs some twenty multiplications, and a grid takes r of them per pair.
    Agrees with the sum of logs within a few units of round-off (relative)."""
    ld, prod = 0.0, 1.0
    for j in range(r):
        prod *= buf[j, j, b]
        if prod > 1e100 or prod < 1e-100:
            ld += log(prod)
            prod = 1.0
    return ld + log(prod)


def _write_factor_py(buf, b: int, r: int, out) -> None:
    """Lane ``b`` of a factored block (active rows ``r``) into ``out`` (R+1, R+1), padded:
    the identity on the padding's rows, the augmented row at R."""
    R = out.shape[0] - 1
    for i in range(r):
        for j in range(i + 1):
            out[i, j] = buf[i, j, b]
        for j in range(i + 1, R + 1):
            out[i, j] = 0.0
    for i in range(r, R):
        for j in range(R + 1):
            out[i, j] = 0.0
        out[i, i] = 1.0
    for j in range(r):
        out[R, j] = buf[r, j, b]
    for j in range(r, R):
        out[R, j] = 0.0
    out[R, R] = buf[r, r, b]


def _product_py(m1, S1, a1, m2, S2, a2, mean, cov) -> bool:
    """``blending._product`` knot by knot into ``mean`` (T, Q) and ``cov`` (T, Q, Q): means
    (T, Q), covariances (T, Q, Q), activations (T,) > 0; the same formulas, M = a2 S1 + a1 S2
    solved by LU with partial pivoting. False at an exactly singular M (the numpy path then
    takes its pseudo-inverse)."""
    T, Q = m1.shape
    M, X = np.empty((Q, Q)), np.empty((Q, Q + 2))
    for t in range(T):
        for i in range(Q):
            for j in range(Q):
                M[i, j] = a2[t] * S1[t, i, j] + a1[t] * S2[t, i, j]
                X[i, j] = S1[t, i, j]
            X[i, Q] = m1[t, i]
            X[i, Q + 1] = m2[t, i]
        for c in range(Q):                                 # M X = [S1, m1, m2]
            p = c
            for i in range(c + 1, Q):
                if abs(M[i, c]) > abs(M[p, c]):
                    p = i
            if M[p, c] == 0.0:
                return False
            for j in range(Q):
                M[c, j], M[p, j] = M[p, j], M[c, j]
            for j in range(Q + 2):
                X[c, j], X[p, j] = X[p, j], X[c, j]
            for i in range(c + 1, Q):
                f = M[i, c] / M[c, c]
                for j in range(c + 1, Q):
                    M[i, j] -= f * M[c, j]
                for j in range(Q + 2):
                    X[i, j] -= f * X[c, j]
        for c in range(Q - 1, -1, -1):
            for j in range(Q + 2):
                acc = X[c, j]
                for k in range(c + 1, Q):
                    acc -= M[c, k] * X[k, j]
                X[c, j] = acc / M[c, c]
        for i in range(Q):
            u, v = 0.0, 0.0
            for k in range(Q):
                u += S2[t, i, k] * X[k, Q]
                v += S1[t, i, k] * X[k, Q + 1]
            mean[t, i] = a1[t] * u + a2[t] * v
            for j in range(Q):
                acc = 0.0
                for k in range(Q):
                    acc += S2[t, i, k] * X[k, j]
                cov[t, i, j] = acc
        for i in range(Q):
            for j in range(i + 1):
                x = 0.5 * (cov[t, i, j] + cov[t, j, i])
                cov[t, i, j] = x
                cov[t, j, i] = x
    return True


_product = _product_py
_factor_block = _factor_block_py     # replaced by their compiled versions in _compile
_active_rows = _active_rows_py
_write_factor = _write_factor_py
_log_pivots = _log_pivots_py
_gather = _gather_py

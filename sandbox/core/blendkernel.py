"""An update's blend in one compiled call, when numba is installed (issue 25).

:meth:`Plan.blended <sandbox.core.plan.Plan.blended>` on the numpy path makes some sixty
numpy calls per update on arrays of a few hundred knots of 7 x 7 covariances: it is
bound by the calls, not by its arithmetic (about 0.2 MFLOP). When the new distribution
is a robot weight distribution held after its end (:class:`~sandbox.core.plan.Held`, what
an update blends) and the optional compiled kernels are in use
(``sandbox/core/_kernels.py``: numba installed, ``SANDBOX_KERNEL`` not ``numpy``),
:func:`blend_knots` does it knot by knot in one compiled call: the activations (eq. 18),
the old plan interpolated at the update and the blended knots, the new distribution at
every new knot (eq. 4, computed up to its end and then held), their product at the
knots blended (eq. 16-17) and the new one divided by its activation past them. The
product solves :math:`M = a_2\\Sigma_1 + a_1\\Sigma_2` by its Cholesky factor (it is
positive definite; the numpy path takes LAPACK's LU, and a knot whose M is not positive
definite in floating point sends the blend back to it). The same formulas as the numpy path
in another order of floating-point operations: what it computes before the product agrees
within 1e-12 of the largest entry; the product, as any solve, scales that round-off by
M's condition (1e4-1e5 where the old plan's activation is tiny): the bench's plans agree
within 1e-13 of their largest entry, a synthetic test's within 1e-11
(``tests/core/test_blendkernel.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from math import exp, sqrt
from typing import cast

import numpy as np

from sandbox.core import _kernels
from sandbox.core.blending import blend_pair_into
from sandbox.validation import FloatArray

_COMPILED: list = []      # [kernel or None] once looked for


def knots_kernel():
    """The compiled :func:`_knots_py`, or None on the numpy path (as
    ``sandbox.core._kernels.product_kernel``). The first call loads (or compiles) it:
    a predictor makes that call when it is built, so that no update pays it."""
    if _kernels.product_kernel() is None:
        return None
    if not _COMPILED:
        jit = cast(Callable, _kernels.compiler())     # numba.njit(cache=True, nogil=True)
        # _knots calls the helpers by their global names: numba resolves them when compiling.
        globals()["_interp"] = jit(_interp_py)
        globals()["_held_rows"] = jit(_held_rows_py)
        globals()["_product_knot"] = jit(_product_knot_py)
        kernel = jit(_knots_py)
        one, zero = np.ones(1), np.zeros(1)
        kernel(one, np.ones((1, 1)), np.ones((1, 1, 1)), 0.0, one, 0.0, 1.0, True,
               np.ones((1, 1)), np.ones((1, 1, 1)), one, zero, -1.0, False, 1.0,
               np.empty((2, 1)), np.empty((2, 1, 1)), np.empty(1), np.empty(1),
               np.empty((1, 1)), np.empty((1, 1, 1)), np.empty((1, 1)), np.empty((1, 1, 1)))
        _COMPILED.append(kernel)
    return _COMPILED[0]


def blend_knots(kernel, old: tuple[FloatArray, FloatArray, FloatArray], t: float,
                new_t: FloatArray, held, how, out: tuple[FloatArray, FloatArray]) -> float:
    """The plan's rows from ``t`` (s) on into ``out`` (means (1 + m, Q), covariances
    (1 + m, Q, Q)): row 0 the old plan at ``t``, then the ``m`` new knots ``new_t``
    (increasing, after ``t``) with the new distribution ``held`` (a
    :class:`~sandbox.core.plan.Held`) blended in as ``how`` (a
    :class:`~sandbox.core.plan.Blending`) says; returns the jump (rad) at the first new knot.
    ``kernel`` is :func:`knots_kernel`'s."""
    robot, basis = held.robot, held.basis
    Q, N, m = robot.n_dims, robot.n_basis, new_t.size
    fall, rise = np.empty(m), np.empty(m)
    om, oc = np.empty((m, Q)), np.empty((m, Q, Q))
    nm, nc = np.empty((m, Q)), np.empty((m, Q, Q))
    # writable C-ordered copies of the (read-only) distribution: one compiled signature
    mu, F, reg = (np.array(x, dtype=np.float64, order="C") for x in
                  (robot.mean.reshape(Q, N), robot.factor.reshape(Q, N, -1), robot.reg))
    n, ok = kernel(*(np.ascontiguousarray(x, dtype=np.float64) for x in old), float(t), new_t,
                   float(t + how.delay), float(how.rate), bool(how.blend), mu, F, reg,
                   basis._centers, float(basis._neg_half_h), bool(basis.normalized),
                   float(held.duration), out[0], out[1], fall, rise, om, oc, nm, nc)
    if not ok:             # an M not positive definite in floating point: as the numpy path
        blend_pair_into(om[:n], oc[:n], fall[:n], nm[:n], nc[:n], rise[:n],
                        out[0][1:n + 1], out[1][1:n + 1])                   # eq. 16-17
    if not m:
        return 0.0
    d = out[0][1] - om[0]
    return float(np.sqrt(d.dot(d)))


def _interp_py(pt, pm, pc, x: float, mean, cov, j: int) -> None:
    """The old plan (knots ``pt``, means ``pm``, covariances ``pc``) at ``x`` (s) into row
    ``j`` of ``mean``, ``cov``: :meth:`Plan.interpolate <sandbox.core.plan.Plan.interpolate>`."""
    lo, hi = 0, pt.size                         # searchsorted(pt, x, side="right")
    while lo < hi:
        mid = (lo + hi) // 2
        if x < pt[mid]:
            hi = mid
        else:
            lo = mid + 1
    i = min(max(lo, 1), pt.size - 1)
    span = pt[i] - pt[i - 1]
    w = min(max((x - pt[i - 1]) / span, 0.0), 1.0) if span > 0 else 1.0
    Q = pm.shape[1]
    for a in range(Q):
        mean[j, a] = (1 - w) * pm[i - 1, a] + w * pm[i, a]
        for b in range(Q):
            cov[j, a, b] = (1 - w) * pc[i - 1, a, b] + w * pc[i, a, b]


def _held_rows_py(mu, F, reg, centers, neg_half_h: float, normalized: bool, z, mean,
                  cov) -> None:
    """The robot's distribution at the phases ``z`` (mk,) (eq. 4,
    :func:`~sandbox.core.promp.trajectory_distribution`) into rows ``0 .. mk-1`` of ``mean``
    (., Q) and ``cov`` (., Q, Q): means ``mu`` (Q, N), factor ``F`` (Q, N, r). The basis at
    every phase first, then each dim's factor rows at all of them in one matrix product
    (BLAS: with many demos r is large and this product is most of the blend), laid out by
    column (r, mk) so that the covariances sum every column across the phases at once."""
    Q, N, r = F.shape
    mk = z.size
    psi = np.empty((mk, N))
    sq = np.zeros(mk)
    for j in range(mk):
        top = -np.inf
        for c in range(N):
            d = z[j] - centers[c]
            psi[j, c] = d * d * neg_half_h
            top = max(top, psi[j, c])
        total = 0.0
        for c in range(N):
            psi[j, c] = exp(psi[j, c] - top) if normalized else exp(psi[j, c])
            total += psi[j, c]
        for c in range(N):
            if normalized:
                psi[j, c] /= total
            sq[j] += psi[j, c] * psi[j, c]
        for a in range(Q):
            acc = 0.0
            for c in range(N):
                acc += psi[j, c] * mu[a, c]
            mean[j, a] = acc
    A = np.zeros((Q, r, mk))              # each dim's factor rows at every phase, by column
    if mk and r:
        psi_t = np.ascontiguousarray(psi.T)
        for a in range(Q):
            A[a] = np.dot(F[a].T, psi_t)                          # (r, mk)
    sums = np.empty(mk)
    for a in range(Q):
        for b in range(a + 1):
            sums[:] = 0.0
            Aa, Ab = A[a], A[b]
            for k in range(r):            # across the phases: a vector operation, no chain
                for j in range(mk):
                    sums[j] += Aa[k, j] * Ab[k, j]
            for j in range(mk):
                cov[j, a, b] = sums[j]
                cov[j, b, a] = sums[j]
    for j in range(mk):
        for a in range(Q):
            cov[j, a, a] += reg[a] * sq[j]


def _knots_py(pt, pm, pc, t: float, new_t, center: float, rate: float, blend: bool, mu, F,
              reg, centers, neg_half_h: float, normalized: bool, duration: float,
              out_m, out_c, fall, rise, om, oc, nm, nc) -> tuple[int, bool]:
    """:func:`blend_knots`' loop: activations into ``fall``, ``rise`` (m,); the old plan at
    ``t`` into row 0 of ``out_m``, ``out_c`` and at the knots blended into ``om``, ``oc``;
    the new distribution at every knot into ``nm``, ``nc`` (and, past the blend, divided
    by its activation into rows 1.. of the outputs), and the product of the two at the
    first n knots, those blended (0 without ``blend``), into rows 1..n
    (:func:`_product_knot_py`). Returns ``(n, ok)``: ``ok`` False when a product could not
    be made (the caller then makes them all from the other outputs)."""
    m, Q = new_t.size, mu.shape[0]
    n = 0
    for j in range(m):                                                # eq. 18
        x = min(max(rate * (new_t[j] - center), -700.0), 700.0)
        rise[j] = 1.0 / (1.0 + exp(-x))
        fall[j] = 1.0 - rise[j]
        if fall[j] > 1e-12:
            n += 1
        if rise[j] < 1e-12:
            rise[j] = 0.0
    if not blend:
        n = 0
    _interp(pt, pm, pc, t, out_m, out_c, 0)
    for j in range(max(n, 1) if m else 0):
        _interp(pt, pm, pc, new_t[j], om, oc, j)
    mk = 0                               # knots up to the first past the end: computed
    for j in range(m):
        mk = j + 1
        if min(max(new_t[j] / duration, 0.0), 1.0) >= 1.0:
            break
    z = np.empty(mk)
    for j in range(mk):
        z[j] = min(max(new_t[j] / duration, 0.0), 1.0)
    _held_rows(mu, F, reg, centers, neg_half_h, normalized, z, nm, nc)
    for j in range(m):
        if j >= mk:
            for a in range(Q):                                # held after the end
                nm[j, a] = nm[j - 1, a]
                for b in range(Q):
                    nc[j, a, b] = nc[j - 1, a, b]
        if j >= n:
            for a in range(Q):
                out_m[1 + j, a] = nm[j, a]
                for b in range(Q):
                    out_c[1 + j, a, b] = nc[j, a, b] / rise[j] if blend else nc[j, a, b]
    L, Y, Z = np.empty((Q, Q)), np.empty((Q, Q + 1)), np.empty((Q, Q + 1))
    for j in range(n):                                                # eq. 16-17
        if not _product_knot(om[j], oc[j], fall[j], nm[j], nc[j], rise[j], L, Y, Z,
                             out_m[1 + j], out_c[1 + j]):
            return n, False
    return n, True


def _product_knot_py(m1, S1, a1: float, m2, S2, a2: float, L, Y, Z, mean, cov) -> bool:
    """The product of (m1, S1)^a1 and (m2, S2)^a2 at one knot (activations > 0) into ``mean``
    (Q,), ``cov`` (Q, Q) by the symmetric form of :mod:`sandbox.core.blending` through the
    Cholesky factor of :math:`M = a_2\\Sigma_1 + a_1\\Sigma_2 = LL^T` (positive definite):
    :math:`Y = L^{-1}[\\Sigma_1, \\mu_2]`, :math:`Z = L^{-1}[\\Sigma_2, \\mu_1]`,
    :math:`\\Sigma^* = Z^TY` (its symmetric part) and
    :math:`\\mu^* = a_1 Z^T L^{-1}\\mu_1 + a_2 Y^T L^{-1}\\mu_2`. ``L`` (Q, Q), ``Y`` and
    ``Z`` (Q, Q+1) are scratch. False, the outputs unfinished, when a pivot is not positive."""
    Q = m1.size
    for c in range(Q):
        for r in range(c, Q):
            acc = a2 * S1[r, c] + a1 * S2[r, c]
            for k in range(c):
                acc -= L[r, k] * L[c, k]
            if r == c:
                if not acc > 0.0:
                    return False
                L[c, c] = sqrt(acc)
            else:
                L[r, c] = acc / L[c, c]
    for r in range(Q):                               # forward substitution, every column
        for c in range(Q + 1):
            y = S1[r, c] if c < Q else m2[r]
            z = S2[r, c] if c < Q else m1[r]
            for k in range(r):
                y -= L[r, k] * Y[k, c]
                z -= L[r, k] * Z[k, c]
            Y[r, c] = y / L[r, r]
            Z[r, c] = z / L[r, r]
    for a in range(Q):
        u, v = 0.0, 0.0
        for k in range(Q):
            u += Z[k, a] * Z[k, Q]               # (S2 M^-1 m1)_a
            v += Y[k, a] * Y[k, Q]               # (S1 M^-1 m2)_a
        mean[a] = a1 * u + a2 * v
        for b in range(a + 1):
            acc = 0.0
            for k in range(Q):
                acc += Z[k, a] * Y[k, b] + Y[k, a] * Z[k, b]
            cov[a, b] = cov[b, a] = 0.5 * acc
    return True


_interp = _interp_py
_held_rows = _held_rows_py
_product_knot = _product_knot_py     # replaced by their compiled versions in knots_kernel

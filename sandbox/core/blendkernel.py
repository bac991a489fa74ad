"""An update's blend in one compiled call, when numba is installed (issue 25).

:meth:`Plan.blended <sandbox.core.plan.Plan.blended>` on the numpy path makes some sixty
numpy calls per update on arrays of a few hundred knots of 7 x 7 covariances: it is
bound by the calls, not by its arithmetic (about 0.2 MFLOP). When the new distribution
is a robot weight distribution held after its end (:class:`~sandbox.core.plan.Held`, what
an update blends) and the optional compiled kernels are in use
(``sandbox/core/_kernels.py``: numba installed, ``SANDBOX_KERNEL`` not ``numpy``),
:func:`blend_knots` does it knot by knot in one compiled call: the activations (eq. 18),
the old plan interpolated at the update and the blended knots, the new distribution at
every new knot (eq. 4, computed up to its end and then held), the new one divided by its
activation past the blend; the product of the two (eq. 16-17) is the blend's compiled
kernel (:func:`~sandbox.core.blending.blend_pair_into`). The same formulas as the numpy
path in another order of floating-point operations: the plans agree within 1e-12 of their
largest entry (``tests/core/test_blendkernel.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from math import exp
from typing import cast

import numpy as np

from sandbox.core import _kernels
from sandbox.core.blending import blend_pair_into
from sandbox.validation import FloatArray

_COMPILED: list = []      # [kernel or None] once looked for


def knots_kernel():
    """The compiled :func:`_knots_py`, or None on the numpy path (as
    :func:`~sandbox.core._kernels.product_kernel`). The first call loads (or compiles) it:
    a predictor makes that call when it is built, so that no update pays it."""
    if _kernels.product_kernel() is None:
        return None
    if not _COMPILED:
        jit = cast(Callable, _kernels.njit)       # numba.njit(cache=True, nogil=True)
        # _knots calls the helpers by their global names: numba resolves them when compiling.
        globals()["_interp"] = jit(_interp_py)
        globals()["_held_row"] = jit(_held_row_py)
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
    n = kernel(*(np.ascontiguousarray(x, dtype=np.float64) for x in old), float(t), new_t,
               float(t + how.delay), float(how.rate), bool(how.blend), mu, F, reg,
               basis._centers, float(basis._neg_half_h), bool(basis.normalized),
               float(held.duration), out[0], out[1], fall, rise, om, oc, nm, nc)
    if n:                                                          # eq. 16-17
        blend_pair_into(om[:n], oc[:n], fall[:n], nm[:n], nc[:n], rise[:n],
                        out[0][1:n + 1], out[1][1:n + 1])
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


def _held_row_py(mu, F, reg, centers, neg_half_h: float, normalized: bool, z: float,
                 mean, cov, j: int) -> None:
    """The robot's distribution at phase ``z`` (eq. 4, :func:`~sandbox.core.promp.
    trajectory_distribution`) into row ``j``: means ``mu`` (Q, N), factor ``F`` (Q, N, r)."""
    Q, N, r = F.shape
    psi = np.empty(N)
    top = -np.inf
    for c in range(N):
        d = z - centers[c]
        psi[c] = d * d * neg_half_h
        top = max(top, psi[c])
    total, sq = 0.0, 0.0
    for c in range(N):
        psi[c] = exp(psi[c] - top) if normalized else exp(psi[c])
        total += psi[c]
    for c in range(N):
        if normalized:
            psi[c] /= total
        sq += psi[c] * psi[c]
    A = np.zeros((Q, r))
    for a in range(Q):
        acc = 0.0
        for c in range(N):
            acc += psi[c] * mu[a, c]
            for k in range(r):
                A[a, k] += psi[c] * F[a, c, k]
        mean[j, a] = acc
    for a in range(Q):
        for b in range(a + 1):
            acc = 0.0
            for k in range(r):
                acc += A[a, k] * A[b, k]
            cov[j, a, b] = acc
            cov[j, b, a] = acc
        cov[j, a, a] += reg[a] * sq


def _knots_py(pt, pm, pc, t: float, new_t, center: float, rate: float, blend: bool, mu, F,
              reg, centers, neg_half_h: float, normalized: bool, duration: float,
              out_m, out_c, fall, rise, om, oc, nm, nc) -> int:
    """:func:`blend_knots`' loop: activations into ``fall``, ``rise`` (m,); the old plan at
    ``t`` into row 0 of ``out_m``, ``out_c`` and at the knots blended into ``om``, ``oc``;
    the new distribution at every knot into ``nm``, ``nc`` (and, past the blend, divided
    by its activation into rows 1.. of the outputs). Returns the knots blended, n (0
    without ``blend``): their product is the caller's."""
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
    for j in range(m):
        z = min(max(new_t[j] / duration, 0.0), 1.0)
        if j and z >= 1.0 and min(max(new_t[j - 1] / duration, 0.0), 1.0) >= 1.0:
            for a in range(Q):                                # held after the end
                nm[j, a] = nm[j - 1, a]
                for b in range(Q):
                    nc[j, a, b] = nc[j - 1, a, b]
        else:
            _held_row(mu, F, reg, centers, neg_half_h, normalized, z, nm, nc, j)
        if j >= n:
            for a in range(Q):
                out_m[1 + j, a] = nm[j, a]
                for b in range(Q):
                    out_c[1 + j, a, b] = nc[j, a, b] / rise[j] if blend else nc[j, a, b]
    return n


_interp = _interp_py
_held_row = _held_row_py      # replaced by their compiled versions in knots_kernel

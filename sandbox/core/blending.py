"""Blending of trajectory distributions: product of Gaussians with activations (eq. 16-18).

Per time step t, distributions :math:`\\mathcal{N}(\\mu_i, \\Sigma_i)` with
activations :math:`a_i \\in [0, 1]` combine into

.. math::  \\Sigma^* = \\Big(\\sum_i (\\Sigma_i / a_i)^{-1}\\Big)^{-1}, \\qquad
           \\mu^* = \\Sigma^* \\sum_i (\\Sigma_i / a_i)^{-1} \\mu_i .

The product is folded pairwise with the symmetric form
:math:`\\Sigma^* = \\Sigma_2 M^{-1} \\Sigma_1`,
:math:`\\mu^* = a_1\\Sigma_2 M^{-1}\\mu_1 + a_2\\Sigma_1 M^{-1}\\mu_2`,
:math:`M = a_2\\Sigma_1 + a_1\\Sigma_2`, which needs no inverse of any
:math:`\\Sigma_i`, handles :math:`a_i = 0` exactly (that distribution drops
out) and returns :math:`(\\mu_1, \\Sigma_1)` for activations (1, 0). Where
:math:`M` is numerically singular (tasks whose means differ by many orders of
magnitude more than their spread), its pseudo-inverse stands in for the inverse.
"""

from __future__ import annotations

import numpy as np

from sandbox.core import _kernels
from sandbox.validation import FloatArray, check_array


def sigmoid_activations(times: FloatArray, center: float, rate: float
                        ) -> tuple[FloatArray, FloatArray]:
    """Falling and rising sigmoids (eq. 18) centred at ``center`` (s) with gradient ``rate`` (1/s).

    Returns
    -------
    fall, rise : ndarray, shape (T,)
        ``fall + rise == 1``.
    """
    x = np.clip(rate * (np.asarray(times, dtype=np.float64) - center), -700.0, 700.0)
    rise = 1.0 / (1.0 + np.exp(-x))                          # eq. 18
    return 1.0 - rise, rise


def blend(means: FloatArray, covs: FloatArray, activations: FloatArray
          ) -> tuple[FloatArray, FloatArray]:
    """Product of k Gaussian trajectory distributions with per-step activations.

    Parameters
    ----------
    means : array_like, shape (k, T, Q)
    covs : array_like, shape (k, T, Q, Q)
        Symmetric positive definite.
    activations : array_like, shape (k, T)
        In [0, 1]; at every step at least one is positive.

    Returns
    -------
    mean : ndarray, shape (T, Q)
    cov : ndarray, shape (T, Q, Q)
    """
    means = check_array(means, "means", 3)
    k, T, Q = means.shape
    covs = check_array(covs, "covs", 4, shape=(k, T, Q, Q))
    act = check_array(activations, "activations", 2, shape=(k, T))
    if np.any(act < 0) or np.any(act > 1):
        raise ValueError("activations: expected values in [0, 1]")
    if np.any(act.sum(axis=0) <= 0):
        raise ValueError("activations: expected at least one positive activation per time step")
    return blend_unchecked(means, covs, act)


def blend_unchecked(means, covs, act):
    """:func:`blend` without validation (for the predictor's hot path)."""
    mean, cov, a_acc = means[0].copy(), covs[0].copy(), act[0].copy()
    for i in range(1, means.shape[0]):
        mean, cov, a_acc = _pair(mean, cov, a_acc, means[i], covs[i], act[i])   # eq. 16
    if np.any(a_acc != 1.0):  # a lone active distribution: N(mu, Sigma)^a ~ N(mu, Sigma / a)
        cov = cov / a_acc[:, None, None]
    return mean, cov


def blend_pair(m1, S1, a1, m2, S2, a2):
    """:func:`blend_unchecked` of two distributions given apart (no stacking, no copies):
    means (T, Q), covariances (T, Q, Q), activations (T,) each; the same numbers."""
    if np.all(a1 > 0) and np.all(a2 > 0):         # the usual case: activation 1 after
        return _product(m1, S1, a1, m2, S2, a2)                            # eq. 16
    mean, cov, a_acc = _pair(m1, S1, a1, m2, S2, a2)
    if np.any(a_acc != 1.0):
        cov = cov / a_acc[:, None, None]
    return mean, cov


def blend_pair_into(m1, S1, a1, m2, S2, a2, mean, cov) -> None:
    """:func:`blend_pair` written into ``mean`` (T, Q) and ``cov`` (T, Q, Q) (C-contiguous,
    e.g. a range of knots of the plan being built): the same numbers, no intermediate arrays."""
    if not a1.size:
        return
    if a1.min() > 0 and a2.min() > 0:             # the usual case (as blend_pair)
        kernel = _kernels.product_kernel()
        if kernel is not None and kernel(*[np.ascontiguousarray(x, dtype=np.float64)
                                           for x in (m1, S1, a1, m2, S2, a2)], mean, cov):
            return
    mean[...], cov[...] = blend_pair(m1, S1, a1, m2, S2, a2)


def _pair(m1, S1, a1, m2, S2, a2):
    """Product of (m1, S1)^a1 and (m2, S2)^a2 per step; result has activation 1 (or a1/a2)."""
    both = (a1 > 0) & (a2 > 0)
    if both.all():                                   # the usual case: no masking needed
        mean, cov = _product(m1, S1, a1, m2, S2, a2)
        return mean, cov, np.ones_like(a1)
    only2 = (a1 <= 0) & (a2 > 0)
    mean, cov = m1.copy(), S1.copy()
    act = np.where(a1 > 0, a1, a2)
    if only2.any():
        mean[only2], cov[only2] = m2[only2], S2[only2]
    if both.any():
        mean[both], cov[both] = _product(m1[both], S1[both], a1[both], m2[both], S2[both],
                                         a2[both])
        act[both] = 1.0
    return mean, cov, act


def _product(m1, S1, a1, m2, S2, a2):
    """Symmetric form of the product for activations > 0 (module docstring); knot by knot
    in numba's compiled kernel when it is installed (``sandbox/core/_kernels.py``)."""
    kernel = _kernels.product_kernel()
    if kernel is not None and m1.shape[0]:
        mean, cov = np.empty(m1.shape), np.empty(S1.shape)
        if kernel(*[np.ascontiguousarray(x, dtype=np.float64) for x in (m1, S1, a1, m2, S2, a2)],
                  mean, cov):
            return mean, cov                     # else a singular M: the pseudo-inverse below
    b1, b2 = a1[:, None, None], a2[:, None, None]
    M = b2 * S1 + b1 * S2
    rhs = np.concatenate([S1, m1[..., None], m2[..., None]], axis=2)
    try:
        sol = np.linalg.solve(M, rhs)
    except np.linalg.LinAlgError:
        # M numerically singular (module docstring): pseudo-inverse, not no command.
        sol = np.linalg.pinv(M, hermitian=True) @ rhs
    new_cov = S2 @ sol[..., :-2]                                           # eq. 17
    new_mean = (b1 * (S2 @ sol[..., -2:-1]) + b2 * (S1 @ sol[..., -1:]))[..., 0]  # eq. 17
    return new_mean, 0.5 * (new_cov + new_cov.transpose(0, 2, 1))

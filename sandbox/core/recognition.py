"""Task recognition: posterior over k task models (paper eq. 14-15).

.. math::  p(k | y) \\propto p(y | \\theta_k, \\alpha^*_k)\\, p(k)

computed in log space and normalised with log-sum-exp (log-likelihoods of a
few dozen observations differ by thousands of nats).
"""

from __future__ import annotations

import numpy as np

from sandbox.validation import FloatArray, check_array


def task_posterior(log_likelihood: FloatArray, priors: FloatArray) -> FloatArray:
    """Normalised posterior over tasks.

    Parameters
    ----------
    log_likelihood : array_like, shape (K,)
        :math:`\\log p(y | \\theta_k, \\alpha^*_k)` per task.
    priors : array_like, shape (K,)
        p(k), non-negative (zero excludes a task).

    Returns
    -------
    posterior : ndarray, shape (K,)
        Sums to one.
    """
    ll = check_array(log_likelihood, "log_likelihood", 1, allow_nan=False)
    p = check_array(priors, "priors", 1, shape=(ll.size,))
    if np.any(p < 0) or p.sum() <= 0:
        raise ValueError(f"priors: expected non-negative values with a positive sum, got {p}")
    return posterior_unchecked(ll, p)


def posterior_unchecked(log_likelihood: FloatArray, priors: FloatArray) -> FloatArray:
    """:func:`task_posterior` of float arrays already checked (the update's inner loop)."""
    with np.errstate(divide="ignore"):
        score = log_likelihood + np.log(priors)   # eq. 14 (ll: eq. 15 at the MAP speed)
    weights = np.exp(score - score.max())
    return weights / weights.sum()

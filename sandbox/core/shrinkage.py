"""Each task's weight covariance shrunk toward the tasks' pooled one (regularised discriminant).

A task's covariance is estimated from its own demos: with ``n`` demos in
``D*N`` weight dims it has rank ``n - 1`` (19 for 20 demos in 210 dims), and the
regulariser gives every other direction a tiny variance. Two tasks whose
demos share a motion (the diverging family's common first half) then differ
in *which* directions they allow, by chance of their samples, and a new motion
of that shared part is scored very differently by them: the task posterior
leaves the prior on motion that says nothing about the task (issue 27).

The remedy is Friedman's regularised discriminant analysis (1989): each task's
covariance becomes

.. math::  \\Sigma_k(\\lambda_k) = (1 - \\lambda_k)\\, S_k + \\lambda_k\\, S_{pool},
           \\qquad S_{pool} = \\frac{1}{n - K} \\sum_k \\sum_{i \\in k}
           (w_i - \\bar w_k)(w_i - \\bar w_k)^T,

with :math:`\\lambda_k` the intensity of Schäfer and Strimmer (2005, eq. 6 with
an arbitrary target, their "target D"), computed on the coordinates
standardised by the pooled variances so that it does not depend on units:

.. math::  \\lambda_k = \\frac{\\sum_{jl} \\widehat{\\mathrm{Var}}(s_{jl})}
           {\\sum_{jl} (s_{jl} - t_{jl})^2},\\qquad
           \\widehat{\\mathrm{Var}}(s_{jl}) = \\frac{n_k}{(n_k - 1)^3}
           \\sum_i (z_{ij} z_{il} - \\bar{(zz)}_{jl})^2,

clipped to [0, 1]: the share of the task's own covariance that its demos
cannot tell from sampling noise. Where the tasks' spreads really differ (many
demos, distinct motions) :math:`\\lambda_k` is small and the task keeps its own;
where they do not, the task takes the pooled one. Everything is learned from
the training demos; nothing is read off one data set.

Both terms stay factors (:math:`[\\sqrt{1-\\lambda} U_k, \\sqrt{\\lambda} U_{pool}]`),
so the shrunk covariance keeps the :class:`~sandbox.core.promp.WeightDistribution`
form; its rank is up to :math:`n - K`. Sums over :math:`jl` are taken through
``n x n`` Gram matrices, never the ``D*N x D*N`` matrices.

**One intensity per task.** An intensity per stretch of the motion (per basis
function) mixes by congruence, :math:`A S_k A + B S_{pool} B`, which weakens the
covariance *between* stretches whose intensities differ, the very coupling by
which an early hand predicts the late robot; measured on the recorded set it made
the prediction worse (dynamic e_p 0.050 m against 0.046 m). Shrinking the task
means too (empirical Bayes per coordinate) helped the diverging family's prefix a
little and hurt the recorded set's recognition; it is not done.

**Cost.** The rank grows from ``n_k - 1`` to up to ``n - K``, so an update costs
more (about 2x with the hand alone, where the likelihood works in the human
block's rank; much more with many observed dims). Hence opt-in
(``IProMP(shrinkage="auto")``); the measured trade-off is in the docs' method page.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from sandbox.core.promp import WeightDistribution, thin
from sandbox.validation import FloatArray, check_choice

#: Choices of ``IProMP(shrinkage=...)``: the learned intensity, none (each task its own), or
#: the learned intensity for the robot's conditioning only (eq. 8; the task posterior and the
#: speeds keep each task's own covariance).
SHRINKAGE = ("auto", "none", "robot")


def check_shrinkage(value) -> str:
    """``value`` if it is one of :data:`SHRINKAGE`, else a ``ValueError`` naming them."""
    return check_choice(value, "shrinkage", SHRINKAGE)


def pooled_factor(weights: Mapping[str, FloatArray]) -> FloatArray:
    """Factor (D*N, r) of the pooled within-task covariance :math:`S_{pool}`.

    Parameters
    ----------
    weights : mapping of str to ndarray, shape (n_k, D*N)
        Each task's demo weights; together more demos than tasks.

    Returns
    -------
    ndarray, shape (D*N, r)
        :math:`U` with :math:`UU^T = S_{pool}`, r <= n - K.
    """
    blocks = [np.asarray(w, dtype=np.float64) for w in weights.values()]
    dof = sum(b.shape[0] for b in blocks) - len(blocks)
    if dof < 1:
        raise ValueError(f"weights: expected more demos than tasks to pool a covariance, got "
                         f"{sum(b.shape[0] for b in blocks)} demos of {len(blocks)} tasks")
    centred = np.hstack([(b - b.mean(axis=0)).T for b in blocks])
    return thin(centred / np.sqrt(dof))


def intensity(weights: FloatArray, pooled: FloatArray) -> float:
    """Schäfer-Strimmer intensity :math:`\\lambda_k` in [0, 1] of one task toward ``pooled``.

    Parameters
    ----------
    weights : ndarray, shape (n_k, D*N)
        The task's demo weights (n_k >= 2; with fewer there is nothing to shrink: 1).
    pooled : ndarray, shape (D*N, r)
        :func:`pooled_factor`.

    Returns
    -------
    float
    """
    w = np.asarray(weights, dtype=np.float64)
    n = w.shape[0]
    if n < 2:
        return 1.0
    var = (pooled**2).sum(axis=1)
    scale = 1.0 / np.sqrt(np.maximum(var, max(var.max(), 1e-300) * 1e-12))
    z = (w - w.mean(axis=0)) * scale                       # standardised, centred (n, D*N)
    gram = z @ z.T
    noise = n / (n - 1) ** 3 * (np.sum(np.diag(gram) ** 2) - np.sum(gram**2) / n)
    a = z.T / np.sqrt(n - 1)                               # S = A A^T
    b = pooled * scale[:, None]                            # T = B B^T
    gap = (np.sum((a.T @ a) ** 2) + np.sum((b.T @ b) ** 2) - 2.0 * np.sum((a.T @ b) ** 2))
    if gap <= 0.0:
        return 1.0
    return float(np.clip(noise / gap, 0.0, 1.0))


def shrink(dist: WeightDistribution, pooled: FloatArray, lam: float) -> WeightDistribution:
    """``dist`` with the covariance :math:`(1 - \\lambda) S_k + \\lambda S_{pool}` (same mean
    and regulariser); ``lam = 0`` leaves it as it is.

    Parameters
    ----------
    dist : WeightDistribution
    pooled : ndarray, shape (D*N, r)
        :func:`pooled_factor`.
    lam : float
        In [0, 1].
    """
    if lam <= 0.0:
        return dist
    factor = thin(np.hstack([np.sqrt(1.0 - lam) * dist.factor, np.sqrt(lam) * pooled]))
    return WeightDistribution(dist.mean, factor, dist.reg, dist.n_basis)


def shrunk(weights: Mapping[str, FloatArray], dists: Mapping[str, WeightDistribution],
           shrinkage: str) -> tuple[dict[str, WeightDistribution], dict[str, float]]:
    """``dists`` shrunk toward the pooled covariance (``"auto"`` or ``"robot"``), or as they
    are (``"none"``, or a single task), and each task's intensity."""
    if shrinkage == "none" or len(weights) < 2:
        return dict(dists), {k: 0.0 for k in dists}
    pooled = pooled_factor(weights)
    lams = {k: intensity(w, pooled) for k, w in weights.items()}
    return {k: shrink(d, pooled, lams[k]) for k, d in dists.items()}, lams

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
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from sandbox.core.promp import WeightDistribution, thin
from sandbox.validation import FloatArray, check_choice

#: Bases on each side of a basis function in the band its intensity is measured on: five
#: bases, a quarter of the motion with the default 21.
BAND = 2
#: Choices of ``IProMP(shrinkage=...)``: the learned intensity, or none (each task its own).
SHRINKAGE = ("auto", "none")


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


def intensities(weights: FloatArray, pooled: FloatArray, n_basis: int,
                half_width: int = BAND) -> FloatArray:
    """Per-coordinate intensities (D*N,): :func:`intensity` of each basis function's band.

    The intensity of basis function n is that of the coordinates of bases
    ``n - half_width`` to ``n + half_width`` of every dim (a stretch of the motion),
    and applies to basis n of every dim.

    Parameters
    ----------
    weights : ndarray, shape (n_k, D*N)
        The task's demo weights, dim-major (index ``d * N + n``).
    pooled : ndarray, shape (D*N, r)
        :func:`pooled_factor`.
    n_basis : int
        N.
    half_width : int
        Bases on each side of n in its band (default :data:`BAND`).

    Returns
    -------
    ndarray, shape (D*N,)
        In [0, 1], the same for every dim of one basis function.
    """
    w = np.asarray(weights, dtype=np.float64)
    dims = np.arange(w.shape[1] // n_basis)[:, None] * n_basis
    lam = np.empty(n_basis)
    for n in range(n_basis):
        cols = (dims + np.arange(max(0, n - half_width), min(n_basis, n + half_width + 1))).ravel()
        lam[n] = intensity(w[:, cols], pooled[cols])
    return np.tile(lam, dims.size)


def shrunk_means(weights: Mapping[str, FloatArray], pooled: FloatArray) -> dict[str, FloatArray]:
    """Each task's mean weights (D*N,) shrunk toward the tasks' average, coordinate by coordinate.

    The empirical-Bayes estimate of a normal means model (Efron and Morris 1975):
    :math:`\\bar w_{kj}` is task k's mean of coordinate j, :math:`m_j` their
    average, :math:`b_j = \\sum_k (\\bar w_{kj} - m_j)^2 / (K - 1)` their spread and
    :math:`v_j = S_{pool,jj}\\, \\overline{1/n_k}` the part of it sampling explains;

    .. math::  \\hat\\mu_{kj} = m_j + \\max(0, 1 - v_j / b_j)\\,(\\bar w_{kj} - m_j).

    Coordinates where the tasks' means differ by no more than sampling noise (the
    stretch of motion they share) take the common mean; where they differ, each keeps its own.
    """
    means = {k: np.asarray(w, dtype=np.float64).mean(axis=0) for k, w in weights.items()}
    if len(means) < 2:
        return means
    stacked = np.array(list(means.values()))
    centre = stacked.mean(axis=0)
    spread = ((stacked - centre) ** 2).sum(axis=0) / (len(means) - 1)
    noise = (pooled**2).sum(axis=1) * np.mean([1.0 / len(w) for w in weights.values()])
    keep = np.clip(1.0 - noise / np.maximum(spread, 1e-300), 0.0, 1.0)
    return {k: centre + keep * (m - centre) for k, m in means.items()}


def shrink(dist: WeightDistribution, pooled: FloatArray, lam,
           mean: FloatArray | None = None) -> WeightDistribution:
    """``dist`` with the covariance :math:`A S_k A + B S_{pool} B`, A, B diagonal.

    :math:`A = \\mathrm{diag}(\\sqrt{1 - \\lambda})`, :math:`B = \\mathrm{diag}(\\sqrt{\\lambda})`:
    positive semi-definite for any ``lam`` in [0, 1], :math:`(1 - \\lambda_j) s_{jj} +
    \\lambda_j t_{jj}` on the diagonal, and the scalar mixture when ``lam`` is one
    number. The regulariser is kept, and the mean unless ``mean`` is given.

    Parameters
    ----------
    dist : WeightDistribution
    pooled : ndarray, shape (D*N, r)
    lam : float or ndarray, shape (D*N,)
    mean : ndarray, shape (D*N,), optional
        A new mean (:func:`shrunk_means`).
    """
    lam = np.broadcast_to(np.asarray(lam, dtype=np.float64), dist.mean.shape)
    mean = dist.mean if mean is None else mean
    if not np.any(lam > 0.0):
        return WeightDistribution(mean, dist.factor, dist.reg, dist.n_basis)
    factor = thin(np.hstack([np.sqrt(1.0 - lam)[:, None] * dist.factor,
                             np.sqrt(lam)[:, None] * pooled]))
    return WeightDistribution(mean, factor, dist.reg, dist.n_basis)

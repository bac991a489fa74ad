"""A hand that has not started: the rest hypothesis beside the task models.

The task models (eq. 14-15) all assume a motion that starts at t = 0. A human
who holds still at the common start (before reaching, in teleop, or waiting for
the robot) is explained by none of them; each task then scores the rest as its
slowest motion, and the task posterior locks on whichever task's slowest speed
fits best (p = 1.00 after a second of a motionless hand), although the rest says
nothing about which task will follow.

So every update also weighs one more hypothesis, *rest*: every observed dim is a
constant :math:`r_j` plus the model's observation noise,

.. math::  y_{ij} = r_j + \\epsilon_{ij},\\quad
           r_j \\sim \\mathcal{N}(m_j, v_j),\\quad \\epsilon_{ij} \\sim \\mathcal{N}(0, \\sigma^2_j)

with :math:`(m_j, v_j)` the tasks' start (the prior mixture of the human's
weights at phase 0, moment-matched) and :math:`\\sigma^2_j` the noise the task
likelihood uses. Its evidence is closed form (rank-one covariance
:math:`\\sigma^2_j I + v_j 11^T`, Sherman-Morrison). With even prior odds,

.. math::  p(\\text{motion} | y) = \\frac{\\sum_k p(k) p(y | k)}
           {\\sum_k p(k) p(y | k) + p(y | \\text{rest})}

and the task posterior reported is
:math:`p(k | y) = p(\\text{motion} | y)\\, p(k | y, \\text{motion}) + p(\\text{rest} | y)\\, p(k)`:
the rest is no evidence about the task, so it leaves the prior. Once the hand
moves by a few noise widths the rest's evidence collapses (it is one constant
for the whole window) and the posterior is the task models' alone. The chosen
task is unchanged wherever the prior is uniform (ties are broken by the task
models' posterior).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.interaction import LOG_2PI
from sandbox.core.promp import trajectory_distribution
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

#: Prior probability that the hand has not started (even odds with a motion).
REST_PRIOR = 0.5


def start_distribution(model: IProMP) -> tuple[FloatArray, FloatArray]:
    """Mean (P,) and variance (P,) of the human dims at phase 0, over the task prior.

    The prior mixture of every task's human weights at z = 0 (eq. 4), moment-matched
    per dim (normalised units, as the observations the predictors keep).
    """
    P, p = model.n_human, model.priors
    starts = [trajectory_distribution(task.weights.dims(slice(0, P)), model.basis, np.zeros(1))
              for task in model.task_models]
    means = np.array([m[0] for m, _ in starts])                   # (K, P)
    variances = np.array([np.diagonal(c[0]) for _, c in starts])  # (K, P)
    mean = p @ means
    var = p @ (variances + (means - mean) ** 2)
    return mean, np.maximum(var, 1e-12)


def rest_log_likelihood(values: FloatArray, sigma2: FloatArray, mean: FloatArray,
                        var: FloatArray, *, joint: bool = True) -> float:
    """:math:`\\log p(y | \\text{rest})` of observations (module docstring).

    Parameters
    ----------
    values : ndarray, shape (s, P)
        Observations (normalised units), NaN where a dim is not observed.
    sigma2 : ndarray, shape (P,)
        Observation noise variance per dim (the task likelihood's).
    mean, var : ndarray, shape (P,)
        The rest position's prior (:func:`start_distribution`).
    joint : bool
        The joint density of all observations (one constant per dim), or the
        product of each observation's marginal (as the ``"marginal"`` likelihood).

    Returns
    -------
    float
        The log density (nats); 0 for no finite value.
    """
    y = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(y)
    d = np.where(ok, y - mean, 0.0)
    n = ok.sum(axis=0).astype(np.float64)                     # (P,)
    if not joint:
        total = var + sigma2
        return float(-0.5 * np.sum(n * (LOG_2PI + np.log(total)) + (d**2).sum(axis=0) / total))
    big = sigma2 + n * var                                    # sigma^2 + n v
    quad = ((d**2).sum(axis=0) - var * d.sum(axis=0) ** 2 / big) / sigma2
    logdet = np.where(n > 0, (n - 1) * np.log(sigma2) + np.log(big), 0.0)
    return float(-0.5 * np.sum(n * LOG_2PI + logdet + quad))


def motion_probability(log_likelihood: FloatArray, priors: FloatArray, rest: float) -> float:
    """:math:`p(\\text{motion} | y)` against the rest hypothesis, with even prior odds.

    ``log_likelihood`` (K,) are the task models' (eq. 15), ``rest`` is
    :func:`rest_log_likelihood`.
    """
    p = np.asarray(priors, dtype=np.float64)
    with np.errstate(divide="ignore"):
        score = np.asarray(log_likelihood, dtype=np.float64) + np.log(p)
    top = score.max()
    motion = top + np.log(np.exp(score - top).sum()) + np.log1p(-REST_PRIOR)
    still = rest + np.log(REST_PRIOR)
    return float(1.0 / (1.0 + np.exp(np.clip(still - motion, -700.0, 700.0))))


def with_rest(posterior: FloatArray, priors: FloatArray, p_motion: float) -> FloatArray:
    """The task posterior with the rest hypothesis.

    ``p_motion * posterior + (1 - p_motion) * priors``, shape (K,).
    """
    return p_motion * np.asarray(posterior) + (1.0 - p_motion) * np.asarray(priors)


def chosen_task(mixed: FloatArray, posterior: FloatArray) -> int:
    """The most probable task of ``mixed``; exact ties go to the task models' ``posterior``."""
    best = np.flatnonzero(mixed == mixed.max())
    return int(best[np.argmax(np.asarray(posterior)[best])])

"""Statistics of the familiarity calibration: ranking a value in a cell, combining ranks,
and the split-conformal threshold (:mod:`sandbox.core.calibration` has the derivations).

Pure functions of arrays (no model), tested on i.i.d. draws (``tests/core/test_calibration.py``).
"""

from __future__ import annotations

import numpy as np

from sandbox.validation import FloatArray, check_fraction

#: Quantile levels stored per time bin.
LEVELS = np.linspace(0.0, 1.0, 41)
#: Level above which a rank follows a fitted tail instead of the quantiles.
TAIL_LEVEL = 0.95
#: Smallest tail scale (log-statistic per e-fold of the rank).
MIN_TAIL = 1e-3
TINY = 1e-300


def rank(quantiles: FloatArray, value: float, min_tail: float = MIN_TAIL) -> float:
    """Share in (0, 1] of a cell's calibration updates with a statistic above ``value``.

    ``quantiles`` (L,) at :data:`LEVELS`: interpolated on the log of the
    statistic up to level :data:`TAIL_LEVEL`; beyond it a power-law tail
    through the quantiles at levels 0.75 and ``TAIL_LEVEL`` (so a motion far
    worse than any calibration one still gets a graded, positive score). A
    value at or below the smallest quantile (e.g. a tie at 0) ranks 1.
    ``min_tail``: smallest tail scale (log-statistic per e-fold of the rank).
    """
    u = np.log(max(value, TINY))
    lq = np.log(np.maximum(quantiles, TINY))
    if u <= lq[0]:
        return 1.0
    top = int(np.searchsorted(LEVELS, TAIL_LEVEL))
    if u <= lq[top]:
        return float(1.0 - np.interp(u, lq[: top + 1], LEVELS[: top + 1]))
    mid = int(np.searchsorted(LEVELS, 0.75))
    decades = np.log((1.0 - LEVELS[mid]) / (1.0 - LEVELS[top]))
    beta = max((lq[top] - lq[mid]) / decades, min_tail)   # log-stat per e-fold of p
    return float(max((1.0 - LEVELS[top]) * np.exp(-(u - lq[top]) / beta), TINY))


def fisher(ranks: FloatArray) -> float:
    """Fisher's combination :math:`P(\\chi^2_{2J} \\ge -2\\sum_j \\log p_j)` of J ranks in (0, 1]
    (module docstring; the even-degree survival function in closed form)."""
    half = -np.sum(np.log(np.maximum(ranks, TINY)))          # X / 2
    terms = np.cumprod(np.r_[1.0, np.full(ranks.size - 1, half)] /
                       np.r_[1.0, np.arange(1, ranks.size)])  # (X/2)^i / i!
    return float(min(1.0, np.exp(-half) * terms.sum()))


def conformal_threshold(lowest: FloatArray, alpha: float) -> float:
    """The split-conformal threshold of per-motion lowest familiarities (module docstring).

    At rank :math:`r = \\alpha (n + 1)` among the sorted values: the
    :math:`\\lfloor r \\rfloor`-th, moved towards the next one geometrically by
    the fraction of :math:`r` (so the rate lies between
    :math:`\\lfloor r \\rfloor / (n + 1)` and :math:`\\lceil r \\rceil / (n + 1)`,
    and is :math:`\\alpha` when the values are locally log-uniform); below the
    first, :math:`r \\ell_{(1)}`. (``np.quantile(lowest, alpha)`` sits at rank
    :math:`1 + \\alpha (n - 1)`: about one motion in :math:`n + 1` more than
    ``alpha`` of new motions fire.)

    Parameters
    ----------
    lowest : array_like, shape (n,)
        Each calibration motion's lowest familiarity (non-finite ones are left out).
    alpha : float
        Share of new motions to fall below the threshold.

    Returns
    -------
    float
        The threshold in [0, 1]; 0 (nothing fires) without a finite value.
    """
    values = np.sort(np.asarray(lowest, dtype=np.float64))
    values = values[np.isfinite(values)]
    r = check_fraction(alpha, "alpha") * (values.size + 1)
    k = int(np.floor(r + 1e-9))
    if values.size == 0:
        return 0.0
    if k < 1:
        return float(r * values[0])
    if k >= values.size:
        return float(values[-1])
    lo, hi = np.log(max(values[k - 1], TINY)), np.log(max(values[k], TINY))
    return float(np.exp(lo + (r - k) * (hi - lo)))


def ongoing(ended, level: float | None) -> np.ndarray:
    """Which updates of one motion are ranked: those before its estimated end, shape (u,).

    ``ended`` (u,) is each update's posterior probability that the motion had
    ended (:meth:`~sandbox.core.inference.Prediction.ended_probability`); once it
    reached ``level`` at an update, that update and every later one are past the
    end (the same latch as a predictor's ``until_end``, causal). ``level`` None:
    every update is ranked.
    """
    ended = np.asarray(ended, dtype=np.float64)
    if level is None:
        return np.ones(ended.shape, dtype=bool)
    return np.maximum.accumulate(np.nan_to_num(ended, nan=0.0)) < level if ended.size else \
        np.zeros(0, dtype=bool)

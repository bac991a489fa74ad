"""The familiarity's two questions, each made a per-motion p-value before they are compared.

A calibration (:mod:`sandbox.core.calibration`) ranks each statistic of an update
as :math:`p_j` in (0, 1]. The statistics ask two questions
(:data:`~sandbox.core.evidence.SEPARATE`): how the fit so far went (the Mahalanobis
term and the timing, :math:`q = 1`) and where the hand is and heads (the goal and the
position, :math:`q = 2`). Each question's ranks are combined by Fisher's method,

.. math::  a_q = P(\\chi^2_{2J_q} \\ge -2 \\sum_{j \\in q} \\log p_j)

(:func:`answers`). A motion is unfamiliar when *some* update is: the per-motion
lowest :math:`\\ell_q = \\min_u a_q(u)` of one question is not on the scale of the
other's (the fit combines four ranks over every update, the position one rank
that calibration motions with a tail after the handover push to tiny values).
Compared as they are (the lower of the two, as calibrations before did), the
question whose calibration motions reach the lowest values sets the threshold and
the other sees nothing below it: with a tail the position or the goal took the
whole ``alpha`` and a slowed motion, which only the fit sees, went from 0.77 to
0.03 flagged (docs, Results).

With ``per_motion=True`` (:meth:`~sandbox.core.calibration.Calibration.from_records`;
measured, not the default: it halves the fit's share of ``alpha``, docs, Results) each
answer is first made a **per-motion p-value** against the calibration
motions' lowest answers of that question (:func:`motion_quantiles`, leave-one-out
as the motions' other ranks),

.. math::  \\pi_q(a) = \\hat P_i(\\ell_{q,i} \\le a),

the share of calibration motions whose lowest answer was as low (:func:`motion_rank`,
a graded tail below the lowest), and the familiarity is the lower of the two, each
divided by its share :math:`w_q` of ``alpha`` (weighted Bonferroni, :data:`WEIGHTS`),

.. math::  f = \\min\\left(1, \\min_q \\pi_q / w_q\\right).

Each question then has its share of ``alpha`` whatever the other's tail does,
and the split-conformal threshold over the calibration motions' lowest :math:`f`
(:func:`~sandbox.core.conformal.conformal_threshold`) still makes the decision
honest. Without the where-question (``score="timing"``) :math:`f = a_1`, as before;
a calibration without :attr:`~sandbox.core.calibration.Calibration.motion` (files
before it) compares the answers as they are, :math:`1 - (1 - \\min_q a_q)^2`.
"""

from __future__ import annotations

import numpy as np

from sandbox.core.conformal import TINY, fisher
from sandbox.core.evidence import SEPARATE
from sandbox.validation import FloatArray

#: Share of ``alpha`` each question is given (weighted Bonferroni), the fit's first.
WEIGHTS = (0.5, 0.5)


def groups(names: tuple) -> list[list[int]]:
    """Indices of ``names`` per question: the fit's, then (if any) the where-question's."""
    where = [j for j, n in enumerate(names) if n in SEPARATE]
    fit = [j for j in range(len(names)) if j not in where]
    return [fit, where] if where else [fit]


def answers(ranks: FloatArray, names: tuple) -> FloatArray:
    """Fisher's combination of each question's ranks, shape (M,) (module docstring)."""
    ranks = np.asarray(ranks, dtype=np.float64)
    return np.array([fisher(ranks[g]) for g in groups(names)])


def motion_quantiles(lowest: FloatArray) -> FloatArray:
    """The calibration motions' lowest answers ``lowest`` (n, M) as :math:`-\\log \\ell_q`,
    each question's sorted ascending, shape (M, n'); motions without a finite answer are
    left out (all: one 0 per question, so :func:`combine` gives 1)."""
    lowest = np.asarray(lowest, dtype=np.float64)
    ok = np.all(np.isfinite(lowest), axis=1)
    if not ok.any():
        return np.zeros((lowest.shape[1], 1))
    return np.sort(-np.log(np.clip(lowest[ok], TINY, 1.0)), axis=0).T


def motion_rank(scores: FloatArray, answer: float) -> float:
    """:math:`\\pi_q`: the share in (0, 1] of calibration motions whose lowest answer is at or
    below ``answer``, of ``scores`` (n,) (one row of :func:`motion_quantiles`), out of
    :math:`n + 1`; interpolated on :math:`\\log(-\\log a)` between the motions, and below the
    lowest :math:`\\frac{1}{n + 1} \\frac{-\\log \\ell_{(1)}}{-\\log a}` (graded, positive)."""
    n = scores.size
    u = -np.log(max(answer, TINY))
    if u <= scores[0]:
        return 1.0
    if u >= scores[-1]:
        return float(scores[-1] / u / (n + 1))
    x = np.log(np.maximum(scores, TINY))
    above = np.interp(np.log(u), x, np.arange(n, 0, -1, dtype=np.float64))   # ~ #(>= u)
    return float(above / (n + 1))


def combine(answer: FloatArray, motion: FloatArray | None) -> float:
    """The familiarity in (0, 1] of an update's answers (M,) (module docstring); ``motion``
    (M, n) from :func:`motion_quantiles`, None: the answers compared as they are."""
    answer = np.asarray(answer, dtype=np.float64)
    if answer.size == 1:
        return float(answer[0])
    if motion is None:
        least = float(answer.min())           # 1 - (1 - least)^M, exact for tiny ones
        return float(-np.expm1(answer.size * np.log1p(-least)))
    share = np.array(WEIGHTS)
    return float(min(1.0, min(motion_rank(motion[q], a) / share[q]
                              for q, a in enumerate(answer))))

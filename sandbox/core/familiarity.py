"""Familiarity: do the observations look like the motions the model learned?

The task posterior only compares the tasks with each other: a motion unlike
any of them (a task left out of training, a hand held still) still gets a
confident "most probable" task. Familiarity asks the other question: how well
do the observations fit the *best* task, compared with how well held-out
motions of the trained tasks fit it?

The statistic of one update (:func:`statistic`) is the squared Mahalanobis
distance of all observations so far from the best task's predictive
distribution at its MAP speed, per observed value,

.. math::  m = \\frac{1}{n} (y - \\mu_y)^T C^{-1} (y - \\mu_y), \\quad
            C = \\Psi \\Sigma_\\omega \\Psi^T + \\Sigma_y

(the quadratic term of the joint log-likelihood, eq. 12; :math:`n` observed
values). Under the model it would be about 1; the real scale is not (the noise
floor is set for recognition, not for calibration, and observations are
correlated), so it is *calibrated* (:func:`calibrate`): each training motion,
streamed as a predictor sees it, is scored by a model fitted without it
(leave-one-out), and the quantiles of the statistic per chosen task and bin of
elapsed time are stored (:class:`Calibration`). The familiarity of an update is
then a p-value-like score in (0, 1]: the share of held-out training updates
that chose the same task at about the same elapsed time and fitted worse
(:meth:`Calibration.familiarity`). The
threshold below which :attr:`~sandbox.core.updating.PredictorBase.familiar` is
False is the ``alpha`` quantile of each calibration motion's *lowest*
familiarity over its updates, so a motion like the training ones is called
unfamiliar at some update with probability about ``alpha``.

The statistic grows with the white noise of the stream (1 cm of tracker noise
adds (1 cm / 2 cm floor)^2 = 0.25), so the calibration streams must be
preprocessed like the live ones (causally filtered, same rate).

Measured on the recorded handovers, hand only (``python -m sandbox.eval.ood``;
README, Results): the Mahalanobis term, the log-likelihood per value and the
smallest Mahalanobis term over tasks all detected a left-out task at about their
false-alarm rate (within 1 point of each other); left-out objects are reached
like the trained ones. The false-alarm rate is as calibrated.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.inference import Prediction, predict
from sandbox.core.likelihood import Scorer
from sandbox.core.limits import MAX_SUBSAMPLE
from sandbox.core.phase import Lattice
from sandbox.core.statistics import StreamStatistics
from sandbox.core.stream import ObservationStream
from sandbox.validation import (
    FloatArray,
    check_array,
    check_choice,
    check_fraction,
    check_integer,
    check_number,
    check_positive,
)

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

#: Quantile levels stored per time bin.
LEVELS = np.linspace(0.0, 1.0, 41)
#: Left edges of the time bins, as fractions of the model's mean duration (last bin open).
EDGES = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.3, 1.7)
LIKELIHOODS = ("joint",)
#: Level above which the familiarity follows a fitted tail instead of the quantiles.
TAIL_LEVEL = 0.95
#: Smallest tail scale (log-statistic per e-fold of familiarity).
MIN_TAIL = 1e-3
TINY = 1e-300
#: Fewest updates of a (task, time bin) cell for its own quantiles (else the bin's).
MIN_CELL = 20


def statistic(prediction: Prediction) -> float:
    """Squared Mahalanobis distance per observed value of the chosen task (module docstring).

    Parameters
    ----------
    prediction : Prediction
        From :func:`~sandbox.core.inference.predict` with the joint likelihood
        (it keeps every task's augmented factor and ``n_values``).

    Returns
    -------
    float
        :math:`m \\ge 0`; NaN when the prediction kept no factors (marginal likelihood).
    """
    if prediction.factors is None or not prediction.n_values:
        return float("nan")
    k = chosen(prediction)
    return float(prediction.factors[k, -1, -1] ** 2 / prediction.n_values)


def chosen(prediction: Prediction) -> int:
    """The task the observations fit best: the most probable one (its own posterior,
    even when a predictor holds another task after the motion's end)."""
    return int(np.argmax(prediction.task_posterior))


@dataclass(frozen=True, eq=False)
class Calibration:
    """What held-out training motions scored, to rank a new update against.

    Attributes
    ----------
    edges : ndarray, shape (B,)
        Left edges (s) of the bins of elapsed time since the motion started;
        the last bin is open-ended.
    quantiles : ndarray, shape (K, B, L)
        Quantiles of :func:`statistic` at :data:`LEVELS` of the updates whose
        chosen task was k, in each bin (a cell with fewer than
        :data:`MIN_CELL` updates holds those of all tasks in the bin).
    counts : ndarray, shape (K, B)
        Updates each cell's quantiles come from (at least one).
    threshold : float
        Familiarity below which an update is unfamiliar.
    alpha : float
        Share of calibration motions unfamiliar at some update (what ``threshold`` is).
    likelihood : str
        Likelihood the statistic was computed with ("joint").
    subsample, dow_t : int, float
        Stream settings of the calibration (a predictor with others still gets a
        familiarity, less well calibrated: more updates fire more often).
    n_motions : int
        Calibration motions.
    """

    edges: FloatArray
    quantiles: FloatArray
    counts: FloatArray
    threshold: float
    alpha: float
    likelihood: str = "joint"
    subsample: int = 2
    dow_t: float = 0.2
    n_motions: int = 0

    def __post_init__(self) -> None:
        check(self)

    @property
    def n_tasks(self) -> int:
        """K."""
        return int(self.quantiles.shape[0])

    def familiarity(self, t: float, value: float, task: int) -> float:
        """Familiarity in (0, 1] of statistic ``value`` at elapsed time ``t`` (s), task chosen.

        The share of the cell's calibration updates with a larger statistic:
        interpolated between the stored quantiles up to level
        :data:`TAIL_LEVEL`; beyond it a power-law tail through the quantiles at
        levels 0.75 and ``TAIL_LEVEL`` (so a motion far worse than any
        calibration one still gets a graded, positive score). NaN for a NaN ``value``.
        """
        if not np.isfinite(value):
            return float("nan")
        b = max(int(np.searchsorted(self.edges, t, side="right")) - 1, 0)
        u = np.log(max(value, TINY))
        lq = np.log(np.maximum(self.quantiles[int(task), b], TINY))
        top = int(np.searchsorted(LEVELS, TAIL_LEVEL))
        if u <= lq[top]:
            return float(1.0 - np.interp(u, lq[: top + 1], LEVELS[: top + 1]))
        mid = int(np.searchsorted(LEVELS, 0.75))
        decades = np.log((1.0 - LEVELS[mid]) / (1.0 - LEVELS[top]))
        beta = max((lq[top] - lq[mid]) / decades, MIN_TAIL)   # log-stat per e-fold of p
        return float((1.0 - LEVELS[top]) * np.exp(-(u - lq[top]) / beta))

    @classmethod
    def from_records(cls, records, n_tasks: int, *, alpha: float = 0.05, edges=None,
                     **settings) -> Calibration:
        """Calibration from per-motion records.

        Parameters
        ----------
        records : sequence of (times, values, tasks)
            Per calibration motion: update times (s,) in seconds, their
            :func:`statistic` (s,) and the task each chose (s,) (int in [0, K)).
        n_tasks : int
            K.
        alpha : float
            Share of calibration motions that may be unfamiliar at some update.
        edges : array_like, shape (B,), optional
            Left bin edges (s); bins holding no update are merged into the one before.
        **settings
            ``likelihood``, ``subsample``, ``dow_t`` as stored.
        """
        alpha = check_fraction(alpha, "alpha")
        full, held_out = leave_one_out(records, n_tasks, edges=edges, **settings)
        lowest = np.array([f.min() if f.size else np.inf for f in held_out])
        threshold = float(np.quantile(lowest[np.isfinite(lowest)], alpha))
        return replace(full, threshold=threshold, alpha=alpha)


def leave_one_out(records, n_tasks: int, *, edges=None,
                  **settings) -> tuple[Calibration, list[FloatArray]]:
    """The quantiles of all records, and each record's familiarities against the others.

    A calibration motion is ranked as a new one would be: against the quantiles
    of the other motions (ranked against quantiles that include its own
    extremes, it would look familiar, and the threshold would let twice
    ``alpha`` of new motions fire).

    Parameters
    ----------
    records, n_tasks, edges, **settings
        As for :meth:`Calibration.from_records`.

    Returns
    -------
    calibration : Calibration
        Of all records, with threshold 0 (nothing fires) and ``alpha`` 1.
    held_out : list of ndarray, shape (s_i,)
        Familiarity of record i's finite updates against the other records.
    """
    n_tasks = check_integer(n_tasks, "n_tasks", 1)
    times, values, tasks, owner = _pool(records, n_tasks)
    edges = check_array(EDGES if edges is None else edges, "edges", 1)
    edges = _populated(np.sort(edges), times)
    bins = np.searchsorted(edges, times, side="right") - 1
    full = Calibration(edges, *_cells(values, tasks, bins, (n_tasks, edges.size)), 0.0, 1.0,
                       n_motions=len(records), **settings)
    held_out = [_against_others(full, times, values, tasks, bins, owner == i)
                for i in range(len(records))]
    return full, held_out


def _cells(values: FloatArray, tasks: np.ndarray, bins: np.ndarray,
           cells: tuple[int, int]) -> tuple[FloatArray, FloatArray]:
    """Quantiles (K, B, L) and counts (K, B) per (task, bin); thin cells use the whole bin."""
    K, B = cells
    q, counts = np.empty((K, B, LEVELS.size)), np.zeros((K, B))
    for b in range(B):
        in_bin = bins == b
        pooled = np.quantile(values[in_bin], LEVELS) if in_bin.any() else np.full(LEVELS.size,
                                                                                  np.nan)
        for k in range(K):
            mine = in_bin & (tasks == k)
            n = int(mine.sum())
            if n >= MIN_CELL:
                q[k, b], counts[k, b] = np.quantile(values[mine], LEVELS), n
            else:
                q[k, b], counts[k, b] = pooled, int(in_bin.sum())
    return q, counts


def _against_others(full: Calibration, times, values, tasks, bins, mine) -> FloatArray:
    """Familiarities of one calibration motion's updates against the quantiles of the others."""
    if not mine.any():
        return np.empty(0)
    q, counts = _cells(values[~mine], tasks[~mine], bins[~mine], full.counts.shape)
    empty = counts == 0
    q[empty], counts[empty] = full.quantiles[empty], full.counts[empty]
    others = replace(full, quantiles=q, counts=counts)
    return np.array([others.familiarity(t, v, k)
                     for t, v, k in zip(times[mine], values[mine], tasks[mine])])


def check(cal: Calibration) -> Calibration:
    """``ValueError`` unless ``cal`` is consistent (shapes, order, ranges); returns it."""
    edges = check_array(cal.edges, "calibration edges", 1)
    if edges[0] != 0.0 or np.any(np.diff(edges) <= 0):
        raise ValueError(f"calibration edges: expected increasing times from 0 s, got {edges}")
    q = check_array(cal.quantiles, "calibration quantiles", 3,
                    shape=(None, edges.size, LEVELS.size))
    if np.any(np.diff(q, axis=2) < 0) or np.any(q < 0):
        raise ValueError("calibration quantiles: expected non-negative, non-decreasing rows")
    counts = check_array(cal.counts, "calibration counts", 2, shape=(q.shape[0], edges.size))
    if np.any(counts < 1) or np.any(counts != np.round(counts)):
        raise ValueError(f"calibration counts: expected positive integers, got {counts}")
    check_number(cal.threshold, "calibration threshold", low=0.0, high=1.0)
    check_fraction(cal.alpha, "calibration alpha")
    check_choice(cal.likelihood, "calibration likelihood", LIKELIHOODS)
    check_integer(cal.subsample, "calibration subsample", 1, MAX_SUBSAMPLE)
    check_positive(cal.dow_t, "calibration dow_t")
    check_integer(cal.n_motions, "calibration n_motions", 0)
    return cal


def _pool(records, n_tasks: int):
    if len(records) == 0:
        raise ValueError("records: expected at least one calibration motion, got none")
    time_parts: list[np.ndarray] = []
    value_parts: list[np.ndarray] = []
    tasks, owner = [], []
    for i, (t, v, k) in enumerate(records):
        t, v = np.asarray(t, dtype=np.float64), np.asarray(v, dtype=np.float64)
        k = np.asarray(k)
        if t.shape != v.shape or t.shape != k.shape or t.ndim != 1:
            raise ValueError(f"records[{i}]: expected times, values and tasks of one length, "
                             f"got shapes {t.shape}, {v.shape} and {k.shape}")
        if k.size and (k.dtype.kind not in "iu" or k.min() < 0 or k.max() >= n_tasks):
            raise ValueError(f"records[{i}]: expected task indices in [0, {n_tasks}), got "
                             f"{k.tolist()[:10]}")
        ok = np.isfinite(v) & np.isfinite(t)
        time_parts.append(t[ok])
        value_parts.append(v[ok])
        tasks.append(k[ok].astype(np.int64))
        owner.append(np.full(int(ok.sum()), i))
    times, values = np.concatenate(time_parts), np.concatenate(value_parts)
    if times.size == 0:
        raise ValueError("records: expected finite statistics, got none")
    return times, values, np.concatenate(tasks), np.concatenate(owner)


def _populated(edges: FloatArray, times: FloatArray) -> FloatArray:
    """Edges from 0 with at least one time in every bin (an empty bin joins the next
    populated one, or the one before at the end)."""
    edges = np.concatenate([[0.0], edges[edges > 0]])
    bins = np.searchsorted(edges, times, side="right") - 1
    kept = edges[np.bincount(bins, minlength=edges.size) > 0]
    kept[0] = 0.0
    return kept


# ----------------------------------------------------------------- calibrating
def update_times(times: FloatArray, kept: FloatArray, dow_t: float) -> FloatArray:
    """Row times at which a :class:`~sandbox.core.predictor.DynamicPredictor` updates.

    ``times`` (T,) are the rows' times (s), ``kept`` (s,) those of the kept
    observations (an update needs at least one).
    """
    out, boundary = [], dow_t
    for ti in times:
        if ti >= boundary - 1e-9:
            if np.searchsorted(kept, ti, side="right") > 0:
                out.append(float(ti))
            boundary = float((np.floor(ti / dow_t + 1e-9) + 1) * dow_t)
    return np.array(out)


def stream_record(model: IProMP, times, human, *, dow_t: float = 0.2, subsample: int = 2,
                  n_candidates: int = 50, width: float = 3.0,
                  refine_steps: int = 1) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Update times (u,), :func:`statistic` (u,) and chosen task (u,) of a stream, as a
    predictor sees it.

    Parameters
    ----------
    model : IProMP
        Fitted.
    times : array_like, shape (T,)
        Row times (s) since the motion started.
    human : array_like, shape (T, P)
        Raw rows (all the model's modalities; NaN where missing).
    dow_t, subsample, n_candidates, width, refine_steps
        As for :class:`~sandbox.core.predictor.DynamicPredictor` (joint likelihood,
        all observations so far).
    """
    times = check_array(times, "times", 1)
    stream = ObservationStream(model, subsample=subsample)
    for ti, yi in zip(times, np.asarray(human, dtype=np.float64)):
        stream.accept(ti, yi)
    t_obs, y_obs = stream.observations()
    scorer = Scorer(model)
    stats = StreamStatistics(scorer, Lattice.for_tasks(model.task_models, n_candidates, width))
    at = update_times(times, t_obs, dow_t)
    out, task, fed = np.empty(at.size), np.zeros(at.size, dtype=np.int64), 0
    for j, tau in enumerate(at):
        n = int(np.searchsorted(t_obs, tau, side="right"))
        for i in range(fed, n):
            stats.add(t_obs[i], y_obs[i])
        fed = n
        pred = predict(model, scorer, t_obs[:n], y_obs[:n], n_candidates=n_candidates,
                       width=width, refine_steps=refine_steps, stats=stats)
        out[j], task[j] = statistic(pred), chosen(pred)
    return at, out, task


def loo_records(model: IProMP, demos, streams=None, **options) -> list[tuple]:
    """:func:`stream_record` of every demo by a model fitted on all the others.

    ``model`` gives the options (its fit, if any, is not used); ``streams[i]``
    is demo i as a predictor receives it (e.g. causally filtered; default the
    demo itself, whose smoothing makes it fit better than live streams do).
    Each task needs three demos or more (two left when one is out).
    """
    streams = demos if streams is None else streams
    if len(streams) != len(demos):
        raise ValueError(f"streams: expected one per demo ({len(demos)}), got {len(streams)}")
    fits = [model.demo_fit(d) for d in demos]
    out = []
    for i, s in enumerate(streams):
        held_out = copy.copy(model).fit_demo_fits(fits[:i] + fits[i + 1:], demos[0])
        t = np.asarray(s.times, dtype=np.float64)
        out.append(stream_record(held_out, t - t[0], s.human, **options))
    return out


def calibrate(model: IProMP, demos, streams=None, *, alpha: float = 0.05, dow_t: float = 0.2,
              subsample: int = 2, **options) -> Calibration:
    """Leave-one-out calibration of the familiarity of ``model`` (fitted on ``demos``).

    Sets ``model.calibration`` and returns it. Cost: one stream of every demo
    with an update every ``dow_t`` (seconds per demo on the recorded set).

    Parameters
    ----------
    model : IProMP
        Fitted on ``demos`` (the calibration refits without each in turn).
    demos, streams, **options
        As for :func:`loo_records`.
    alpha : float
        Share of held-out motions allowed to be unfamiliar at some update.
    dow_t, subsample : float, int
        The predictor's window (s) and subsampling the familiarity is calibrated for.
    """
    records = loo_records(model, demos, streams, dow_t=dow_t, subsample=subsample, **options)
    mean = float(np.dot(model.priors, [t.mean_duration for t in model.task_models]))
    cal = Calibration.from_records(records, len(model.task_models), alpha=alpha,
                                   edges=np.array(EDGES) * mean,
                                   subsample=subsample, dow_t=dow_t)
    model.calibration = cal
    return cal

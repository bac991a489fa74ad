"""The familiarity calibration: quantiles of held-out updates' statistic, to rank new ones.

:class:`Calibration` stores, per chosen task and bin of elapsed time, the
quantiles of :func:`~sandbox.core.familiarity.statistic` over the updates of
held-out training motions, and ranks a new update against them
(:meth:`Calibration.familiarity`); :func:`leave_one_out` builds it from
per-motion records and ranks each motion against the others (for the
threshold); :func:`check` validates one (e.g. read from a model file). How the
records are made, and what the statistic means: :mod:`sandbox.core.familiarity`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sandbox.core.limits import MAX_SUBSAMPLE, MAX_TIME_S
from sandbox.validation import (
    FloatArray,
    check_array,
    check_choice,
    check_fraction,
    check_integer,
    check_number,
    check_positive,
)

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


@dataclass(frozen=True, eq=False)
class Calibration:
    """What held-out training motions scored, to rank a new update against.

    Attributes
    ----------
    edges : ndarray, shape (B,)
        Left edges (s) of the bins of elapsed time since the motion started;
        the last bin is open-ended.
    quantiles : ndarray, shape (K, B, L)
        Quantiles of :func:`~sandbox.core.familiarity.statistic` at :data:`LEVELS` of
        the updates whose chosen task was k, in each bin (a cell with fewer than
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
            :func:`~sandbox.core.familiarity.statistic` (s,) and the task each chose
            (s,) (int in [0, K)).
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
    if edges[0] != 0.0 or np.any(np.diff(edges) <= 0) or edges[-1] > MAX_TIME_S:
        raise ValueError(f"calibration edges: expected increasing times from 0 s to at most "
                         f"{MAX_TIME_S:g} s (limits.MAX_TIME_S), got {edges}")
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
    check_positive(cal.dow_t, "calibration dow_t", high=MAX_TIME_S)
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

"""The familiarity calibration: quantiles of held-out updates' statistics, to rank new ones.

:class:`Calibration` stores, per chosen task and bin of elapsed time, the
quantiles of each statistic of :data:`~sandbox.core.evidence.COMPONENTS` (or of
the Mahalanobis term alone, as files before them did) over the updates of
held-out training motions, and ranks a new update against them
(:meth:`Calibration.familiarity`); :func:`leave_one_out` builds it from
per-motion records and ranks each motion against the others (for the
threshold, :func:`conformal_threshold`); :func:`check` validates one (e.g. read
from a model file). How the records are made, and what the statistics mean:
:mod:`sandbox.core.familiarity`, :mod:`sandbox.core.evidence`.

**Combining.** Statistic :math:`j` of an update ranks as
:math:`p_j = \\hat F_j^c(s_j)`, the share of the cell's held-out updates with a
larger value (a p-value under the calibration motions' distribution). The
:math:`J` ranks are combined by Fisher's method,

.. math::  X = -2 \\sum_{j=1}^{J} \\log p_j, \\qquad
           f = P(\\chi^2_{2J} \\ge X) = e^{-X/2} \\sum_{i=0}^{J-1} \\frac{(X/2)^i}{i!},

the familiarity in (0, 1] (exact for independent uniform :math:`p_j`; the
statistics are not independent, so :math:`f` is a score, not a p-value, and the
threshold below makes the decision honest). The goal and the position
(:data:`~sandbox.core.evidence.SEPARATE`) ask another question (where the hand is
heading, where it is now) than how the fit so far went, and see something only in a
few updates (the last tenths of a second before an odd end): in one Fisher
combination of all :math:`J` a tiny :math:`p` of theirs would be diluted among ranks
that see nothing. So they are combined with each other (Fisher,
:math:`f_{where}`), the others apart (:math:`f_{fit}`), and the familiarity is the
lower of the two questions' p-values in the scale of one (Šidák's correction, exact for
independent uniform p-values, conservative for positively dependent ones),

.. math::  f = 1 - (1 - \\min(f_{fit}, f_{where}))^2.

Where they see nothing (:math:`f_{where}` near 1) it is :math:`2 f_{fit}` to first
order, so motions rank as without them. Measured (``python -m sandbox ood``, hand,
detection before the handover at 5 % false alarms; docs, Results): the synthetic
endpoint family 0.30 without the goal, 0.62 with all five in one combination, 0.66 this
way, 0.79 with the position too (0.72 with the three apart); the recorded set's
leave-task-out (hand) 0.14, 0.11 and 0.13, (hand, arm, EMG) 0.33 timing, 0.38 all.
**Threshold (split-conformal, per motion).** Each calibration motion's lowest
familiarity :math:`\\ell_i` over its updates is computed as a new motion's
would be: the motion streamed by a model fitted without it
(:func:`~sandbox.core.familiarity.loo_records`) and ranked against the other
motions' updates (:func:`leave_one_out`). With the :math:`n` values sorted,
:math:`\\ell_{(1)} \\le \\dots \\le \\ell_{(n)}`, the threshold is
:math:`\\ell_{(k)}`, :math:`k = \\alpha (n + 1)` (interpolated between order
statistics when not an integer, :func:`conformal_threshold`), and a motion is
unfamiliar when some update's familiarity is below it. For a new motion
exchangeable with the calibration ones, :math:`\\ell` is below
:math:`\\ell_{(k)}` with probability :math:`k / (n + 1)` for an integer
:math:`k` (the rank of :math:`\\ell` among the :math:`n + 1` is uniform),
whatever the statistics' distribution: about ``alpha``.

**Gated to the ongoing motion (opt-in).** With ``end_prob`` (e.g. 0.5), the
updates from the first whose probability that the motion had ended reached it
(:func:`~sandbox.core.conformal.ongoing`) are neither calibrated nor ranked: what
people do after the handover no longer sets the threshold. A hand that stops mid-reach or reaches an
odd end looks arrived, though, so it is not the default (issue 30; docs, Results).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from sandbox.core.conformal import (
    LEVELS,
    conformal_threshold,
    fisher,
    ongoing,
    rank,
)
from sandbox.core.evidence import ANALYTIC, COMPONENTS, SEPARATE, TIMING
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

#: Left edges of the time bins, as fractions of the model's mean duration (last bin open).
EDGES = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.3, 1.7)
LIKELIHOODS = ("joint",)
#: Smallest tail scale of the statistics after the Mahalanobis term: a statistic whose
#: calibration values hardly vary (e.g. all 0) must grow by 10 % per e-fold of its rank.
EXTRA_MIN_TAIL = 0.1
#: The statistics a calibration can rank: the Mahalanobis term alone (files before
#: issue 30), the four of timing, those with the goal, with the position, or all
#: :data:`COMPONENTS`.
NAMES = (("mahalanobis",), TIMING, TIMING + ("goal",), TIMING + ("position",), COMPONENTS)
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
    components : tuple of str
        The statistics ranked, one of :data:`NAMES` (``("mahalanobis",)``: files before
        the timing evidence).
    extra : ndarray or None, shape (J - 1, K, B, L)
        Quantiles of the statistics after the first, like ``quantiles``; None for one.
    end_prob : float or None
        Gate to the ongoing motion: an update at or after the first whose posterior
        probability that the motion had ended reached ``end_prob``
        (:func:`~sandbox.core.conformal.ongoing`) is neither calibrated nor ranked;
        None (files before the gate): every update.
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
    components: tuple = ("mahalanobis",)
    extra: FloatArray | None = None
    end_prob: float | None = None

    def __post_init__(self) -> None:
        check(self)

    @property
    def n_tasks(self) -> int:
        """K."""
        return int(self.quantiles.shape[0])

    @property
    def stack(self) -> FloatArray:
        """All statistics' quantiles, shape (J, K, B, L)."""
        if self.extra is None:
            return self.quantiles[None]
        return np.concatenate([self.quantiles[None], self.extra])

    def familiarity(self, t: float, value, task: int, ended: float = 0.0) -> float:
        """Familiarity in (0, 1] of the statistics ``value`` at elapsed time ``t`` (s), task chosen.

        ``ended`` is the highest posterior probability so far that the motion had
        ended: at or above :attr:`end_prob` the update is past the motion's
        estimated end and not ranked (NaN).

        ``value`` is one float per statistic of :attr:`components` (a float for
        one), or all :data:`~sandbox.core.evidence.COMPONENTS` (or the first five, as
        records before the position have them; those of :attr:`components` are taken:
        an older calibration ranks what it was made of). Each ranks as the share of
        the cell's calibration updates with a larger value (:func:`rank`; the tail of
        a statistic after the first falls at most one e-fold per
        :data:`EXTRA_MIN_TAIL` of its log), except the
        :data:`~sandbox.core.evidence.ANALYTIC` ones, p-value bounds: they rank as
        :math:`e^{-s}` (their stored quantiles only describe them). The ranks combine
        by Fisher's method, the :data:`~sandbox.core.evidence.SEPARATE` ones apart
        (module docstring). NaN when the first statistic is NaN; a later NaN
        statistic counts as no evidence (rank 1).
        """
        v = np.atleast_1d(np.asarray(value, dtype=np.float64))
        names = tuple(self.components)
        where = [COMPONENTS.index(n) for n in names]
        if v.size != len(names) and v.size >= len(COMPONENTS) - 1 and max(where) < v.size:
            v = v[where]                                  # all statistics (older records: 5)
        if v.shape != (len(names),):
            raise ValueError(f"value: expected {len(names)} statistics {names}, got shape "
                             f"{v.shape}")
        if not np.isfinite(v[0]) or (self.end_prob is not None and ended >= self.end_prob):
            return float("nan")
        b = max(int(np.searchsorted(self.edges, t, side="right")) - 1, 0)
        q = self.stack[:, int(task), b]
        if v.size == 1:
            return rank(q[0], v[0])
        ranks = [rank(q[j], v[j], EXTRA_MIN_TAIL) if np.isfinite(v[j]) else 1.0
                 for j in range(v.size)]
        ranks[0] = rank(q[0], v[0])
        for j, name in enumerate(names):
            if name in ANALYTIC:
                ranks[j] = float(np.exp(-v[j])) if np.isfinite(v[j]) else 1.0
        apart = [j for j, name in enumerate(names) if name in SEPARATE]
        if not apart:
            return fisher(np.array(ranks))
        fit = fisher(np.array([r for j, r in enumerate(ranks) if j not in apart]))
        least = min(fit, fisher(np.array([ranks[j] for j in apart])))
        return float(least * (2.0 - least))          # 1 - (1 - least)^2: the lower of two

    @classmethod
    def from_records(cls, records, n_tasks: int, *, alpha: float = 0.05, edges=None,
                     **settings) -> Calibration:
        """Calibration from per-motion records.

        Parameters
        ----------
        records : sequence of (times, values, tasks[, ended])
            Per calibration motion: update times (s,) in seconds, their
            statistics, (s,) (:func:`~sandbox.core.familiarity.statistic`) or
            (s, J) (J statistics of one of :data:`NAMES`), the task each
            chose (s,) (int in [0, K)) and, with ``end_prob``, each update's
            probability that the motion had ended (s,)
            (:func:`~sandbox.core.conformal.ongoing`).
        n_tasks : int
            K.
        alpha : float
            Share of calibration motions that may be unfamiliar at some update.
        edges : array_like, shape (B,), optional
            Left bin edges (s); bins holding no update are merged into the one before.
        **settings
            ``likelihood``, ``subsample``, ``dow_t``, ``end_prob`` as stored (with
            ``end_prob``, the updates past each motion's estimated end are left out).
        """
        alpha = check_fraction(alpha, "alpha")
        full, held_out = leave_one_out(records, n_tasks, edges=edges, **settings)
        lowest = np.array([f.min() if f.size else np.inf for f in held_out])
        return replace(full, threshold=conformal_threshold(lowest, alpha), alpha=alpha)


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
    end_prob = settings.get("end_prob")
    if end_prob is not None:
        settings["end_prob"] = check_fraction(end_prob, "end_prob")
    times, values, tasks, owner = _pool(records, n_tasks, settings.get("end_prob"))
    edges = check_array(EDGES if edges is None else edges, "edges", 1)
    edges = _populated(np.sort(edges), times)
    bins = np.searchsorted(edges, times, side="right") - 1
    q, counts = _cells(values, tasks, bins, (n_tasks, edges.size))
    names = [n for n in NAMES if len(n) == q.shape[0]]   # the first of a length, unless named
    if not names or len(settings.setdefault("components", names[0])) != q.shape[0]:
        raise ValueError(f"records: expected {' or '.join(sorted({str(len(n)) for n in NAMES}))} "
                         f"statistics per update ({NAMES}), got {q.shape[0]}")
    full = Calibration(edges, q[0], counts, 0.0, 1.0, n_motions=len(records),
                       extra=q[1:] if q.shape[0] > 1 else None, **settings)
    held_out = [_against_others(full, times, values, tasks, bins, owner == i)
                for i in range(len(records))]
    return full, held_out


def _cells(values: FloatArray, tasks: np.ndarray, bins: np.ndarray,
           cells: tuple[int, int]) -> tuple[FloatArray, FloatArray]:
    """Quantiles (J, K, B, L) of ``values`` (n, J) and counts (K, B) per (task, bin); thin
    cells use the whole bin."""
    K, B = cells
    q, counts = np.empty((values.shape[1], K, B, LEVELS.size)), np.zeros((K, B))
    for b in range(B):
        in_bin = bins == b
        pooled = (np.quantile(values[in_bin], LEVELS, axis=0).T if in_bin.any()
                  else np.full((values.shape[1], LEVELS.size), np.nan))
        for k in range(K):
            mine = in_bin & (tasks == k)
            n = int(mine.sum())
            if n >= MIN_CELL:
                q[:, k, b], counts[k, b] = np.quantile(values[mine], LEVELS, axis=0).T, n
            else:
                q[:, k, b], counts[k, b] = pooled, int(in_bin.sum())
    return q, counts


def _against_others(full: Calibration, times, values, tasks, bins, mine) -> FloatArray:
    """Familiarities of one calibration motion's updates against the quantiles of the others."""
    if not mine.any():
        return np.empty(0)
    q, counts = _cells(values[~mine], tasks[~mine], bins[~mine], full.counts.shape)
    empty = counts == 0
    q[:, empty], counts[empty] = full.stack[:, empty], full.counts[empty]
    others = replace(full, quantiles=q[0], counts=counts,
                     extra=q[1:] if q.shape[0] > 1 else None)
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
    _check_extra(cal, q)
    check_number(cal.threshold, "calibration threshold", low=0.0, high=1.0)
    check_fraction(cal.alpha, "calibration alpha")
    check_choice(cal.likelihood, "calibration likelihood", LIKELIHOODS)
    check_integer(cal.subsample, "calibration subsample", 1, MAX_SUBSAMPLE)
    check_positive(cal.dow_t, "calibration dow_t", high=MAX_TIME_S)
    check_integer(cal.n_motions, "calibration n_motions", 0)
    if cal.end_prob is not None:
        check_fraction(cal.end_prob, "calibration end_prob")
    return cal


def _check_extra(cal: Calibration, q: FloatArray) -> None:
    names = tuple(cal.components)
    if names not in NAMES:
        raise ValueError(f"calibration components: expected one of {NAMES}, got {names!r}")
    if len(names) == 1 or cal.extra is None:
        if cal.extra is not None or len(names) > 1:
            raise ValueError(f"calibration extra: expected quantiles of {len(names) - 1} more "
                             f"statistics, got {'none' if cal.extra is None else 'some'}")
        return
    extra = check_array(cal.extra, "calibration extra quantiles", 4,
                        shape=(len(names) - 1,) + q.shape)
    if np.any(np.diff(extra, axis=3) < 0) or np.any(extra < 0):
        raise ValueError("calibration extra quantiles: expected non-negative, non-decreasing rows")


def _pool(records, n_tasks: int, end_prob: float | None = None):
    if len(records) == 0:
        raise ValueError("records: expected at least one calibration motion, got none")
    time_parts: list[np.ndarray] = []
    value_parts: list[np.ndarray] = []
    tasks, owner = [], []
    for i, (t, v, k, *ended) in enumerate(records):
        t, v = np.asarray(t, dtype=np.float64), np.array(v, dtype=np.float64)
        v = v[:, None] if v.ndim == 1 else v
        k = np.asarray(k)
        if (t.ndim != 1 or v.ndim != 2 or t.shape != k.shape or v.shape[0] != t.size
                or (value_parts and v.shape[1] != value_parts[0].shape[1])):
            raise ValueError(f"records[{i}]: expected times, values and tasks of one length "
                             f"(values (s,) or (s, J), J alike in all records), got shapes "
                             f"{t.shape}, {v.shape} and {k.shape}")
        if k.size and (k.dtype.kind not in "iu" or k.min() < 0 or k.max() >= n_tasks):
            raise ValueError(f"records[{i}]: expected task indices in [0, {n_tasks}), got "
                             f"{k.tolist()[:10]}")
        if end_prob is not None:
            if not ended or np.shape(ended[0]) != t.shape:
                raise ValueError(f"records[{i}]: expected each update's ended probability "
                                 f"(a fourth entry, shape {t.shape}) to gate on, got "
                                 f"{np.shape(ended[0]) if ended else 'none'}")
            v[~ongoing(ended[0], end_prob)] = np.nan       # past the estimated end
        ok = np.isfinite(v[:, 0]) & np.isfinite(t)
        time_parts.append(t[ok])
        value_parts.append(np.where(np.isfinite(v[ok]), v[ok], 0.0))   # later NaN: no evidence
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

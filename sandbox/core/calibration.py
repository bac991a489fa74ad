"""The familiarity calibration: quantiles of held-out updates' statistics, to rank new ones.

:class:`Calibration` stores, per task and bin of elapsed time, the
quantiles of each statistic of :data:`~sandbox.core.evidence.COMPONENTS` (or of
the Mahalanobis term alone, as files before them did) over the updates of
held-out training motions of that task, under it (or, ``cells="chosen"``, the updates
that chose it; :mod:`sandbox.core.cells`, with the derivation), and ranks a new update
in the cell of the task chosen at it
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
threshold below makes the decision honest).

The statistics ask two questions (:data:`~sandbox.core.evidence.SEPARATE`): how the fit
so far went, and where the hand is and heads (the goal and the position, which see
something only in a few updates: in one Fisher combination of all :math:`J` their tiny
:math:`p` would be diluted among ranks that see nothing). Each question's ranks are
combined apart and the familiarity is the lower of the two (Šidák; with
``per_motion=True`` each first made a per-motion p-value, :mod:`sandbox.core.questions`). The
position asks the same question at every phase, so its quantiles are those of all the
task's updates (:data:`BINLESS`): binned by elapsed time, the bins around the handover
hold the calibration motions' tails after it, which hid an odd end reached on time
(synthetic endpoint family, position alone, 0.57 binned, 0.84 not; ``score="position"``
0.45 binned, 0.65 not; docs, Results).

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

from sandbox.core.cells import CELLS, MIN_CELL, against_others, quantile_cells
from sandbox.core.conformal import (
    LEVELS,
    conformal_threshold,
    fisher,
    ongoing,
    rank,
)
from sandbox.core.evidence import ANALYTIC, COMPONENTS, TIMING
from sandbox.core.limits import MAX_SUBSAMPLE, MAX_TIME_S
from sandbox.core.questions import answers, combine, groups, motion_quantiles
from sandbox.core.records import pool as _pool
from sandbox.core.records import populated as _populated
from sandbox.validation import (
    FloatArray,
    check_array,
    check_choice,
    check_fraction,
    check_integer,
    check_number,
    check_positive,
)

__all__ = ["BINLESS", "CELLS", "COMPONENTS", "EDGES", "LEVELS", "MIN_CELL", "NAMES", "Calibration",
           "check", "conformal_threshold", "fisher", "leave_one_out", "ongoing", "rank"]

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
#: Statistics ranked against all of the task's updates, whatever the elapsed time.
BINLESS = ("position",)


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
        the updates filed under task k (:attr:`cells`), in each bin (a cell with fewer than
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
    motion : ndarray or None, shape (2, n)
        The calibration motions' lowest answer to each question, as :math:`-\\log`
        (:func:`~sandbox.core.questions.motion_quantiles`), with the goal or the
        position; None: the answers compared as they are (files before it).
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
    motion: FloatArray | None = None
    cells: str | None = None

    def __post_init__(self) -> None:
        if self.motion is not None:            # a model file's metadata holds a list
            object.__setattr__(self, "motion", np.asarray(self.motion, dtype=np.float64))
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
        by Fisher's method per question, and the questions as
        :func:`~sandbox.core.questions.combine` says (module docstring). NaN when the
        first statistic is NaN; a later NaN statistic counts as no evidence (rank 1).
        """
        found = self.answers(t, value, task, ended)
        return float("nan") if np.isnan(found[0]) else combine(found, self.motion)

    def answers(self, t: float, value, task: int, ended: float = 0.0) -> FloatArray:
        """Each question's Fisher combination of its ranks, shape (M,) (M = 2 with the goal
        or the position, else 1; :func:`~sandbox.core.questions.answers`), NaN where
        :meth:`familiarity` is; same arguments."""
        v = np.atleast_1d(np.asarray(value, dtype=np.float64))
        names = tuple(self.components)
        where = [COMPONENTS.index(n) for n in names]
        if v.size != len(names) and v.size >= len(COMPONENTS) - 1 and max(where) < v.size:
            v = v[where]                                  # all statistics (older records: 5)
        if v.shape != (len(names),):
            raise ValueError(f"value: expected {len(names)} statistics {names}, got shape "
                             f"{v.shape}")
        if not np.isfinite(v[0]) or (self.end_prob is not None and ended >= self.end_prob):
            return np.full(len(groups(names)), np.nan)
        b = max(int(np.searchsorted(self.edges, t, side="right")) - 1, 0)
        q = self.stack[:, int(task), b]
        if v.size == 1:
            return np.array([rank(q[0], v[0])])
        ranks = [rank(q[j], v[j], EXTRA_MIN_TAIL) if np.isfinite(v[j]) else 1.0
                 for j in range(v.size)]
        ranks[0] = rank(q[0], v[0])
        for j, name in enumerate(names):
            if name in ANALYTIC:
                ranks[j] = float(np.exp(-v[j])) if np.isfinite(v[j]) else 1.0
        return answers(np.array(ranks), names)

    @classmethod
    def from_records(cls, records, n_tasks: int, *, alpha: float = 0.05, edges=None,
                     own=None, **settings) -> Calibration:
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
        own : sequence of (times, values, tasks[, ended]), optional
            Per record, the same updates with the statistics under the motion's own (true)
            task, that task at every update: the cells are filed from these
            (``cells="own"``, :mod:`sandbox.core.cells`), the motions still ranked as
            ``records`` say (the chosen task's cell); None: filed from ``records``
            (``cells="chosen"``).
        **settings
            ``likelihood``, ``subsample``, ``dow_t``, ``end_prob`` as stored (with
            ``end_prob``, the updates past each motion's estimated end are left out);
            ``per_motion=True``: each question's answer made a per-motion p-value first
            (:mod:`sandbox.core.questions`; measured, not the default: docs, Results).
        """
        alpha = check_fraction(alpha, "alpha")
        full, held_out = leave_one_out(records, n_tasks, edges=edges, own=own, **settings)
        lowest = np.array([f.min() if f.size else np.inf for f in held_out])
        return replace(full, threshold=conformal_threshold(lowest, alpha), alpha=alpha)


def leave_one_out(records, n_tasks: int, *, edges=None, own=None,
                  **settings) -> tuple[Calibration, list[FloatArray]]:
    """The quantiles of all records, and each record's familiarities against the others.

    A calibration motion is ranked as a new one would be: under the task chosen at each
    update, against the cells of the other motions (ranked against quantiles that include
    its own extremes, it would look familiar, and the threshold would let twice ``alpha``
    of new motions fire).

    Parameters
    ----------
    records, n_tasks, edges, own, **settings
        As for :meth:`Calibration.from_records`.

    Returns
    -------
    calibration : Calibration
        Of all records, with threshold 0 (nothing fires) and ``alpha`` 1.
    held_out : list of ndarray, shape (s_i,)
        Familiarity of record i's finite updates against the other records.
    """
    n_tasks = check_integer(n_tasks, "n_tasks", 1)
    per_motion = bool(settings.pop("per_motion", False))
    end_prob = settings.get("end_prob")
    if end_prob is not None:
        settings["end_prob"] = check_fraction(end_prob, "end_prob")
    times, values, tasks, owner = _pool(records, n_tasks, settings.get("end_prob"))
    filing = _filing(records, own, n_tasks, settings.get("end_prob"), values.shape[1])
    edges = check_array(EDGES if edges is None else edges, "edges", 1)
    edges = _populated(np.sort(edges), np.concatenate([times, filing[0]]))
    filed_bins = np.searchsorted(edges, filing[0], side="right") - 1
    names = [n for n in NAMES if len(n) == values.shape[1]]   # the first of a length, unless named
    if not names or len(settings.setdefault("components", names[0])) != values.shape[1]:
        raise ValueError(f"records: expected {' or '.join(sorted({str(len(n)) for n in NAMES}))} "
                         f"statistics per update ({NAMES}), got {values.shape[1]}")
    binless = [j for j, n in enumerate(settings["components"]) if n in BINLESS]
    _, filed, filed_tasks, filed_owner = filing
    q, counts = quantile_cells(filed, filed_tasks, filed_bins, (n_tasks, edges.size), binless)
    full = Calibration(edges, q[0], counts, 0.0, 1.0, n_motions=len(records),
                       extra=q[1:] if q.shape[0] > 1 else None,
                       cells="chosen" if own is None else "own", **settings)
    found = []
    for i in range(len(records)):
        mine, others = owner == i, filed_owner != i
        found.append(against_others(full, (times[mine], values[mine], tasks[mine]),
                                    (filed[others], filed_tasks[others], filed_bins[others]),
                                    binless))
    if found[0].shape[1] == 1 or not per_motion:
        return full, [np.array([combine(x, None) for x in a]) for a in found]
    lowest = np.array([a.min(axis=0) if a.size else np.full(a.shape[1], np.inf) for a in found])
    held_out = []
    for i, a in enumerate(found):                # against the other motions' lowest answers
        others = motion_quantiles(np.delete(lowest, i, axis=0))
        held_out.append(np.array([combine(x, others) for x in a]))
    return replace(full, motion=motion_quantiles(lowest)), held_out


def _filing(records, own, n_tasks: int, end_prob, n_stats: int) -> tuple:
    """Times, statistics, tasks and owner of the updates filed into cells: ``own``'s (one
    per record, as many statistics), else those of ``records``."""
    if own is None:
        return _pool(records, n_tasks, end_prob)
    if len(own) != len(records):
        raise ValueError(f"own: expected one record per calibration motion ({len(records)}), "
                         f"got {len(own)}")
    filing = _pool(own, n_tasks, end_prob)
    if filing[1].shape[1] != n_stats:
        raise ValueError(f"own: expected {n_stats} statistics per update as in records, got "
                         f"{filing[1].shape[1]}")
    return filing


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
    if cal.cells is not None:
        check_choice(cal.cells, "calibration cells", CELLS)
    if cal.motion is not None:
        motion = check_array(cal.motion, "calibration motion quantiles", 2,
                             shape=(len(groups(tuple(cal.components))), None))
        if motion.shape[0] < 2 or np.any(np.diff(motion, axis=1) < 0) or np.any(motion < 0):
            raise ValueError("calibration motion quantiles: expected non-negative, "
                             "non-decreasing rows of the two questions")
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

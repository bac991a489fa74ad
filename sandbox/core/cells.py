"""The cells of a familiarity calibration: quantiles per (task, time bin), and a
calibration motion ranked against the other motions' cells.

:mod:`sandbox.core.calibration`'s building side. A cell (k, b) holds the
quantiles of the statistics of the calibration updates *filed under* task k in
time bin b. Two filings (:data:`CELLS`):

* ``"own"`` (default since issue 30's own-task cells): every update of a
  calibration motion of task k, its statistics taken under task k (the task that
  explains it), whatever the predictor chose at that update;
* ``"chosen"`` (before): every update under the task the predictor chose then,
  with that task's statistics.

**Why the true task's motions calibrate the chosen task's cell.** At test time an
update is ranked in the cell of the task the predictor chose, :math:`\\hat k`. The
question that cell answers is "is this statistic unusual for a normal motion *of*
:math:`\\hat k`, seen under :math:`\\hat k`?", so its reference distribution is that of
:math:`s(\\cdot \\mid k)` over updates of normal motions of task :math:`k = \\hat k`, at
that elapsed time. Filed by the chosen task, the cell mixes in the early updates
of motions of *other* tasks, scored under a task that does not explain them
(before the posterior settles): their statistics are large, they fatten the
cell's tail, and an unusual motion ranks as ordinary. Filed by the true task,
each cell holds only what normal motions of its own task score (the labels are
known at calibration time and used only there: at test time nothing changes). The
threshold stays split-conformal: each calibration motion's lowest familiarity is
computed as a new motion's would be, *under the task chosen at each update*,
against the others' own-task cells (:func:`against_others`), and the
:math:`\\alpha (n + 1)`-th lowest is the threshold, so a new normal motion
exchangeable with them fires with probability about :math:`\\alpha` whichever
filing made the cells (the filing only changes how sharply the score separates
unusual motions; docs, Results).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sandbox.core.conformal import LEVELS
from sandbox.core.questions import groups
from sandbox.validation import FloatArray

__all__ = ["CELLS", "MIN_CELL", "against_others", "quantile_cells"]

#: How calibration updates are filed into cells (module docstring): under the calibration
#: motion's own (true) task, or under the task chosen at the update.
CELLS = ("own", "chosen")
#: Fewest updates of a (task, time bin) cell for its own quantiles (else the bin's).
MIN_CELL = 20


def quantile_cells(values: FloatArray, tasks: np.ndarray, bins: np.ndarray,
                   cells: tuple[int, int], binless=()) -> tuple[FloatArray, FloatArray]:
    """Quantiles (J, K, B, L) at :data:`~sandbox.core.conformal.LEVELS` of ``values`` (n, J)
    and counts (K, B) per (task ``tasks``, bin ``bins``), ``cells`` = (K, B); thin cells use
    the whole bin; statistics ``binless`` (indices) those of the task in every bin (of all
    updates when the task has fewer than :data:`MIN_CELL`)."""
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
    for k in range(K) if binless else ():
        mine = values[tasks == k] if np.sum(tasks == k) >= MIN_CELL else values
        q[binless, k] = np.quantile(mine[:, binless], LEVELS, axis=0).T[:, None]
    return q, counts


def against_others(full, ranked: tuple, filed: tuple, binless=()) -> FloatArray:
    """Answers (s, M) of one calibration motion's updates against the cells of the others.

    Parameters
    ----------
    full : Calibration
        Of all motions (its cells stand in for those the others leave empty).
    ranked : tuple of ndarray
        The motion's updates as a new motion's are ranked: times (s,) in seconds,
        statistics (s, J) under the task chosen at each update, those tasks (s,).
    filed : tuple of ndarray
        The other motions' updates as filed into cells: statistics (n, J), tasks (n,) and
        time bins (n,) (:data:`CELLS`).
    binless : sequence of int
        As for :func:`quantile_cells`.

    Returns
    -------
    ndarray, shape (s, M)
        :meth:`~sandbox.core.calibration.Calibration.answers` of each update.
    """
    times, values, tasks = ranked
    if times.size == 0:
        return np.empty((0, len(groups(tuple(full.components)))))
    values_filed, tasks_filed, bins_filed = filed
    q, counts = quantile_cells(values_filed, tasks_filed, bins_filed, full.counts.shape, binless)
    empty = counts == 0
    q[:, empty], counts[empty] = full.stack[:, empty], full.counts[empty]
    others = replace(full, quantiles=q[0], counts=counts,
                     extra=q[1:] if q.shape[0] > 1 else None)
    return np.array([others.answers(t, v, k) for t, v, k in zip(times, values, tasks)])

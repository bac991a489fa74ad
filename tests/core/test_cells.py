"""Calibration cells filed under each motion's own task or the chosen one (sandbox.core.cells,
Calibration.from_records(own=...)): known quantiles, the conformal false-alarm rate on fresh
motions, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.core.calibration import LEVELS, Calibration
from sandbox.core.evidence import TIMING

EDGES = [0.0, 0.8]


def labelled(rng, n: int, shift: float = 0.0):
    """Records of n motions of two tasks (8 updates, 4 statistics): under its own task k a
    motion scores lognormal(k / 2 + shift); its first two updates choose the other task and
    score 3 times larger under it (what a predictor does before the posterior settles).
    Returns the records as ranked (chosen task) and as filed under the own task."""
    ranked, own = [], []
    for i in range(n):
        k, t = i % 2, np.arange(8) * 0.2
        mine = rng.lognormal(k / 2 + shift, 0.5, (8, len(TIMING)))
        chosen = np.array([1 - k] * 2 + [k] * 6)
        seen = mine.copy()
        seen[:2] *= 3.0
        ranked.append((t, seen, chosen))
        own.append((t, mine, np.full(8, k)))
    return ranked, own


def test_own_cells_hold_the_quantiles_of_each_tasks_own_motions():
    """Filed by the own task, cell (k, b) holds the quantiles of the task-k motions' own
    statistics in bin b; filed by the chosen task (as before), those of every update that
    chose k. Either way the threshold is made of the motions as ranked (chosen task)."""
    rng = np.random.default_rng(0)
    ranked, own = labelled(rng, 40)
    mine = Calibration.from_records(ranked, 2, edges=EDGES, own=own, components=TIMING)
    before = Calibration.from_records(ranked, 2, edges=EDGES, components=TIMING)
    assert (mine.cells, before.cells) == ("own", "chosen")
    for k in (0, 1):
        for b, sel in enumerate([slice(0, 4), slice(4, 8)]):
            filed = np.concatenate([v[sel] for _, v, _ in own[k::2]])
            np.testing.assert_allclose(mine.stack[:, k, b], np.quantile(filed, LEVELS, axis=0).T)
            chose = np.concatenate([v[sel][c[sel] == k] for _, v, c in ranked])
            np.testing.assert_allclose(before.stack[:, k, b],
                                       np.quantile(chose, LEVELS, axis=0).T)
    assert mine.threshold != before.threshold


def test_own_cells_keep_the_false_alarms_of_fresh_motions_near_alpha():
    """Split-conformal whatever the filing: fresh motions from the same two-task generator,
    ranked under the chosen task, fire at about alpha = 0.2 (99.9 % bounds of one
    calibration of 100 motions, 250 fresh: sd 0.040 and 0.025); shifted ones nearly always."""
    rng = np.random.default_rng(1)
    ranked, own = labelled(rng, 100)
    cal = Calibration.from_records(ranked, 2, alpha=0.2, edges=EDGES, own=own,
                                   components=TIMING)

    def fires(recs):
        return [min(cal.familiarity(t, v, k) for t, v, k in zip(*r)) < cal.threshold
                for r in recs]

    assert 0.05 < np.mean(fires(labelled(rng, 250)[0])) < 0.35
    assert np.mean(fires(labelled(rng, 50, shift=1.5)[0])) > 0.9


def test_own_records_must_match_the_records():
    rng = np.random.default_rng(2)
    ranked, own = labelled(rng, 6)
    with pytest.raises(ValueError, match="one record per calibration motion"):
        Calibration.from_records(ranked, 2, own=own[:5], components=TIMING)
    with pytest.raises(ValueError, match="statistics per update as in records"):
        Calibration.from_records(ranked, 2, own=[(t, v[:, :1], k) for t, v, k in own],
                                 components=TIMING)
    with pytest.raises(ValueError, match="calibration cells"):
        Calibration(np.zeros(1), np.zeros((2, 1, LEVELS.size)), np.ones((2, 1)), 0.0, 0.5,
                     cells="true")

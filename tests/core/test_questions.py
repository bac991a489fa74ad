"""The familiarity's two questions (sandbox.core.questions): per-motion ranks by known answers."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.core.evidence import COMPONENTS, TIMING
from sandbox.core.questions import combine, groups, motion_quantiles, motion_rank


def test_the_statistics_split_into_the_fit_and_the_where_question():
    assert groups(TIMING) == [[0, 1, 2, 3]]
    assert groups(COMPONENTS) == [[0, 1, 2, 3], [4, 5]]


def test_a_motion_rank_is_the_share_of_calibration_motions_as_low_out_of_n_plus_one():
    lowest = np.array([[1e-1, 1e-2], [1e-2, 1e-3], [1e-3, 1e-4], [1e-4, 1e-5]])
    scores = motion_quantiles(lowest)
    assert scores.shape == (2, 4) and np.all(np.diff(scores, axis=1) > 0)
    assert motion_rank(scores[0], 1e-2) == pytest.approx(3 / 5)   # 1e-2, 1e-3, 1e-4
    assert motion_rank(scores[0], 1e-4) == pytest.approx(1 / 5)
    assert motion_rank(scores[0], 0.5) == 1.0                       # above every motion
    below = motion_rank(scores[0], 1e-8)                            # graded below the lowest
    assert below == pytest.approx(np.log(1e4) / np.log(1e8) / 5)
    assert motion_rank(scores[0], 1e-16) < below


def test_combine_divides_the_lower_share_by_its_weight_and_older_ones_by_sidak():
    scores = motion_quantiles(np.array([[1e-1, 1e-2], [1e-2, 1e-3], [1e-3, 1e-4]]))
    assert combine(np.array([1e-2, 0.5]), scores) == pytest.approx(2 * 2 / 4)
    assert combine(np.array([0.3]), scores) == 0.3                   # one question: as is
    assert combine(np.array([1e-40, 0.5]), None) == pytest.approx(2e-40, rel=1e-9)
    assert motion_quantiles(np.full((3, 2), np.inf)).tolist() == [[0.0], [0.0]]

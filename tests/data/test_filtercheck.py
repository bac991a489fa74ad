"""Tests of sandbox.data.filtercheck (holding tracker frames out to check the filter)."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.filtercheck import holdout_errors
from tests.data.test_filtering import reach_track


def test_holdout_errors_on_a_clean_reach_are_at_the_noise_level():
    rng = np.random.default_rng(8)
    t, _, y = reach_track(rng, noise=0.002)
    smooth, causal, counts = holdout_errors(t, y, every=3, phase_max=0.6)
    hidden = np.arange(t.size)[(t - t[0]) <= 0.6 * (t[-1] - t[0])][3::3]
    assert smooth.size == causal.size == hidden.size
    # a hidden sample carries its own noise (3-D norm ~ 2 mm * 1.6) plus the estimate's error
    assert np.median(smooth) < 0.006 and np.median(causal) < 0.008
    assert np.median(smooth) <= np.median(causal)
    assert counts["rejected"] == 0


def test_holdout_errors_refuses_bad_every():
    with pytest.raises(ValueError, match="every"):
        holdout_errors([0.0, 1.0, 2.0], np.zeros((3, 3)) + 1.0, every=1)

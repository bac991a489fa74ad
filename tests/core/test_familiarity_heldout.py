"""Issue 30: the familiarity's false alarms on unseen normal motions stay at the calibrated
alpha, and simple out-of-distribution motions are flagged before the handover.

Synthetic diverging set (known distributions): the model is fitted and calibrated on one
seed's motions and streams fresh motions of another seed, as a predictor sees them.
"""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.core.familiarity import stream_record
from sandbox.data.synthetic import make_dataset

OPTIONS = {"dow_t": 0.2, "subsample": 5, "n_candidates": 25}
ALPHA = 0.05


@pytest.fixture(scope="module")
def model():
    train = make_dataset("diverging", 20, np.random.default_rng(0))
    # The constant 2 cm floor: under the default jitter floor (33 mm on this set) the rate
    # of the first test is 2 % on this seed (issue 30's calibration target, open).
    model = IProMP(jitter_floor=None).fit(train)
    model.calibrate(train, alpha=ALPHA, **OPTIONS)
    return model


def lowest(model, times, human, until: float = np.inf) -> float:
    """The lowest familiarity of a stream's updates up to ``until`` (s)."""
    at, values, tasks = stream_record(model, times, human, **OPTIONS)
    fam = np.array([model.calibration.familiarity(t, v, k) for t, v, k in zip(at, values, tasks)])
    return float(np.min(fam[(at <= until) & np.isfinite(fam)], initial=1.0))   # NaN: not ranked


@pytest.mark.slow
def test_unseen_normal_motions_fire_at_alpha(model):
    """300 fresh motions (another seed) fire at about alpha. One calibration of 100 motions
    fires at a rate spread by about 2.5 points around alpha (the Beta of its threshold's
    rank, 2.2 points, and the binomial of 300 fresh motions, 1.3; docs, Results), so one
    is held to twice that spread (some, and at most 2 alpha); the issue's ±1.5 points is
    met by the mean over calibrations (docs, Results: 4.9 % over three seeds, 900 motions;
    this seed fires at 2.7 % with own-task cells, 3.7 % with the chosen task's)."""
    fresh = make_dataset("diverging", 60, np.random.default_rng(123))
    fired = [lowest(model, d.times - d.times[0], d.human) < model.calibration.threshold
             for d in fresh]
    assert 0.0 < np.mean(fired) <= 2 * ALPHA


@pytest.mark.slow
def test_a_motion_slowed_to_half_speed_or_paused_is_flagged_before_the_handover(model):
    rng = np.random.default_rng(7)
    slow, paused = [], []
    for d in make_dataset("diverging", 4, np.random.default_rng(321)):
        t = d.times - d.times[0]
        end = float(t[model.motion_end(t, d.robot, d.human)])
        slow.append(lowest(model, 2 * t, d.human, 2 * end))
        i, dt = int(np.searchsorted(t, 0.4 * end)), 0.01
        held = d.human[i] + 0.002 * rng.standard_normal((150, d.human.shape[1]))
        tp = np.r_[t[:i], t[i] + dt * np.arange(1, 151), t[i:] + 1.5 + dt]
        paused.append(lowest(model, tp, np.vstack([d.human[:i], held, d.human[i:]]), end + 1.5))
    threshold = model.calibration.threshold
    assert np.mean(np.array(slow) < threshold) >= 0.8
    assert np.mean(np.array(paused) < threshold) >= 0.8

"""The sessions' tails: each kind shows its signature in the data, and the recording shows it."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic import TrackerModel, make_dataset
from sandbox.data.synthetic.base import sample_times
from sandbox.data.synthetic.human import Reach, reach_positions
from sandbox.data.synthetic.session import NO_TAIL, TAILS, draw_session
from sandbox.data.synthetic.tails import (
    draw_tail,
    freeze_row,
    frozen,
    tail_positions,
    tail_rng,
)

SEEDS = (0, 1)


def _demos(tail: str, seed: int, **kw):
    return make_dataset("objects", 3, np.random.default_rng(seed),
                        session=draw_session(10 + seed, tail=tail), **kw)


def _after(d, t: float) -> np.ndarray:
    return d.times >= t - 1e-9


def _approach(d) -> np.ndarray:
    """Unit vector from the hand's start (first row) to its end point."""
    v = d.meta["hand_end"] - d.meta["clean_human"][0]
    return v / np.linalg.norm(v)


def _meeting(d) -> int:
    return int(np.flatnonzero(d.times == d.meta["meeting_time"])[0])


@pytest.mark.parametrize("tail", TAILS)
def test_the_recording_runs_on_after_the_robot_stops(tail):
    for d in _demos(tail, 0):
        assert d.times[-1] - d.meta["robot_time"][1] >= 0.4 - 1e-9
        assert d.meta["session"]["tail"] == tail


@pytest.mark.parametrize("seed", SEEDS)
def test_stop_wait_stops_short_of_the_end_and_waits_still_where_the_robot_meets_it(seed):
    for d in _demos("stop_wait", seed):
        clean, rest = d.meta["clean_human"], _after(d, d.meta["reach_time"][1])
        assert np.ptp(clean[rest], axis=0).max() < 1e-9                   # still
        short = d.meta["hand_end"] - clean[-1]
        assert 0.03 - 1e-9 <= np.linalg.norm(short) <= 0.08 + 1e-9
        assert short @ _approach(d) > 0.9 * np.linalg.norm(short)        # back along the approach
        shift = d.meta["handover_target"] - clean[-1] - np.array(d.meta["session"]["object_offset"])
        assert np.abs(shift).max() < 0.05                # the robot meets the stopped hand


@pytest.mark.parametrize("seed", SEEDS)
def test_linger_wanders_a_little_around_the_end(seed):
    for d in _demos("linger", seed):
        held = d.meta["clean_human"][_after(d, d.meta["reach_time"][1])]
        wander = np.linalg.norm(held - d.meta["hand_end"], axis=1)
        assert wander.max() <= 0.03 + 1e-9
        assert wander.max() > 0.002                                       # it does wander


@pytest.mark.parametrize("seed", SEEDS)
def test_drift_back_leaves_the_meeting_point_after_the_release(seed):
    for d in _demos("drift_back", seed):
        row = _meeting(d)
        met = d.meta["tracked_clean"][row]
        assert np.linalg.norm(d.meta["tracked_clean"][-1] - met) > 0.10
        assert np.linalg.norm(np.nanmedian(d.human[-5:], axis=0) - met) > 0.10
        # Back toward the start.
        assert (d.meta["clean_human"][-1] - d.meta["clean_human"][row]) @ _approach(d) < -0.09


@pytest.mark.parametrize("seed", SEEDS)
def test_drift_back_starts_0_1_to_0_3_s_after_the_meeting(seed):
    # The same demonstrations without a tail: the hand is the same until the release.
    for d, plain in zip(_demos("drift_back", seed), _demos(NO_TAIL, seed), strict=True):
        n = min(len(d.times), len(plain.times))
        apart = np.linalg.norm(d.meta["clean_human"][:n] - plain.meta["clean_human"][:n], axis=1)
        release = d.times[np.flatnonzero(apart > 1e-9)[0]] - d.meta["meeting_time"]
        assert 0.1 - 1e-9 <= release <= 0.3 + 0.011


@pytest.mark.parametrize("seed", SEEDS)
def test_overshoot_passes_the_end_and_is_back_before_the_robot_arrives(seed):
    for d in _demos("overshoot", seed):
        beyond = (d.meta["clean_human"] - d.meta["hand_end"]) @ _approach(d)
        assert beyond.max() > 0.03 - 0.005
        robot_off = d.meta["robot_time"][1]
        back = d.meta["clean_human"][_after(d, robot_off)]
        assert np.linalg.norm(back - d.meta["hand_end"], axis=1).max() < 0.03


@pytest.mark.parametrize("seed", SEEDS)
def test_freeze_repeats_the_last_frame_to_the_end_while_the_hand_moves_on(seed):
    for d in _demos("freeze", seed, observe="hand,arm"):
        same = np.all(d.human == d.human[-1], axis=1)
        first = len(same) - np.argmin(same[::-1])                # first row of the last run
        # From 70-95 % of the recording on: longer than any sample-and-hold step (~4 rows).
        assert 0.69 <= (d.times[first] - d.times[0]) / d.duration <= 0.951
        assert d.times[-1] - d.times[first] >= 0.05 * d.duration - 0.011
        assert len(d.times) - first > 6
        assert np.all(d.human[first:, 3:] == d.human[-1, 3:])           # the arm froze too
        clean = d.meta["clean_human"][first - 1:]
        assert np.ptp(clean, axis=0).max() > 1e-4                        # the true hand moves on


def test_no_tail_and_freeze_keep_the_clean_reach():
    reach = Reach(points=np.array([[1.1, -0.1, 0.25], [0.8, 0.2, 0.2]]), t_on=0.0, t_off=1.0,
                  drift=np.array([0.01, 0.0, 0.0]))
    times = sample_times(2.0, 100.0)
    for kind in (NO_TAIL, "freeze"):
        tail = draw_tail(kind, tail_rng(0))
        np.testing.assert_array_equal(tail_positions(reach, times, tail, 1.2),
                                      reach_positions(reach, times))


def test_frozen_copies_and_freeze_row_is_inside():
    times = sample_times(1.0, 100.0)
    tail = draw_tail("freeze", tail_rng(3))
    row = freeze_row(times, tail)
    assert 0.7 * len(times) - 2 <= row <= len(times) - 2
    x = np.arange(len(times) * 3, dtype=float).reshape(-1, 3)
    out = frozen(x, row)
    assert np.all(out[row:] == x[row - 1]) and np.array_equal(out[:row], x[:row])
    assert x[-1, 0] == 3 * len(times) - 3                                 # input untouched
    assert freeze_row(times, draw_tail("linger", tail_rng(3))) is None


def test_the_tail_stream_is_its_own():
    a = np.random.default_rng(5)
    draw_tail("linger", tail_rng(5))
    assert a.random() == np.random.default_rng(5).random()
    assert tail_rng(5).random() != np.random.default_rng(5).random()


@pytest.mark.parametrize("tail", TAILS)
def test_tails_observe_clean_without_artefacts_but_freeze(tail):
    for d in _demos(tail, 1, tracker=TrackerModel.clean()):
        same = np.allclose(d.human, d.meta["tracked_clean"], atol=1e-12)
        assert same == (tail != "freeze")

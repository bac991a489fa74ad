"""Realism statistics: the robust estimator, and synthetic `objects` vs the recordings."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic import compare_realism, objects_demos, realism_stats
from sandbox.data.synthetic.base import minimum_jerk
from sandbox.data.synthetic.realism import (
    STATISTICS,
    format_realism,
    smooth_track,
    track_stats,
    valid_rows,
)

JOINTS = ["left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2"]
HAND = ["human_left_hand_x", "human_left_hand_y", "human_left_hand_z"]
START, END = np.array([1.1, -0.12, 0.25]), np.array([0.8, 0.2, 0.2])


def _reach(duration=2.0, reach_s=1.0, rate=100.0):
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    return t, START + np.outer(minimum_jerk(t / reach_s), END - START)


def _demo(t, human, task="a"):
    return Demonstration(times=t, human=human, robot=np.zeros((t.size, 7)), task=task)


def _read_trial(path: Path) -> Demonstration:
    """One recorded trial read with numpy; of rows sharing a timestamp the last is kept."""
    with open(path, newline="") as f:
        header = next(csv.reader(f))
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    col = {name: i for i, name in enumerate(header)}
    t = table[:, col["t"]]
    last = np.r_[np.diff(t) > 0, True]
    return Demonstration(
        times=t[last], human=table[last][:, [col[c] for c in HAND]],
        robot=table[last][:, [col[c] for c in JOINTS]], task=path.parent.name, source=str(path),
    )


def test_minimum_jerk_reach_gives_its_known_statistics():
    t, hand = _reach()
    stats = track_stats(t, hand)
    distance = np.linalg.norm(END - START)
    assert stats["duration"] == pytest.approx(2.0)
    assert stats["path_length"] == pytest.approx(distance, rel=0.01)
    # the filters flatten the peak of 1.875 D / T a little
    assert stats["peak_speed"] == pytest.approx(1.875 * distance / 1.0, rel=0.08)
    assert 0.6 < stats["reach_time"] < 0.85  # 90 % of the way at 77 % of the reach


def test_estimator_ignores_steps_repeats_short_jumps_and_bad_rows():
    t, hand = _reach()
    base = track_stats(t, hand)
    held = hand[(np.arange(t.size) // 3) * 3]  # 33 Hz sample-and-hold
    jumpy = held.copy()
    jumpy[150:155] += [0.0, 0.0, 0.12]  # a 5-row 12 cm excursion during the hold
    jumpy[[60, 61]] = np.nan
    jumpy[[90]] = 0.0
    t_rep = t.copy()
    t_rep[100] = t_rep[99]  # a repeated timestamp
    stats = track_stats(t_rep, jumpy)
    for key in ("path_length", "peak_speed", "reach_time"):
        assert stats[key] == pytest.approx(base[key], rel=0.05), key
    kept_t, kept = valid_rows(t_rep, jumpy)
    assert kept_t.size == t.size - 4 and np.all(np.diff(kept_t) > 0)
    assert np.isfinite(kept).all()


def test_smooth_track_is_on_a_100hz_grid_and_refuses_empty_tracks():
    t, hand = _reach()
    grid, track = smooth_track(t, hand)
    assert np.allclose(np.diff(grid), 0.01) and track.shape == (grid.size, 3)
    with pytest.raises(ValueError, match="valid rows"):
        smooth_track(t, np.zeros_like(hand))
    with pytest.raises(ValueError, match="human"):
        smooth_track(t, hand[:, :2])


def test_spreads_are_measured_per_task():
    t, hand = _reach()
    demos = [_demo(t, hand + [0.0, 0.0, dz], task) for task, dz in
             (("a", 0.0), ("a", 0.02), ("a", 0.04), ("b", 0.5), ("b", 0.5))]
    stats = realism_stats(demos)
    assert np.allclose(stats["end_spread"], [0.02, 0.0, 0.02, 0.0, 0.0])
    assert np.allclose(stats["start_spread"], stats["end_spread"])
    assert stats["n"] == 5 and set(stats["median"]) == set(STATISTICS)


def test_compare_is_one_for_the_same_set_and_accepts_computed_stats():
    demos = objects_demos(3, np.random.default_rng(0))
    stats = realism_stats(demos)
    table = compare_realism(demos, stats)
    assert set(table) == set(STATISTICS)
    assert all(row["ratio"] == pytest.approx(1.0) for row in table.values())
    assert "peak_speed" in format_realism(table)


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="Demonstration"):
        realism_stats([])
    t, hand = _reach()
    two_d = Demonstration(times=t, human=hand[:, :2], robot=np.zeros((t.size, 7)), task="a")
    with pytest.raises(ValueError, match="P = 3"):
        realism_stats([two_d])


@pytest.fixture(scope="module")
def recorded_stats(recorded_dir):
    demos = [_read_trial(p) for p in sorted(Path(recorded_dir).glob("*/*.csv"))]
    assert len(demos) == 174
    return realism_stats(demos)


def test_synthetic_objects_resemble_the_recordings(recorded_stats):
    synthetic = objects_demos(40, np.random.default_rng(0))
    table = compare_realism(synthetic, recorded_stats)
    print("\n" + format_realism(table))
    for key, row in table.items():
        assert 0.75 <= row["ratio"] <= 1.25, (key, row)


@pytest.mark.parametrize("seed", [1, 2])
def test_realism_holds_for_other_seeds(recorded_stats, seed):
    table = compare_realism(objects_demos(40, np.random.default_rng(seed)), recorded_stats)
    assert all(0.75 <= row["ratio"] <= 1.25 for row in table.values()), table

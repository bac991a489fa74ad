"""Realism statistics: the robust estimator; synthetic `objects` vs the recordings (hand, arm)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from sandbox.data.demonstration import Demonstration
from sandbox.data.spec import ARM
from sandbox.data.spec import HAND as HAND_MODALITY
from sandbox.data.synthetic import (
    arm_realism_stats,
    compare_arm_realism,
    compare_realism,
    objects_demos,
    realism_stats,
)
from sandbox.data.synthetic.base import minimum_jerk
from sandbox.data.synthetic.realism import (
    ARM_STATISTICS,
    ARM_TARGETS,
    STATISTICS,
    arm_track_stats,
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
    """One recorded trial (hand and arm) read with numpy; of rows sharing a timestamp the last
    is kept."""
    with open(path, newline="") as f:
        header = next(csv.reader(f))
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    col = {name: i for i, name in enumerate(header)}
    t = table[:, col["t"]]
    last = np.r_[np.diff(t) > 0, True]
    return Demonstration(
        times=t[last], human=table[last][:, [col[c] for c in HAND + list(ARM.dims)]],
        robot=table[last][:, [col[c] for c in JOINTS]], task=path.parent.name, source=str(path),
        modalities=(HAND_MODALITY, ARM),
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
def recorded_demos(recorded_dir):
    demos = [_read_trial(p) for p in sorted(Path(recorded_dir).glob("*/*.csv"))]
    assert len(demos) == 174
    return demos


@pytest.fixture(scope="module")
def recorded_stats(recorded_demos):
    return realism_stats(recorded_demos)


@pytest.fixture(scope="module")
def recorded_arm_stats(recorded_demos):
    return arm_realism_stats(recorded_demos)


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


def _arm_demo(t, hand, elbow, shoulder, task="a"):
    return Demonstration(times=t, human=np.column_stack([hand, elbow, shoulder]),
                         robot=np.zeros((t.size, 7)), task=task, modalities=(HAND_MODALITY, ARM))


def test_arm_statistics_of_a_known_arm():
    t, hand = _reach()
    elbow = hand + [0.1, 0.2, -0.05]  # rigidly attached: same path, 0.229 m away
    shoulder = np.tile([1.35, 0.0, 0.34], (t.size, 1))
    stats = arm_track_stats(t, hand, np.column_stack([elbow, shoulder]))
    assert stats["elbow_path"] == pytest.approx(np.linalg.norm(END - START), rel=0.01)
    assert stats["elbow_hand"] == pytest.approx(np.linalg.norm([0.1, 0.2, -0.05]))
    assert stats["shoulder_path"] == pytest.approx(0.0, abs=1e-9)
    assert stats["shoulder_travel"] == pytest.approx(0.0, abs=1e-9)
    assert stats["upper_arm"] == pytest.approx(np.median(np.linalg.norm(elbow - shoulder, axis=1)))
    demos = [_arm_demo(t, hand, elbow, shoulder + [0.0, dy, 0.0], task) for task, dy in
             (("a", 0.0), ("a", 0.02), ("a", 0.04), ("b", 0.5))]
    table = arm_realism_stats(demos)
    assert np.allclose(table["shoulder_spread"], [0.02, 0.0, 0.02, 0.0])
    assert table["n"] == 4 and set(table["median"]) == set(ARM_STATISTICS)
    # the hand statistics read the hand modality of such demonstrations
    assert realism_stats(demos)["median"]["path_length"] == pytest.approx(
        realism_stats([_demo(t, hand)])["median"]["path_length"])


def test_arm_statistics_ignore_tracker_glitches():
    t, hand = _reach()
    elbow, shoulder = hand + [0.1, 0.2, -0.05], np.tile([1.35, 0.0, 0.34], (t.size, 1))
    base = arm_track_stats(t, hand, np.column_stack([elbow, shoulder]))
    arm = np.column_stack([elbow, shoulder])[(np.arange(t.size) // 3) * 3]
    arm[150:155, :3] += [0.0, 0.0, 0.12]
    arm[[60, 61]] = np.nan
    stats = arm_track_stats(t, hand, arm)
    for key in ("elbow_path", "elbow_hand", "shoulder_path"):
        assert stats[key] == pytest.approx(base[key], rel=0.05, abs=1e-3), key


def test_arm_statistics_need_the_arm():
    t, hand = _reach()
    with pytest.raises(ValueError, match="'arm'"):
        arm_realism_stats([_demo(t, hand)])
    with pytest.raises(ValueError, match="Demonstration"):
        arm_realism_stats([])


def test_synthetic_arm_resembles_the_recordings(recorded_arm_stats):
    synthetic = objects_demos(40, np.random.default_rng(0), observe="hand,arm")
    table = compare_arm_realism(synthetic, recorded_arm_stats)
    print("\n" + format_realism(table))
    for key in ARM_TARGETS:
        assert 0.75 <= table[key]["ratio"] <= 1.25, (key, table[key])
    # reported, not a target: the tracker's upper arm is shorter than an anatomical one
    assert table["upper_arm"]["recorded"] < table["upper_arm"]["synthetic"]
    assert compare_realism(synthetic, realism_stats(synthetic))["duration"]["ratio"] == 1.0


@pytest.mark.parametrize("seed", [1, 2])
def test_arm_realism_holds_for_other_seeds(recorded_arm_stats, seed):
    synthetic = objects_demos(40, np.random.default_rng(seed), observe="hand,arm")
    table = compare_arm_realism(synthetic, recorded_arm_stats)
    assert all(0.75 <= table[key]["ratio"] <= 1.25 for key in ARM_TARGETS), table

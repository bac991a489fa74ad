"""The synthetic data package: public names, registry, reproducibility, speed, errors."""

from __future__ import annotations

import time

import numpy as np
import pytest

from sandbox.data.demonstration import Demonstration
from sandbox.data.synthetic import (
    DATASETS,
    HAND_START,
    HUMAN_NAMES,
    ROBOT_NAMES,
    make_dataset,
    minimum_jerk,
    two_task_demos,
)
from sandbox.data.synthetic.base import sample_times, skewed_minimum_jerk
from sandbox.robot import Q_HOME

TASKS = {
    "two_task": ["left", "right"],
    "diverging": ["left", "right", "up", "down", "straight"],
    "objects": ["box", "glasses_case", "tape"],
}


def _same(a: Demonstration, b: Demonstration) -> bool:
    return (
        a.task == b.task
        and np.array_equal(a.times, b.times)
        and np.array_equal(a.human, b.human, equal_nan=True)
        and np.array_equal(a.robot, b.robot)
    )


def test_public_names_keep_their_values():
    assert HUMAN_NAMES == ("human_left_hand_x", "human_left_hand_y", "human_left_hand_z")
    assert len(ROBOT_NAMES) == 7 and ROBOT_NAMES[0] == "left_s0"
    assert Q_HOME.shape == (7,) and HAND_START.shape == (3,)


def test_datasets_lists_every_registered_name():
    assert set(DATASETS) == set(TASKS)
    assert DATASETS[0] == "two_task"


@pytest.mark.parametrize("name", sorted(TASKS))
def test_make_dataset_gives_n_per_task_of_each_task_in_order(name):
    demos = make_dataset(name, 2, np.random.default_rng(1))
    assert [d.task for d in demos] == [t for t in TASKS[name] for _ in range(2)]
    for d in demos:
        assert d.human.shape == (d.n_steps, 3) and d.robot.shape == (d.n_steps, 7)
        assert d.human_names == HUMAN_NAMES and d.robot_names == ROBOT_NAMES
        assert 1.7 <= d.duration <= 4.0


@pytest.mark.parametrize("name", sorted(TASKS))
def test_same_seed_gives_identical_demos_and_another_seed_does_not(name):
    a = make_dataset(name, 2, np.random.default_rng(7))
    b = make_dataset(name, 2, np.random.default_rng(7))
    c = make_dataset(name, 2, np.random.default_rng(8))
    assert all(_same(x, y) for x, y in zip(a, b, strict=True))
    assert not any(_same(x, y) for x, y in zip(a, c, strict=True))


def test_make_dataset_passes_options_to_the_generator():
    demos = make_dataset("two_task", 2, np.random.default_rng(0), rate_hz=50.0)
    assert np.allclose(np.diff(demos[0].times)[:-1], 0.02)


def test_unknown_dataset_name_lists_the_known_ones():
    with pytest.raises(ValueError, match="two_task.*diverging.*objects"):
        make_dataset("nope", 2, np.random.default_rng(0))


@pytest.mark.parametrize("name", sorted(TASKS))
def test_bad_rng_or_count_is_refused(name):
    with pytest.raises(ValueError, match="rng"):
        make_dataset(name, 2, 0)
    with pytest.raises(ValueError, match="n_per_task"):
        make_dataset(name, 0, np.random.default_rng(0))


def test_minimum_jerk_known_values_and_zero_end_velocity():
    s = np.array([0.0, 0.5, 1.0, -1.0, 2.0])
    assert np.allclose(minimum_jerk(s), [0.0, 0.5, 1.0, 0.0, 1.0])
    eps = 1e-6
    assert abs(minimum_jerk(np.array([eps]))[0]) / eps < 1e-6
    assert abs(1.0 - minimum_jerk(np.array([1 - eps]))[0]) / eps < 1e-6


def test_skew_moves_the_speed_peak_earlier_and_keeps_the_ends():
    s = np.linspace(0.0, 1.0, 2001)
    for skew, lo, hi in ((1.0, 0.49, 0.51), (0.8, 0.35, 0.42)):
        u = skewed_minimum_jerk(s, skew)
        assert u[0] == 0.0 and u[-1] == 1.0 and np.all(np.diff(u) >= 0)
        assert lo <= s[np.argmax(np.gradient(u, s))] <= hi


def test_sample_times_end_exactly_at_the_duration():
    for duration in (1.7, 2.003, 2.2049, 3.99):
        t = sample_times(duration, 100.0)
        assert t[0] == 0.0 and t[-1] == duration and np.all(np.diff(t) > 0)


def test_two_task_keeps_its_behaviour():
    demos = two_task_demos(10, np.random.default_rng(0))
    ends = {task: np.mean([d.human[-1] for d in demos if d.task == task], axis=0)
            for task in ("left", "right")}
    assert abs((ends["left"] - ends["right"])[1] - 0.30) < 0.05
    assert all(np.allclose(d.robot[0], Q_HOME, atol=1e-9) for d in demos)


def test_a_hundred_paired_demos_are_generated_and_timed(record_property):
    start = time.perf_counter()
    demos = make_dataset("diverging", 20, np.random.default_rng(0))
    elapsed = time.perf_counter() - start
    record_property("seconds_for_100_paired_diverging_demos", round(elapsed, 3))
    print(f"100 paired diverging demos in {elapsed:.2f} s")
    assert len(demos) == 100
    assert all(d.meta["hand_end"].shape == (3,) for d in demos)

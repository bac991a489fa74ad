"""Task families: diverging tasks (Experiment 2) and objects (Experiment 1)."""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest

from sandbox.data.synthetic import TrackerModel, diverging_demos, objects_demos
from sandbox.data.synthetic.families import (
    DIRECTIONS,
    DIVERGING_VARIABILITY,
    OBJECTS,
    diverging_specs,
)
from sandbox.data.synthetic.human import reach_positions
from sandbox.data.synthetic.tasks import TaskSpec, Variability, draw_demo, make_reach


@pytest.fixture(scope="module")
def diverging():
    return diverging_demos(12, np.random.default_rng(0), tracker=TrackerModel.clean())


@pytest.fixture(scope="module")
def objects():
    return objects_demos(12, np.random.default_rng(0))


def _mean_on_phase(demos, phase):
    """Mean clean hand position per task at the given phases, {task: (len(phase), 3)}."""
    out = {}
    for d in demos:
        path = np.column_stack([np.interp(phase, d.phase, d.meta["clean_human"][:, j])
                                for j in range(3)])
        out.setdefault(d.task, []).append(path)
    return {task: np.mean(paths, axis=0) for task, paths in out.items()}


def test_diverging_tasks_share_their_path_until_about_half_way(diverging):
    early = _mean_on_phase(diverging, np.linspace(0.0, 0.45, 10))
    pooled = np.mean(list(early.values()), axis=0)
    for path in early.values():
        assert np.linalg.norm(path - pooled, axis=1).max() < 0.03
    for d in diverging:
        assert 0.45 <= d.meta["divergence_time"] / d.duration <= 0.55


def test_diverging_end_points_are_at_least_15cm_apart(diverging):
    ends = _mean_on_phase(diverging, np.array([1.0]))
    for a, b in combinations(ends, 2):
        assert np.linalg.norm(ends[a] - ends[b]) >= 0.15, (a, b)
    straight = ends["straight"][0]
    assert ends["left"][0][1] > straight[1] + 0.1 and ends["right"][0][1] < straight[1] - 0.1
    assert ends["up"][0][2] > straight[2] + 0.1 and ends["down"][0][2] < straight[2] - 0.1


def test_under_one_draw_all_directions_coincide_exactly_before_the_divergence():
    specs = diverging_specs()
    draw = draw_demo(specs[0], DIVERGING_VARIABILITY, np.random.default_rng(5))
    times = np.linspace(0.0, draw.duration, 300)
    paths = [reach_positions(make_reach(s, draw, DIVERGING_VARIABILITY), times) for s in specs]
    before = times <= draw.t_div
    for path in paths[1:]:
        assert np.array_equal(path[before], paths[0][before])
        assert np.linalg.norm(path[-1] - paths[0][-1]) >= 0.15


def test_diverging_directions_and_branch_size_are_options():
    demos = diverging_demos(2, np.random.default_rng(1), directions=("up", "straight"),
                            branch_m=0.25)
    assert [d.task for d in demos] == ["up", "up", "straight", "straight"]
    ends = _mean_on_phase(demos, np.array([1.0]))
    assert ends["up"][0][2] - ends["straight"][0][2] > 0.18


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"directions": ("left", "sideways")}, "directions"),
        ({"directions": ("left", "left")}, "directions"),
        ({"directions": "left"}, "directions"),
        ({"branch_m": 0.0}, "branch_m"),
    ],
)
def test_bad_diverging_options_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        diverging_demos(2, np.random.default_rng(0), **kwargs)


def test_objects_are_handed_over_at_distinct_places_and_heights(objects):
    assert {d.task for d in objects} == {"box", "glasses_case", "tape"}
    means = {s.name: s.end for s in OBJECTS}
    for a, b in combinations(means, 2):
        assert np.linalg.norm(means[a] - means[b]) >= 0.08
        assert abs(means[a][2] - means[b][2]) >= 0.05
    ends = {}
    for d in objects_demos(60, np.random.default_rng(2), tracker=TrackerModel.clean()):
        ends.setdefault(d.task, []).append(d.meta["hand_end"])
    heights = {task: np.median(np.array(e)[:, 2]) for task, e in ends.items()}
    assert heights["box"] < heights["tape"] < heights["glasses_case"]
    for spec in OBJECTS:
        assert np.linalg.norm(np.median(ends[spec.name], axis=0) - spec.end) < 0.04


def test_objects_start_near_the_recorded_start_and_end_near_the_recorded_end(objects):
    assert all(d.meta["divergence_time"] is None for d in objects)
    starts = np.array([d.meta["clean_human"][0] for d in objects])
    ends = np.array([d.meta["hand_end"] for d in objects])
    assert np.linalg.norm(np.median(starts, axis=0) - [1.10, -0.12, 0.25]) < 0.03
    assert np.linalg.norm(np.median(ends, axis=0) - [0.81, 0.2, 0.2]) < 0.06


def test_noise_switches_leave_the_motion_itself_unchanged():
    noisy = objects_demos(2, np.random.default_rng(4))
    clean = objects_demos(2, np.random.default_rng(4), tracker=TrackerModel.clean())
    for a, b in zip(noisy, clean, strict=True):
        assert np.array_equal(a.meta["clean_human"], b.meta["clean_human"])
        assert np.array_equal(a.robot, b.robot)
        assert np.array_equal(b.human, b.meta["clean_human"])
        assert not np.array_equal(a.human, b.human)


def test_task_spec_and_variability_validate_their_fields():
    with pytest.raises(ValueError, match="end"):
        TaskSpec("x", end=(0.8, 0.2))
    with pytest.raises(ValueError, match="name"):
        TaskSpec("", end=(0.8, 0.2, 0.2))
    with pytest.raises(ValueError, match="skew"):
        Variability(skew=0.2)
    with pytest.raises(ValueError, match="wobble_std"):
        Variability(wobble_std=(0.1,))
    with pytest.raises(ValueError, match="reach_off"):
        Variability(reach_off=(0.1, 0.0))


def test_directions_table_matches_the_base_frame():
    assert DIRECTIONS["left"] == (0.0, 1.0, 0.0) and DIRECTIONS["up"] == (0.0, 0.0, 1.0)

"""Meeting geometry learned from the demos: known answers, its shift with the tracker, errors."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.core.fitting import motion_end
from sandbox.data.geometry import (
    DEFAULT_OFFSET,
    GEOMETRY_KEY,
    MeetingGeometry,
    attach_geometry,
    geometry_of,
    learn_geometry,
    meeting_offset,
)
from sandbox.data.synthetic import make_dataset
from sandbox.robot import TIP_LINK, BaxterKinematics


@pytest.fixture(scope="module")
def demos():
    return make_dataset("diverging", 4, np.random.default_rng(5))


def _with_hand(demo, hand):
    return dataclasses.replace(demo, human=hand)


def _met_at(demo, offset, rng):
    """``demo`` whose hand approaches along ``offset`` and, from the robot's arrival on,
    holds the object at the fingertip: hand = fingertip - ``offset`` (0.5 mm noise)."""
    tip = BaxterKinematics().fk(demo.robot, link=TIP_LINK)
    arrival = motion_end(demo.times, demo.robot, 0.05)
    left = np.clip((arrival - np.arange(len(tip))) / max(arrival, 1), 0.0, 1.0)
    away = 0.3 * left[:, None] * offset / np.linalg.norm(offset)
    return _with_hand(demo, tip - offset - away + rng.normal(0, 5e-4, tip.shape))


def test_a_known_offset_is_recovered_per_task(demos):
    rng = np.random.default_rng(0)
    truth = {task: rng.uniform(-0.08, 0.08, 3) for task in dict.fromkeys(d.task for d in demos)}
    made = [_met_at(d, truth[d.task], rng) for d in demos]
    geometry = learn_geometry(made)
    assert geometry.source == "learned"
    for task, offset in truth.items():
        np.testing.assert_allclose(geometry.offset(task), offset, atol=3e-3)
        assert geometry.tasks[task].count == 4
        cov = geometry.tasks[task].cov
        np.testing.assert_allclose(cov, cov.T)
        assert np.linalg.eigvalsh(cov).min() >= -1e-15


def test_meeting_is_the_fingertip_nearest_the_hand(demos):
    demo = _met_at(demos[0], np.array([0.02, 0.0, -0.01]), np.random.default_rng(1))
    hand = demo.human.copy()
    hand[:10] = np.nan                       # dropouts are skipped
    offset, index = meeting_offset(demo.times, hand, demo.robot)
    tip = BaxterKinematics().fk(demo.robot, link=TIP_LINK)
    distance = np.linalg.norm(tip - hand, axis=1)
    assert index == int(np.nanargmin(distance))
    np.testing.assert_allclose(offset, tip[index] - hand[index])


def test_a_tracker_frame_offset_moves_the_geometry_by_its_opposite(demos):
    """The same handovers seen by a tracker shifted by c: the offset moves by -c."""
    shift = np.array([0.04, -0.03, 0.02])
    before = learn_geometry(demos)
    after = learn_geometry([_with_hand(d, d.human + shift) for d in demos])
    for task in before.tasks:
        np.testing.assert_allclose(after.offset(task), before.offset(task) - shift, atol=1e-12)


def test_synthetic_demos_meet_at_the_generators_offset(demos):
    """The generator's fingertip meets the hand at GRASP_OFFSET plus a small per-demo shift."""
    geometry = learn_geometry(demos)
    for task in geometry.tasks:
        assert np.linalg.norm(geometry.offset(task) - DEFAULT_OFFSET) < 0.03


def test_the_geometry_survives_the_model_file(demos, tmp_path):
    model = attach_geometry(IProMP(n_basis=11).fit(demos), demos)
    model.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    geometry, note = geometry_of(loaded)
    assert note is None
    for task, g in learn_geometry(demos).tasks.items():
        np.testing.assert_array_equal(geometry.tasks[task].mean, g.mean)
        np.testing.assert_array_equal(geometry.tasks[task].cov, g.cov)


def test_a_model_without_geometry_uses_the_default_and_says_so(demos, tmp_path):
    model = IProMP(n_basis=11).fit(demos)            # as saved before the geometry existed
    model.save(tmp_path / "old.npz")
    loaded = IProMP.load(tmp_path / "old.npz")
    assert loaded.session == {}
    geometry, note = geometry_of(loaded)
    assert geometry.source == "default" and "no meeting geometry" in note
    np.testing.assert_array_equal(geometry.offset("left"), DEFAULT_OFFSET)
    with pytest.warns(UserWarning, match="no meeting geometry"):
        geometry_of(loaded, warn=True)


def test_a_refit_forgets_the_old_geometry(demos):
    model = attach_geometry(IProMP(n_basis=11).fit(demos), demos)
    assert GEOMETRY_KEY in model.session
    model.fit(demos)
    assert model.session == {}


def test_data_whose_robot_does_not_reach_the_hand_keeps_the_default():
    two_task = make_dataset("two_task", 3, np.random.default_rng(0))
    assert learn_geometry(two_task).source == "default"
    model = attach_geometry(IProMP(n_basis=11).fit(two_task), two_task)
    assert GEOMETRY_KEY not in model.session


def test_an_offset_beyond_30_cm_names_the_trials(demos):
    bad = [_with_hand(d, d.human * 1000.0) if i == 2 else d for i, d in enumerate(demos)]
    with pytest.raises(ValueError, match=r"farther.*" + demos[2].source.replace("[", r"\[")
                       .replace("]", r"\]")) as info:
        learn_geometry(bad)
    assert "\n" not in str(info.value)


def test_a_task_without_a_robot_that_reaches_the_hand_is_named(demos):
    mixed = [dataclasses.replace(d, meta={**d.meta, "robot_meets_hand": False})
             if d.task == "up" else d for d in demos]
    with pytest.raises(ValueError, match=r"tasks \['up'\].*robot trajectory"):
        learn_geometry(mixed)


@pytest.mark.parametrize("entry", [
    None, {}, {"tasks": {}}, {"tasks": {"a": {"mean": [0, 0, 0]}}},
    {"tasks": {"a": {"mean": [0.5, 0, 0], "cov": np.eye(3).tolist(), "count": 2}}},
    {"tasks": {"a": {"mean": [0, 0, 0], "cov": (-np.eye(3)).tolist(), "count": 2}}},
    {"tasks": {"a": {"mean": [0, 0, np.nan], "cov": np.eye(3).tolist(), "count": 2}}},
    {"tasks": {"a": {"mean": [0, 0, 0], "cov": np.eye(3).tolist(), "count": -1}}},
])
def test_a_malformed_stored_geometry_is_refused(entry):
    with pytest.raises(ValueError):
        MeetingGeometry.from_dict(entry)


def test_a_learned_geometry_refuses_an_unknown_task(demos):
    with pytest.raises(ValueError, match="tasks with a learned meeting geometry"):
        learn_geometry(demos).offset("sideways")


def test_a_motion_of_no_task_gets_the_offset_pooled_over_the_tasks(demos):
    from sandbox.episodes.scenarios import grasp_options

    geometry = learn_geometry(demos)
    offsets = np.array([g.mean for g in geometry.tasks.values()])
    np.testing.assert_allclose(geometry.pooled(), offsets.mean(axis=0))   # 4 demos each
    model = attach_geometry(IProMP(n_basis=11).fit(demos), demos)
    np.testing.assert_allclose(grasp_options(model, task="scripted")["grasp_offset"],
                               geometry.pooled())
    assert grasp_options(model, task="up")["grasp_offset"] == geometry.offsets()
    np.testing.assert_array_equal(MeetingGeometry.default(["a"]).pooled(), DEFAULT_OFFSET)


def test_a_task_whose_hand_was_never_tracked_is_named(demos):
    lost = [_with_hand(d, np.full_like(d.human, np.nan)) if d.task == "down" else d
            for d in demos]
    with pytest.raises(ValueError, match=r"tasks \['down'\]"):
        learn_geometry(lost)

"""Recording sessions (issue 21, item 2): the drawn calibration and what it does to the data."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sandbox.data.synthetic import TrackerModel, make_dataset
from sandbox.data.synthetic.session import (
    NO_TAIL,
    PIVOT,
    TAILS,
    Session,
    as_session,
    draw_session,
)
from sandbox.robot import GRASP_OFFSET, TIP_LINK, BaxterKinematics

#: The environment's grasp radius (m): sessions should differ by more than it.
GRASP_RADIUS = 0.05


def _session(**changes) -> Session:
    fields = dict(seed=None, tracker_offset=np.zeros(3), tracker_rotation=np.zeros(3),
                  object_offset=GRASP_OFFSET, tempo=1.0, tail=NO_TAIL)
    return Session(**{**fields, **changes})


def _demos(session, name="objects", n=3, seed=0, **kw):
    return make_dataset(name, n, np.random.default_rng(seed), session=session, **kw)


# -- the drawn session -----------------------------------------------------------------------

def test_same_seed_same_session_and_another_seed_another():
    assert draw_session(3) == draw_session(3)
    assert draw_session(3) != draw_session(4)
    assert as_session(3) == draw_session(3) and as_session(None) is None


def test_drawn_fields_are_in_their_ranges_and_every_tail_is_drawn():
    sessions = [draw_session(s) for s in range(200)]
    offsets = np.linalg.norm([s.tracker_offset for s in sessions], axis=1)
    angles = np.rad2deg(np.linalg.norm([s.tracker_rotation for s in sessions], axis=1))
    shifts = np.array([s.object_offset for s in sessions]) - GRASP_OFFSET
    tempo = np.array([s.tempo for s in sessions])
    assert offsets.min() >= 0.02 and offsets.max() <= 0.06
    assert angles.min() >= 1.0 - 1e-9 and angles.max() <= 5.0 + 1e-9
    assert np.abs(shifts).max() <= 0.04
    assert tempo.min() >= 0.8 and tempo.max() <= 1.25
    assert {s.tail for s in sessions} == set(TAILS)


def test_sessions_typically_differ_by_more_than_the_grasp_radius():
    # The hand-to-fingertip offset a model learns: object offset minus tracker offset.
    learned = np.array([s.object_offset - s.tracker_offset for s in map(draw_session, range(100))])
    gaps = np.linalg.norm(learned[:, None] - learned[None], axis=-1)[np.triu_indices(100, 1)]
    assert np.median(gaps) > GRASP_RADIUS
    assert np.mean(gaps > GRASP_RADIUS) > 0.6


def test_a_given_tail_keeps_the_drawn_calibration():
    drawn, freeze = draw_session(7), draw_session(7, tail="freeze")
    assert freeze.tail == "freeze"
    assert freeze.to_dict() == {**drawn.to_dict(), "tail": "freeze"}


def test_to_dict_is_json_and_round_trips():
    session = draw_session(11)
    text = json.dumps(session.to_dict())
    assert Session.from_dict(json.loads(text)) == session


def test_to_tracker_rotates_about_the_pivot_then_offsets():
    quarter = _session(tracker_rotation=[0.0, 0.0, np.pi / 2], tracker_offset=[0.01, 0.02, 0.03])
    points = np.array([PIVOT + [1.0, 0.0, 0.0], PIVOT])
    kept = points.copy()
    out = quarter.to_tracker(points)
    np.testing.assert_allclose(out, [PIVOT + [0.01, 1.02, 0.03], PIVOT + [0.01, 0.02, 0.03]],
                               atol=1e-12)
    np.testing.assert_array_equal(points, kept)                 # input untouched
    arm = np.hstack([points, points + 1.0])                     # (T, 6): two points per row
    np.testing.assert_allclose(quarter.to_tracker(arm)[:, :3], out)


@pytest.mark.parametrize("changes, field", [
    ({"tail": "wobble"}, "tail"),
    ({"tracker_offset": [0.0, 0.1]}, "tracker_offset"),
    ({"tracker_rotation": [4.0, 0.0, 0.0]}, "tracker_rotation"),
    ({"object_offset": [np.nan, 0.0, 0.0]}, "object_offset"),
    ({"tempo": 10.0}, "tempo"),
    ({"tempo": "fast"}, "tempo"),
    ({"seed": -2}, "seed"),
])
def test_bad_fields_are_one_line_errors_naming_the_field(changes, field):
    with pytest.raises(ValueError, match=f"^{field}: expected") as info:
        _session(**changes)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("session", [-1, "3", 2.5, True])
def test_bad_sessions_are_refused(session):
    with pytest.raises(ValueError, match="^session: expected"):
        _demos(session)


def test_bad_tail_names_and_dicts_are_refused():
    with pytest.raises(ValueError, match="^tail: expected one of"):
        draw_session(1, tail="stop")
    with pytest.raises(ValueError, match="^session: expected a dict with keys"):
        Session.from_dict({"seed": 1})


def test_two_task_takes_no_session():
    assert _demos(None, "two_task", 2)
    with pytest.raises(ValueError, match="^session: expected None for 'two_task'"):
        _demos(1, "two_task", 2)


# -- session=None is today's data ------------------------------------------------------------

@pytest.mark.parametrize("name", ["objects", "diverging", "two_task"])
def test_session_none_is_the_call_without_a_session(name):
    old = make_dataset(name, 2, np.random.default_rng(5), observe="hand,arm")
    new = make_dataset(name, 2, np.random.default_rng(5), observe="hand,arm", session=None)
    for a, b in zip(old, new, strict=True):
        np.testing.assert_array_equal(a.times, b.times)
        np.testing.assert_array_equal(a.human, b.human)
        np.testing.assert_array_equal(a.robot, b.robot)
        assert a.meta.keys() == b.meta.keys()
        assert not {"session", "tracked_clean", "meeting_offset"} & set(b.meta)


def test_a_session_leaves_the_other_random_numbers_alone():
    # Same dataset seed: the same tasks, starts and tracker streams with or without a session.
    plain = _demos(None, seed=2)
    moved = _demos(_session(tracker_offset=[0.03, 0.0, 0.0]), seed=2)
    for a, b in zip(plain, moved, strict=True):
        np.testing.assert_allclose(b.meta["clean_human"], a.meta["clean_human"], atol=1e-12)
        np.testing.assert_allclose(b.human, a.human + [0.03, 0.0, 0.0], atol=1e-12)


# -- what a session does ---------------------------------------------------------------------

def test_same_seed_and_session_give_the_same_demonstrations():
    a, b = _demos(4, seed=1), _demos(4, seed=1)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.human, y.human)
        np.testing.assert_array_equal(x.robot, y.robot)
        assert x.meta["session"] == y.meta["session"] == draw_session(4).to_dict()


@pytest.mark.parametrize("seed", [0, 5])
def test_the_tracker_offset_is_recovered_from_the_demos(seed):
    session = draw_session(seed, tail=NO_TAIL)
    demos = _demos(session, n=4, tracker=TrackerModel(glitch_rate=0.0))
    R = session.rotation_matrix
    residual = np.vstack([d.human - ((d.meta["clean_human"] - PIVOT) @ R.T + PIVOT)
                          for d in demos])
    # Left: the offset plus zero-mean jitter and the sample-and-hold lag (a few mm).
    np.testing.assert_allclose(np.nanmedian(residual, axis=0), session.tracker_offset, atol=0.004)
    assert np.linalg.norm(session.tracker_offset) >= 0.02       # so the check means something


def test_tracked_clean_is_the_clean_hand_in_the_tracker_frame_and_the_arm_is_tracked_too():
    session = draw_session(2)
    for d in _demos(session, observe="hand,arm", tracker=TrackerModel.clean()):
        np.testing.assert_allclose(d.meta["tracked_clean"],
                                   session.to_tracker(d.meta["clean_human"]), atol=1e-12)
        if session.tail != "freeze":
            np.testing.assert_allclose(d.select("arm").human,
                                       session.to_tracker(d.meta["clean_arm"]), atol=1e-12)


def test_tempo_scales_every_duration():
    session = draw_session(0, tail=NO_TAIL)
    plain, slow = _demos(None, n=4), _demos(session, n=4)
    ratio = np.mean([d.duration for d in slow]) / np.mean([d.duration for d in plain])
    assert ratio == pytest.approx(session.tempo, rel=1e-9)
    for key in ("reach_time", "robot_time"):
        np.testing.assert_allclose([s.meta[key] for s in slow],
                                   [session.tempo * np.array(p.meta[key]) for p in plain])
    assert abs(session.tempo - 1.0) > 0.05                       # so the check means something


@pytest.mark.parametrize("seed", [1, 3])
def test_meeting_offset_is_the_fingertip_minus_the_tracked_hand_at_the_meeting(seed):
    session = draw_session(seed)
    kin = BaxterKinematics()
    for d in _demos(session):
        row = int(np.flatnonzero(d.times == d.meta["meeting_time"])[0])
        tip = kin.fk(d.robot[row], link=TIP_LINK)
        np.testing.assert_allclose(d.meta["meeting_offset"], tip - d.meta["tracked_clean"][row],
                                   atol=1e-12)
        assert np.linalg.norm(tip - d.meta["handover_target"]) <= 0.01      # IK tolerance
        assert d.meta["meeting_time"] >= max(d.meta["reach_time"][1], d.meta["robot_time"][1])


def test_the_fingertip_meets_the_true_hand_at_the_object_offset():
    session = draw_session(6, tail=NO_TAIL)
    demos = _demos(session, n=5)
    gap = [d.meta["handover_target"] - d.meta["hand_end"] - session.object_offset for d in demos]
    # What is left is each demo's grasp shift (1 cm per axis): zero on average.
    np.testing.assert_allclose(np.mean(gap, axis=0), 0.0, atol=0.012)
    learned = np.mean([d.meta["meeting_offset"] for d in demos], axis=0)
    end = np.mean([d.meta["hand_end"] for d in demos], axis=0)
    expected = end + session.object_offset - session.to_tracker(end[None])[0]
    np.testing.assert_allclose(learned, expected, atol=0.015)

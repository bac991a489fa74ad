"""The human hand motion and its kinematic body."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sandbox.envs.human import SHOULDER, HumanMotion, _quaternion, forearm_orientation


def motion(measured=None) -> HumanMotion:
    times = np.array([0.0, 0.5, 1.0, 2.0])
    true = np.array([[1.0, 0.0, 0.2], [0.9, 0.0, 0.2], [0.8, 0.1, 0.2], [0.8, 0.1, 0.3]])
    return HumanMotion(times, true, true if measured is None else measured, "left", "test")


def test_position_interpolates_and_holds_at_the_ends():
    m = motion()
    np.testing.assert_allclose(m.position(0.25), [0.95, 0.0, 0.2])
    np.testing.assert_allclose(m.position(1.5), [0.8, 0.1, 0.25])
    np.testing.assert_allclose(m.position(-1.0), m.true[0])
    np.testing.assert_allclose(m.position(10.0), m.true[-1])
    assert m.duration == 2.0


def test_measurement_is_the_latest_valid_sample():
    measured = motion().true.copy()
    measured[0] = np.nan
    measured[2] = np.nan
    m = motion(measured)
    np.testing.assert_array_equal(m.measurement(0.0), measured[1])  # none yet: the first valid
    np.testing.assert_array_equal(m.measurement(0.7), measured[1])
    np.testing.assert_array_equal(m.measurement(1.9), measured[1])  # row 2 is a dropout
    np.testing.assert_array_equal(m.measurement(2.0), measured[3])
    m.measurement(0.7)[0] = 99.0  # a copy: the motion does not change
    assert m.measured[1, 0] != 99.0


def test_scaled_plays_faster_and_keeps_the_path():
    m = motion()
    fast = m.scaled(2.0)
    assert fast.duration == 1.0 and fast.meta["speed"] == 2.0
    np.testing.assert_allclose(fast.position(0.75), m.position(1.5))
    with pytest.raises(ValueError, match="speed"):
        m.scaled(0.0)


def test_arrays_are_read_only_copies():
    true = motion().true.copy()
    m = HumanMotion(np.array([0.0, 1.0]), true[:2], true[:2], "x")
    true[0, 0] = 5.0
    assert m.true[0, 0] == 1.0
    with pytest.raises(ValueError):
        m.true[0, 0] = 2.0


@pytest.mark.parametrize("kwargs, match", [
    ({"times": [0.5, 1.0]}, "start at 0"),
    ({"times": [0.0, 0.0]}, "strictly increasing"),
    ({"true": np.full((2, 3), np.nan)}, "true: expected finite"),
    ({"measured": np.full((2, 3), np.nan)}, "at least one sample"),
    ({"true": np.zeros((2, 2))}, "true: expected shape"),
])
def test_bad_motion_is_refused(kwargs, match):
    args = {"times": [0.0, 1.0], "true": np.zeros((2, 3)), "measured": np.zeros((2, 3)),
            "task": "t"}
    with pytest.raises(ValueError, match=match):
        HumanMotion(**{**args, **kwargs})


def test_quaternion_matches_scipy_for_any_rotation():
    for R in Rotation.random(100, random_state=0).as_matrix():
        q = np.array(_quaternion(R))
        ref = Rotation.from_matrix(R).as_quat()
        assert min(np.abs(q - ref).max(), np.abs(q + ref).max()) < 1e-9


def test_forearm_points_at_the_shoulder():
    hand = np.array([0.9, -0.1, 0.25])
    R = Rotation.from_quat(forearm_orientation(hand)).as_matrix()
    direction = (SHOULDER - hand) / np.linalg.norm(SHOULDER - hand)
    np.testing.assert_allclose(R[:, 0], direction, atol=1e-12)
    assert R[2, 2] > 0.5  # the palm's z stays up-ish


def test_hand_body_follows_the_motion(diverging_env):
    obs, _ = diverging_env.reset(seed=0)
    env = diverging_env.unwrapped
    for _ in range(30):
        obs, *_ = env.step(np.append(obs["q"], -1.0))
    position, quaternion = env.sim.pose("human_hand")
    np.testing.assert_allclose(position, env.motion.position(obs["time"][0]), atol=1e-9)
    np.testing.assert_allclose(np.abs(quaternion), np.abs(forearm_orientation(position)),
                               atol=1e-6)


def test_body_measurement_holds_the_latest_valid_sample_and_is_nan_before():
    times = np.array([0.0, 0.1, 0.2, 0.3])
    arm = np.array([[np.nan] * 6, [1.0] * 6, [np.nan, 2, 2, 2, 2, 2], [3.0] * 6])
    motion = HumanMotion(times, np.zeros((4, 3)), np.zeros((4, 3)), "up", body={"arm": arm})
    assert np.isnan(motion.body_measurement("arm", 0.05)).all()
    np.testing.assert_array_equal(motion.body_measurement("arm", 0.25), np.ones(6))
    np.testing.assert_array_equal(motion.body_measurement("arm", 9.0), np.full(6, 3.0))
    assert np.isnan(motion.body_measurement("emg", 0.3)).all()  # not carried
    assert motion.body_measurement("emg", 0.3).shape == (8,)
    fast = motion.scaled(2.0)
    np.testing.assert_array_equal(fast.body_measurement("arm", 0.125), np.ones(6))
    arm[1] = 7.0  # the motion copied it
    np.testing.assert_array_equal(motion.body_measurement("arm", 0.1), np.ones(6))
    with pytest.raises(ValueError, match="name"):
        motion.body_measurement("leg", 0.0)


def test_tracked_gives_the_measurement_its_frame_and_the_body_at_once():
    times = np.array([0.0, 0.1, 0.2, 0.3])
    measured = np.array([[np.nan] * 3, [1.0] * 3, [1.0] * 3, [2.0] * 3])
    arm = np.array([[np.nan] * 6, [np.nan] * 6, [1.0] * 6, [np.nan, 2, 2, 2, 2, 2]])
    motion = HumanMotion(times, np.zeros((4, 3)), measured, "up", body={"arm": arm})
    for t in (-1.0, 0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 9.0):
        hand, frame, body = motion.tracked(t)
        np.testing.assert_array_equal(hand, motion.measurement(t))
        assert frame == motion.frame_time(t) and list(body) == ["arm"]   # emg: not carried
        if t < 0.2:
            assert body["arm"] is None            # no valid arm sample yet
        else:
            np.testing.assert_array_equal(body["arm"], motion.body_measurement("arm", t))
    hand, _, body = motion.tracked(0.3)
    with pytest.raises(ValueError, match="read-only"):
        hand[0] = 9.0                             # views of the motion's own arrays
    with pytest.raises(ValueError, match="read-only"):
        body["arm"][0] = 9.0


@pytest.mark.parametrize("body, match", [
    ({"leg": np.zeros((4, 3))}, "body: expected keys"),
    ({"arm": np.zeros((4, 3))}, "arm"),
    ({"emg": np.zeros((3, 8))}, "emg"),
    ([("arm", np.zeros((4, 6)))], "body: expected a mapping"),
])
def test_bad_body_is_refused(body, match):
    with pytest.raises(ValueError, match=match):
        HumanMotion(np.arange(4) * 0.1, np.zeros((4, 3)), np.zeros((4, 3)), "up", body=body)

"""The teleoperated hand (:class:`TeleopMotion`), scripted ``motion`` and ``source="teleop"``."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic.base import HAND_START
from sandbox.envs.human import HumanMotion
from sandbox.envs.options import parse_options
from sandbox.envs.sources import minimum_jerk, waypoint_motion
from sandbox.envs.teleop import MAX_SPEED, WORKSPACE, TeleopMotion
from sandbox.robot import Q_HOME


def test_hand_moves_at_the_commanded_velocity_from_now_on():
    hand = TeleopMotion(np.random.default_rng(0), noise_m=0.0)
    np.testing.assert_allclose(hand.position(0.5), HAND_START)  # no command yet: still
    hand.set_velocity([-0.2, 0.1, 0.0])
    np.testing.assert_allclose(hand.position(1.5), HAND_START + [-0.2, 0.1, 0.0])
    hand.set_velocity([0.0, 0.0, 0.3])  # applies from t = 1.5 (the latest time queried)
    np.testing.assert_allclose(hand.position(2.0), HAND_START + [-0.2, 0.1, 0.15])
    np.testing.assert_allclose(hand.velocity, [0.0, 0.0, 0.3])
    assert hand.duration == 2.0


def test_hand_stays_in_the_workspace():
    hand = TeleopMotion(np.random.default_rng(0))
    hand.set_velocity([-1.0, 0.0, 1.0])
    far = hand.position(10.0)
    np.testing.assert_allclose(far, [WORKSPACE[0, 0], HAND_START[1], WORKSPACE[2, 1]])


def test_edges_name_where_the_hand_is_held_back():
    """Issue 27: the hand stopped at the workspace's bounds silently; now they are named."""
    hand = TeleopMotion(np.random.default_rng(0))
    assert hand.edges(0.0) == []
    hand.set_velocity([-1.0, 0.0, 1.0])
    assert hand.edges(0.05) == []                          # not there yet
    assert hand.edges(10.0) == [(0, -1, WORKSPACE[0, 0]), (2, 1, WORKSPACE[2, 1])]
    hand.position(10.0)
    hand.set_velocity([0.5, 0.0, 0.0])                     # away from the edge: free again
    assert hand.edges(10.1) == []


def test_speed_factor_scales_commands():
    hand = TeleopMotion(np.random.default_rng(0)).scaled(2.0)
    hand.set_velocity([0.0, 0.1, 0.0])
    np.testing.assert_allclose(hand.position(1.0) - HAND_START, [0.0, 0.2, 0.0])


def test_tracker_holds_frames_and_adds_noise():
    hand = TeleopMotion(np.random.default_rng(1), frame_hz=30.0, noise_m=0.002)
    hand.set_velocity([0.0, 0.3, 0.0])
    a, b = hand.measurement(0.10), hand.measurement(0.11)  # same 30 Hz frame
    np.testing.assert_array_equal(a, b)
    c = hand.measurement(0.2)
    assert not np.array_equal(a, c)
    errors = [hand.measurement((k + 0.5) / 30) - hand.position(k / 30) for k in range(9, 90)]
    assert 0.001 < np.std(errors) < 0.003  # the noise level asked for


def test_tracked_is_the_measurement_and_its_frame_without_a_body():
    hand = TeleopMotion(np.random.default_rng(3), noise_m=0.01)
    twin = TeleopMotion(np.random.default_rng(3), noise_m=0.01)
    for t in (0.0, 0.01, 0.05, 0.4):
        measured, frame, body = hand.tracked(t)
        np.testing.assert_array_equal(measured, twin.measurement(t))  # the same noise draws
        assert frame == twin.frame_time(t) and body == {}


@pytest.mark.parametrize("kwargs, match", [
    ({"rng": 0}, "rng"),
    ({"start": [1.0, 0.0]}, "start"),
    ({"frame_hz": 0.0}, "frame_hz"),
    ({"noise_m": -1.0}, "noise_m"),
])
def test_bad_arguments(kwargs, match):
    kwargs = {"rng": np.random.default_rng(0), **kwargs}
    with pytest.raises(ValueError, match=match):
        TeleopMotion(**kwargs)


def test_too_fast_a_command_is_refused():
    hand = TeleopMotion(np.random.default_rng(0))
    with pytest.raises(ValueError, match="speed"):
        hand.set_velocity([MAX_SPEED + 0.1, 0.0, 0.0])
    with pytest.raises(ValueError, match="velocity"):
        hand.set_velocity([np.nan, 0.0, 0.0])


def test_env_teleop_source_follows_the_commands(diverging_env):
    obs, info = diverging_env.reset(seed=0, options={"source": "teleop"})
    assert info["task"] == "teleop" and info["source"] == "teleop"
    np.testing.assert_allclose(obs["hand"], HAND_START, atol=0.01)
    hand = diverging_env.unwrapped.motion
    hand.set_velocity([-0.25, 0.0, 0.0])
    for _ in range(50):  # 1 s
        obs, *_ = diverging_env.step(np.append(Q_HOME, -1.0))
    np.testing.assert_allclose(obs["hand"], HAND_START + [-0.25, 0.0, 0.0], atol=0.015)
    body = diverging_env.unwrapped.sim.client.getBasePositionAndOrientation(
        diverging_env.unwrapped.sim.bodies["human_hand"])[0]
    np.testing.assert_allclose(body, hand.position(1.0), atol=1e-6)


def test_env_teleop_is_seeded(diverging_env):
    def hands(seed):
        obs, _ = diverging_env.reset(seed=seed, options={"source": "teleop"})
        diverging_env.unwrapped.motion.set_velocity([0.0, 0.2, 0.0])
        return [diverging_env.step(np.append(Q_HOME, -1.0))[0]["hand"] for _ in range(10)]

    np.testing.assert_array_equal(hands(3), hands(3))


def test_scripted_motion_option(diverging_env):
    motion = waypoint_motion([0.0, 1.0], [HAND_START, [0.8, 0.2, 0.2]],
                             np.random.default_rng(0), task="mine")
    obs, info = diverging_env.reset(seed=0, options={"motion": motion})
    assert info["task"] == "mine" and info["source"] == "waypoints[2]"
    for _ in range(60):
        obs, *_ = diverging_env.step(np.append(Q_HOME, -1.0))
    np.testing.assert_allclose(obs["hand"], [0.8, 0.2, 0.2], atol=0.01)


@pytest.mark.parametrize("options, match", [
    ({"motion": "left"}, "HumanMotion"),
    ({"source": "teleop", "trial": 2}, "trial"),
    ({"source": "teleop", "switch_to": "up"}, "switch_to"),
    ({"source": "tele0p"}, "teleop"),
])
def test_bad_teleop_and_motion_options(options, match):
    with pytest.raises(ValueError, match=match):
        parse_options(options, "diverging")


def test_motion_option_excludes_other_sources():
    motion = waypoint_motion([0.0, 1.0], [HAND_START, HAND_START - 0.1],
                             np.random.default_rng(0))
    with pytest.raises(ValueError, match="motion"):
        parse_options({"motion": motion, "task": "up"}, "diverging")
    assert parse_options({"motion": motion, "speed": 2.0}, "diverging").motion is motion


def test_minimum_jerk_passes_the_waypoints_at_rest():
    times = np.array([0.0, 1.0, 3.0])
    points = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 2.0, 0.0]])
    t = np.array([-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.0])
    path = minimum_jerk(t, times, points)
    np.testing.assert_allclose(path[[0, 1, 3, 5, 6]], points[[0, 0, 1, 2, 2]], atol=1e-12)
    np.testing.assert_allclose(path[[2, 4]], [[0.5, 0.0, 0.0], [1.0, 1.0, 0.0]])  # midpoints
    eps = 1e-4
    speed = (minimum_jerk(np.array([1.0 + eps]), times, points)
             - minimum_jerk(np.array([1.0 - eps]), times, points)) / (2 * eps)
    np.testing.assert_allclose(speed, 0.0, atol=1e-6)


def test_waypoint_motion_is_tracked_and_reproducible():
    a = waypoint_motion([0.5, 2.0], [HAND_START, [0.8, 0.2, 0.2]], np.random.default_rng(4))
    b = waypoint_motion([0.5, 2.0], [HAND_START, [0.8, 0.2, 0.2]], np.random.default_rng(4))
    assert isinstance(a, HumanMotion)
    np.testing.assert_array_equal(a.measured, b.measured)
    assert a.duration == pytest.approx(2.5, abs=0.011)
    np.testing.assert_allclose(a.position(0.3), HAND_START)  # waits at the first waypoint
    error = np.abs(a.measured - a.true).max()
    assert 0.0 < error < 0.05  # tracker noise and 30 Hz steps, no jumps


@pytest.mark.parametrize("times, points, match", [
    ([0.0, 0.0], [[1, 0, 0], [1, 0, 0]], "waypoint_times"),
    ([-1.0, 1.0], [[1, 0, 0], [1, 0, 0]], "waypoint_times"),
    ([0.0, 1.0], [[1, 0, 0]], "waypoints"),
    ([0.0], [[1, 0, 0]], "waypoint_times"),
])
def test_bad_waypoints(times, points, match):
    with pytest.raises(ValueError, match=match):
        waypoint_motion(times, points, np.random.default_rng(0))

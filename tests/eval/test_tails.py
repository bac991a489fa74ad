"""Emulated motion tails written onto trials after their meeting (sandbox.eval.tails)."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.core.fitting import motion_end
from sandbox.core.modality import Modality
from sandbox.data.demonstration import Demonstration
from sandbox.eval import tails

START = np.array([1.0, -0.2, 0.2])
END = np.array([0.8, 0.1, 0.3])      # 0.38 m from START
HZ = 30.0


def minjerk(x):
    x = np.clip(x, 0.0, 1.0)
    return x**3 * (10 - 15 * x + 6 * x**2)


def trial(points: int = 1, seconds: float = 3.5, arrive: float = 2.0) -> Demonstration:
    """A reach START -> END over ``arrive`` s, then still; the robot settles at the same time.
    ``points`` 3-D points: the hand, then (arm) points that follow it at a distance."""
    t = np.arange(0.0, seconds, 1.0 / HZ)
    s = minjerk(t / arrive)[:, None]
    hand = START + s * (END - START)
    human = np.hstack([hand + 0.1 * j for j in range(points)])
    robot = np.outer(s[:, 0], np.linspace(0.2, 0.8, 7))
    modalities = (Modality("hand", ("x", "y", "z")),)
    if points > 1:
        modalities += (Modality("arm", tuple(f"a{i}" for i in range(3 * points - 3))),)
    return Demonstration(t, human, robot, "reach", modalities=modalities)


def meeting(demo) -> int:
    t = demo.times - demo.times[0]
    return motion_end(t, demo.robot, 0.05, demo.human, 0.02)


def emulate(demo, kind, seed=0, **kw):
    return tails.emulate_tail(demo, kind, np.random.default_rng(seed), **kw)


def test_none_is_the_trial_itself():
    demo = trial()
    assert emulate(demo, "none") is demo


@pytest.mark.parametrize("kind", [k for k in tails.KINDS if k not in ("none", "stop_short")])
def test_the_motion_up_to_the_meeting_is_kept_and_the_input_unchanged(kind):
    demo = trial()
    before = demo.human.copy()
    out = emulate(demo, kind)
    i_m = meeting(demo)
    if kind == "freeze":          # the freeze starts in the last 30 % of the recording
        i_m = int(0.7 * len(demo.times)) - 1
    np.testing.assert_array_equal(out.human[: i_m + 1], before[: i_m + 1])
    np.testing.assert_array_equal(demo.human, before)


def test_hold_keeps_the_hand_at_the_meeting_pose():
    demo = trial()
    i_m = meeting(demo)
    out = emulate(demo, "hold")
    after = out.human[i_m + 1:]
    assert after.shape[0] > 10
    dev = np.abs(after - demo.human[i_m])
    assert dev.max() < 6 * tails.HOLD_NOISE_M and dev.std() > 0.5 * tails.HOLD_NOISE_M


def test_stop_short_waits_three_to_eight_cm_back_along_the_approach():
    demo = trial()
    i_m = meeting(demo)
    out = emulate(demo, "stop_short", seed=3)
    short = demo.human[i_m] - out.human[-12:].mean(axis=0)
    u = (demo.human[i_m] - START) / np.linalg.norm(demo.human[i_m] - START)
    assert 0.03 - 0.002 < short @ u < 0.08 + 0.002
    assert np.linalg.norm(short - (short @ u) * u) < 0.003
    half = int(np.searchsorted(demo.times, 0.5 * demo.times[i_m]))  # the ramp's start
    np.testing.assert_array_equal(out.human[:half], demo.human[:half])


def test_overshoot_goes_past_and_comes_back():
    demo = trial()
    i_m = meeting(demo)
    out = emulate(demo, "overshoot", seed=1)
    u = (demo.human[i_m] - START) / np.linalg.norm(demo.human[i_m] - START)
    past = (out.human[i_m + 1:] - demo.human[i_m]) @ u
    assert 0.04 - 0.005 < past.max() < 0.08 + 0.005
    assert abs(past[-1]) < 0.006                 # back, 0.5 s after the meeting


def test_drift_back_ends_ten_to_twenty_five_cm_toward_the_start():
    demo = trial(seconds=4.0)
    i_m = meeting(demo)
    out = emulate(demo, "drift_back", seed=2)
    back = out.human[-1] - demo.human[i_m]
    toward = (START - demo.human[i_m]) / np.linalg.norm(START - demo.human[i_m])
    assert 0.10 - 0.006 < back @ toward < 0.25 + 0.006


def test_linger_extends_the_recording_and_holds_the_robot():
    demo = trial()
    out = emulate(demo, "linger")
    extra = len(out.times) - len(demo.times)
    assert extra == int(tails.LINGER_S * HZ) or extra == int(tails.LINGER_S * HZ) + 1
    assert np.all(np.diff(out.times) > 0)
    np.testing.assert_array_equal(out.robot[-extra:], np.repeat(demo.robot[-1:], extra, 0))


def test_freeze_repeats_one_row_to_the_end():
    out = emulate(trial(), "freeze", seed=4)
    same = np.all(out.human == out.human[-1], axis=1)
    first = int(np.argmin(same[::-1]))            # rows equal to the last, from the end
    assert first >= 2 and np.all(same[-first:])


def test_the_arm_follows_the_hand_by_the_point_gains():
    demo = trial(points=3)
    i_m = meeting(demo)
    out = emulate(demo, "stop_short", seed=5)
    moved = (out.human[-12:] - demo.human[i_m]).mean(axis=0).reshape(3, 3)   # held, offset
    hand = np.linalg.norm(moved[0])
    np.testing.assert_allclose(np.linalg.norm(moved, axis=1) / hand, tails.POINT_GAINS,
                               atol=0.03)
    assert i_m < len(demo.times) - 12


def test_a_seed_gives_one_tail_and_with_tail_shares_it_with_the_training_version():
    demos = [trial(), trial(arrive=1.8)]
    a = tails.with_tail(demos, demos, "stop_short")
    b = tails.with_tail(demos, demos, "stop_short", in_training=True)
    for one, two in zip(a[1], b[1]):
        np.testing.assert_array_equal(one.human, two.human)
    assert a[0][0] is demos[0]                     # training versions left alone
    for train, test in zip(*b):                    # the same numbers on both versions
        np.testing.assert_array_equal(train.human, test.human)
    assert not np.array_equal(b[1][0].human, demos[0].human)


def test_bad_input_is_one_line():
    demo = trial()
    with pytest.raises(ValueError, match="tail"):
        emulate(demo, "wobble")
    with pytest.raises(ValueError, match="as many test streams"):
        tails.with_tail([demo], [demo, demo], "hold")
    with pytest.raises(ValueError, match="truth with the trial's"):
        emulate(demo, "hold", truth=trial(seconds=3.0))
    emg = Demonstration(demo.times, np.abs(demo.human), demo.robot, "reach",
                        modalities=(Modality("emg", ("e0", "e1", "e2"), "signal"),))
    with pytest.raises(ValueError, match="3-D position"):
        emulate(emg, "hold")

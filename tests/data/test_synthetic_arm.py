"""The human arm model: anthropometry, trunk motion, swivel, placement, seeding."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic.arm import (
    FOREARM,
    SHOULDER_START,
    UPPER_ARM,
    ArmModel,
    arm_positions,
    arm_rng,
    draw_arm,
    reach_progress,
    torso_sway,
)
from sandbox.data.synthetic.base import minimum_jerk, sample_times
from sandbox.data.synthetic.two_link import swivel_angle

TIMES = sample_times(2.2, 100.0)
START, END = np.array([1.10, -0.12, 0.25]), np.array([0.80, 0.20, 0.20])
HAND = START + np.outer(minimum_jerk(TIMES / 1.4), END - START)


def _arm(seed: int = 0, **kwargs) -> np.ndarray:
    return arm_positions(TIMES, HAND, np.random.default_rng(seed), model=ArmModel(**kwargs))


def test_columns_are_elbow_then_shoulder_at_winters_segment_lengths():
    arm = _arm(height=(1.80, 0.0))
    elbow, shoulder = arm[:, :3], arm[:, 3:]
    assert arm.shape == (TIMES.size, 6)
    assert np.allclose(np.linalg.norm(elbow - shoulder, axis=1), UPPER_ARM * 1.80)
    assert np.allclose(np.linalg.norm(elbow - HAND, axis=1), FOREARM * 1.80)


def test_swivel_angle_is_respected_when_it_does_not_drop():
    arm = _arm(swivel_deg=(30.0, 0.0), swivel_drop_deg=(0.0, 0.0))
    angle = swivel_angle(arm[:, 3:], arm[:, :3], HAND)
    assert np.allclose(np.degrees(angle), 30.0)


def test_elbow_hangs_outward_and_drops_at_the_end_of_the_reach():
    for seed in range(5):
        arm = _arm(seed)
        angle = np.degrees(swivel_angle(arm[:, 3:], arm[:, :3], HAND))
        assert 30.0 < angle[0] < 110.0  # out to the +y side
        assert np.mean(arm[:, 1] > arm[:, 4]) > 0.9  # the elbow is outward of the shoulder
    drop = _arm(swivel_deg=(70.0, 0.0), swivel_drop_deg=(25.0, 0.0))
    angle = np.degrees(swivel_angle(drop[:, 3:], drop[:, :3], HAND))
    assert angle[0] == pytest.approx(70.0) and angle[-1] == pytest.approx(45.0)


def test_torso_sway_is_bounded_slow_and_off_when_asked():
    for seed in range(50):
        draw = draw_arm(ArmModel(sway_m=0.01), np.random.default_rng(seed))
        sway = torso_sway(sample_times(4.0, 100.0), draw)
        assert np.linalg.norm(sway, axis=1).max() <= 0.01 + 1e-12
        assert np.all(draw.sway_hz <= 0.6)
    still = arm_positions(TIMES, HAND, np.random.default_rng(0), model=ArmModel.still())
    assert np.allclose(still[:, 3:], still[0, 3:])  # a still trunk: the shoulder does not move


def test_the_trunk_leans_toward_the_handover_like_the_recordings():
    moves = np.array([_arm(seed)[-1, 3:] - _arm(seed)[0, 3:] for seed in range(40)])
    mean = moves.mean(axis=0)
    # recorded: (-0.115, +0.020, -0.033) m from start to end (median distance 0.13 m)
    assert -0.16 < mean[0] < -0.08 and -0.02 < mean[1] < 0.06 and -0.06 < mean[2] < -0.01
    assert 0.08 < np.median(np.linalg.norm(moves, axis=1)) < 0.18


def test_start_shoulder_is_placed_where_the_recordings_put_it():
    starts = np.array([_arm(seed)[0, 3:] for seed in range(200)])
    assert np.allclose(starts.mean(axis=0), SHOULDER_START, atol=0.01)
    assert np.all(starts.std(axis=0) < 0.02)
    # the tracked "left" shoulder is on the +y side, 1.2-1.4 m in front of Baxter
    assert np.all((starts[:, 0] > 1.2) & (starts[:, 0] < 1.45))


def test_heights_vary_per_demonstration_within_the_clip():
    heights = [draw_arm(ArmModel(), np.random.default_rng(s)).height for s in range(300)]
    assert 1.5 <= min(heights) and max(heights) <= 1.95
    assert np.mean(heights) == pytest.approx(1.70, abs=0.01)
    assert np.std(heights) == pytest.approx(0.07, rel=0.15)


def test_same_seed_same_arm_and_the_arm_stream_is_not_the_trackers():
    assert np.array_equal(_arm(3), _arm(3))
    assert not np.allclose(_arm(3), _arm(4))
    assert np.array_equal(arm_rng(11).normal(size=5), arm_rng(11).normal(size=5))
    assert not np.allclose(arm_rng(11).normal(size=5), np.random.default_rng(11).normal(size=5))


def test_arm_positions_does_not_change_its_inputs():
    hand, times = HAND.copy(), TIMES.copy()
    arm_positions(times, hand, np.random.default_rng(0))
    assert np.array_equal(hand, HAND) and np.array_equal(times, TIMES)


def test_reach_progress_goes_from_zero_to_one_and_lags():
    p = reach_progress(TIMES, HAND)
    assert p[0] == 0.0 and p[-1] == 1.0 and np.all(np.diff(p) >= -1e-12)
    late = reach_progress(TIMES, HAND, lag_s=0.1)
    assert np.all(late <= p + 1e-12)
    assert np.array_equal(reach_progress(TIMES, np.tile(START, (TIMES.size, 1))),
                          np.zeros(TIMES.size))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"height": (1.7, -0.1)}, "height"),
        ({"height_range": (1.9, 1.5)}, "height_range"),
        ({"upper_arm": 0.0}, "upper_arm"),
        ({"shoulder_std": (0.01, -0.01, 0.01)}, "shoulder_std"),
        ({"shoulder_start": (1.3, 0.0)}, "shoulder_start"),
        ({"sway_m": -0.01}, "sway_m"),
        ({"sway_hz": (0.5, 0.2)}, "sway_hz"),
        ({"swivel_deg": (float("nan"), 10.0)}, "swivel_deg"),
        ({"outward": (1.0, 1.0, 0.0)}, "outward"),
    ],
)
def test_bad_arm_models_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ArmModel(**kwargs)


def test_bad_arm_inputs_are_refused():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="hand"):
        arm_positions(TIMES, HAND[:, :2], rng)
    with pytest.raises(ValueError, match="times"):
        arm_positions(TIMES[::-1], HAND, rng)
    with pytest.raises(ValueError, match="rng"):
        arm_positions(TIMES, HAND, 0)
    with pytest.raises(ValueError, match="ArmModel"):
        arm_positions(TIMES, HAND, rng, model={"height": (1.7, 0.0)})

"""Tracker artefacts: each one switchable, at the measured strength."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic.base import sample_times
from sandbox.data.synthetic.tracker import TrackerModel, apply_tracker, frame_index

TIMES = sample_times(2.2, 100.0)
CLEAN = np.column_stack([1.1 - 0.3 * TIMES / 2.2, -0.1 + 0.3 * TIMES / 2.2, 0.2 + 0 * TIMES])
OFF = dict(noise_m=0.0, frame_hz=None, glitch_rate=0.0)


def _run(seed: int = 0, **kwargs) -> np.ndarray:
    return apply_tracker(TIMES, CLEAN, TrackerModel(**kwargs), np.random.default_rng(seed))


def test_clean_tracker_reports_the_clean_motion():
    assert np.array_equal(apply_tracker(TIMES, CLEAN, TrackerModel.clean(),
                                        np.random.default_rng(0)), CLEAN)
    assert np.array_equal(_run(**OFF), CLEAN)


def test_sample_and_hold_repeats_about_30_frames_per_second_never_from_the_future():
    rng = np.random.default_rng(3)
    shown = frame_index(TIMES, 30.0, rng)
    assert np.all(shown <= np.arange(TIMES.size)) and shown[0] == 0
    assert np.all(np.diff(shown) >= 0)
    frames_per_s = np.unique(shown).size / TIMES[-1]
    assert 25 <= frames_per_s <= 36
    out = _run(**{**OFF, "frame_hz": 30.0})
    assert np.array_equal(out, CLEAN[frame_index(TIMES, 30.0, np.random.default_rng(0))])


def test_white_noise_has_the_requested_spread():
    residual = _run(**{**OFF, "noise_m": 0.004}) - CLEAN
    assert residual.std() == pytest.approx(0.004, rel=0.15)
    assert abs(residual.mean()) < 0.001


def test_glitches_are_5cm_plus_jumps_after_the_given_phase():
    jumps, first = 0, []
    for seed in range(30):
        out = _run(seed, **{**OFF, "glitch_rate": 2.0, "glitch_phase": (0.5, 1.0)})
        off = np.linalg.norm(out - CLEAN, axis=1)
        if off.any():
            first.append(TIMES[np.argmax(off > 0)] / TIMES[-1])
            assert off[off > 0].min() >= 0.05 - 1e-12
        jumps += int(off.any())
    assert jumps >= 20  # P(no episode) = exp(-2) per demo
    assert min(first) >= 0.5 - 0.01
    assert not np.any(_run(**{**OFF, "glitch_rate": 0.0}) != CLEAN)


def test_dropouts_and_zero_rows_are_switchable_and_off_by_default():
    default = _run()
    assert np.isfinite(default).all() and not np.any(np.all(default == 0, axis=1))
    lost = _run(**{**OFF, "dropout_rate": 0.1})
    zero = _run(**{**OFF, "zero_rate": 0.1})
    nan_rows = np.isnan(lost).all(axis=1)
    assert 0.05 < nan_rows.mean() < 0.15 and not np.isnan(lost[~nan_rows]).any()
    assert 0.05 < np.all(zero == 0, axis=1).mean() < 0.15
    # with 30 Hz frames, a lost frame blanks all the rows that repeat it
    held = _run(**{**OFF, "frame_hz": 30.0, "dropout_rate": 0.2})
    runs = np.diff(np.r_[0, np.isnan(held[:, 0]).astype(int), 0])
    assert (np.flatnonzero(runs == -1) - np.flatnonzero(runs == 1)).mean() > 2.0


def test_default_tracker_resembles_the_recordings():
    model = TrackerModel()
    assert model.frame_hz == 30.0 and 0.0 < model.noise_m <= 0.003
    assert model.glitch_rate > 0 and model.glitch_m[0] >= 0.05
    assert model.dropout_rate == 0.0 and model.zero_rate == 0.0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"noise_m": -0.1}, "noise_m"),
        ({"frame_hz": 0.0}, "frame_hz"),
        ({"glitch_rate": -1.0}, "glitch_rate"),
        ({"glitch_m": (0.1, 0.05)}, "glitch_m"),
        ({"glitch_phase": (0.5, 1.5)}, "glitch_phase"),
        ({"dropout_rate": 1.0}, "dropout_rate"),
        ({"zero_rate": float("nan")}, "zero_rate"),
    ],
)
def test_bad_tracker_settings_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        TrackerModel(**kwargs)

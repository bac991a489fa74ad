"""Tests of sandbox.data.filtering (gated hand filter, RTS smoother) and sandbox.data.glitches."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.filtering import (
    ACCEPTED,
    MISSING,
    REJECTED,
    RESET,
    STALE,
    FilterConfig,
    HandFilter,
    filter_track,
    smooth_track,
)
from sandbox.data.glitches import excursions, find_glitches

#: A filter matched to a constant-velocity signal (little process noise).
CV_CONFIG = FilterConfig(accel_std=0.2, noise_std=0.003)


def cv_track(rng: np.random.Generator, n: int = 90, noise: float = 0.003):
    """A 30 Hz constant-velocity hand track with slightly irregular times."""
    t = np.sort(np.arange(n) / 30.0 + rng.uniform(0.0, 0.005, n))
    true = np.array([1.1, -0.1, 0.25]) + t[:, None] * np.array([-0.3, 0.2, -0.1])
    return t, true, true + rng.normal(0.0, noise, true.shape)


def reach_track(rng: np.random.Generator, n: int = 120, noise: float = 0.005):
    """A bell-shaped-speed reach of 0.4 m in 2 s at 60 Hz, with white noise."""
    t = np.linspace(0.0, 2.0, n)
    s = t / 2.0
    s = s**3 * (10 - 15 * s + 6 * s**2)
    true = np.array([1.1, -0.1, 0.25]) + s[:, None] * np.array([-0.3, 0.25, 0.05])
    return t, true, true + rng.normal(0.0, noise, true.shape)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_jumps_of_10_cm_are_rejected_and_estimate_stays_within_mm(seed):
    rng = np.random.default_rng(seed)
    t, true, y = cv_track(rng)
    jumps = np.arange(15, 90, 9)
    directions = rng.normal(size=(jumps.size, 3))
    y[jumps] += 0.10 * directions / np.linalg.norm(directions, axis=1, keepdims=True)
    run = filter_track(t, y, CV_CONFIG)
    np.testing.assert_array_equal(np.flatnonzero(run.status == REJECTED), jumps)
    err = np.linalg.norm(run.filtered - true, axis=1)[10:]
    raw = np.linalg.norm(y - true, axis=1)[10:]
    raw[np.isin(np.arange(10, 90), jumps)] = 0.0
    assert np.sqrt(np.mean(err**2)) < min(0.005, np.sqrt(np.mean(raw**2)))
    assert err.max() < 0.012


def test_rejected_sample_is_not_used():
    rng = np.random.default_rng(3)
    t, _, y = cv_track(rng, n=40)
    clean = filter_track(t, y, CV_CONFIG)
    y_jump = y.copy()
    y_jump[30] += [0.0, 0.0, 0.1]
    jumped = filter_track(t, y_jump, CV_CONFIG)
    assert jumped.status[30] == REJECTED
    # Same as if the sample had been missing.
    y_nan = y.copy()
    y_nan[30] = np.nan
    missing = filter_track(t, y_nan, CV_CONFIG)
    np.testing.assert_allclose(jumped.filtered[31:], missing.filtered[31:])
    assert not np.allclose(jumped.filtered[31:], clean.filtered[31:])


def test_nan_samples_are_skipped_by_predicting():
    rng = np.random.default_rng(4)
    t, true, y = cv_track(rng)
    y[[20, 21, 22, 50]] = np.nan
    y[60, 1] = np.nan  # one missing coordinate makes the sample missing
    run = filter_track(t, y, CV_CONFIG)
    assert set(np.flatnonzero(run.status == MISSING)) == {20, 21, 22, 50, 60}
    assert np.isfinite(run.filtered).all()
    assert np.linalg.norm(run.filtered[10:] - true[10:], axis=1).max() < 0.012


@pytest.mark.parametrize("k", [10, 45, 80])
def test_causal_output_does_not_depend_on_later_samples(k):
    rng = np.random.default_rng(5)
    t, _, y = cv_track(rng)
    later = y.copy()
    later[k + 1 :] += rng.normal(0.0, 0.05, later[k + 1 :].shape)
    a = filter_track(t, y).filtered
    b = filter_track(t, later).filtered
    np.testing.assert_array_equal(a[: k + 1], b[: k + 1])
    assert not np.allclose(a[k + 1 :], b[k + 1 :])


def test_streaming_filter_matches_batch_run():
    rng = np.random.default_rng(6)
    t, _, y = reach_track(rng)
    f = HandFilter(3)
    streamed = np.array([f.update(ti, yi) for ti, yi in zip(t, y, strict=True)])
    np.testing.assert_array_equal(streamed, filter_track(t, y).filtered)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_rts_smoother_beats_causal_filter_on_noisy_reach(seed):
    rng = np.random.default_rng(seed)
    t, true, y = reach_track(rng)
    run = filter_track(t, y)
    smooth = smooth_track(run)
    rms = lambda est: np.sqrt(np.mean(np.sum((est - true) ** 2, axis=1)))  # noqa: E731
    assert rms(smooth) < 0.8 * rms(run.filtered)
    assert rms(smooth) < rms(y)


def test_smoother_leaves_samples_before_the_first_one_nan():
    t = np.linspace(0.0, 1.0, 30)
    y = np.column_stack([t, 0 * t, 0 * t + 1.0])
    y[:5] = np.nan
    smooth = smooth_track(filter_track(t, y))
    assert np.isnan(smooth[:5]).all() and np.isfinite(smooth[5:]).all()


def test_smoother_of_a_track_without_any_sample_is_all_nan():
    smooth = smooth_track(filter_track([0.0, 0.1, 0.2], np.full((3, 3), np.nan)))
    assert smooth.shape == (3, 3) and np.isnan(smooth).all()


def test_persistent_shift_resets_the_filter():
    t = np.arange(60) / 30.0
    y = np.tile([1.0, 0.0, 0.2], (60, 1)) + np.random.default_rng(7).normal(0, 1e-3, (60, 3))
    y[30:] += [0.0, 0.3, 0.0]  # the track really moved
    config = FilterConfig(accel_std=0.5, max_rejects=4)
    run = filter_track(t, y, config)
    np.testing.assert_array_equal(np.flatnonzero(run.status == REJECTED), [30, 31, 32])
    assert run.status[33] == RESET
    np.testing.assert_allclose(run.filtered[-1], [1.0, 0.3, 0.2], atol=3e-3)
    smooth = smooth_track(run)
    # No blending across the reset: each side stays at its own level.
    np.testing.assert_allclose(smooth[:30], np.tile([1.0, 0.0, 0.2], (30, 1)), atol=3e-3)
    np.testing.assert_allclose(smooth[33:], np.tile([1.0, 0.3, 0.2], (27, 1)), atol=3e-3)


def test_equal_times_use_every_sample():
    f = HandFilter(3, CV_CONFIG)
    f.update(0.0, [1.0, 0.0, 0.0])
    f.update(0.0, [1.002, 0.0, 0.0])
    assert f.status == ACCEPTED
    assert 1.0 < f.position[0] < 1.002


def test_repeated_and_zero_samples_are_not_used():
    f = HandFilter(3, CV_CONFIG)
    f.update(0.00, [1.0, 0.0, 0.2])
    f.update(0.03, [1.01, 0.0, 0.2])
    before = f.state
    f.update(0.03, [1.0, 0.0, 0.2])  # an old frame sent again
    assert f.status == STALE
    np.testing.assert_array_equal(f.state[0], before[0])
    f.update(0.03, [0.0, 0.0, 0.0])
    assert f.status == MISSING
    g = HandFilter(3, CV_CONFIG, drop_repeats=False)
    g.update(0.0, [1.0, 0.0, 0.2])
    g.update(0.03, [1.0, 0.0, 0.2])
    assert g.status == ACCEPTED


def test_before_first_sample_output_is_nan():
    f = HandFilter(3)
    assert np.isnan(f.update(0.0, [np.nan] * 3)).all()
    assert not f.initialised
    np.testing.assert_array_equal(f.update(0.1, [1.0, 2.0, 3.0]), [1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda f: f.update(0.0, [1.0, 2.0]), "expected shape"),
        (lambda f: f.update(np.nan, [1.0, 2.0, 3.0]), "finite time"),
        (lambda f: (f.update(1.0, [1, 2, 3]), f.update(0.5, [1, 2, 3])), "time order"),
    ],
)
def test_bad_updates_are_refused(call, match):
    with pytest.raises(ValueError, match=match):
        call(HandFilter(3))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"accel_std": 0.0}, "accel_std"),
        ({"noise_std": -1.0}, "noise_std"),
        ({"gate_prob": 1.5}, "gate_prob"),
        ({"max_rejects": 0}, "max_rejects"),
    ],
)
def test_bad_config_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        FilterConfig(**kwargs)


def test_filter_track_refuses_decreasing_times():
    with pytest.raises(ValueError, match="non-decreasing"):
        filter_track([0.0, 0.2, 0.1], np.zeros((3, 3)) + 1.0)


def test_find_glitches_known_answer():
    t = np.array([0.0, 0.01, 0.04, 0.04, 0.08, 0.12, 0.2, 0.3, 0.4, 0.45, 0.5, 0.55])
    a, b, c, d = [1.0, 0, 0.2], [1.01, 0, 0.2], [1.2, 0, 0.2], [1.21, 0, 0.2]
    nan, zero = [np.nan] * 3, [0.0] * 3
    y = np.array([a, a, b, a, zero, nan, c, c, c, c, d, d])
    g = find_glitches(t, y, freeze_s=0.2, jump_m=0.05)
    np.testing.assert_array_equal(np.flatnonzero(g.fresh), [0, 2, 6, 10])
    np.testing.assert_array_equal(np.flatnonzero(g.stale), [1, 3, 7, 8, 9, 11])
    np.testing.assert_array_equal(np.flatnonzero(g.zero), [4])
    np.testing.assert_array_equal(np.flatnonzero(g.missing), [5])
    np.testing.assert_array_equal(np.flatnonzero(g.jump), [6])  # b -> c is 19 cm
    np.testing.assert_array_equal(np.flatnonzero(g.frozen), [7, 8, 9])  # c held 0.2 -> 0.45
    assert g.frozen_segments == 1 and g.frozen_s == pytest.approx(0.25)
    assert g.counts()["new_frames"] == 4


def test_excursions_flags_short_jumps_not_motion():
    t = np.arange(60) / 30.0
    y = np.array([1.1, -0.1, 0.25]) + t[:, None] * np.array([-0.6, 0.5, 0.1])  # 0.8 m/s
    y = y + np.random.default_rng(9).normal(0.0, 0.002, y.shape)
    assert not excursions(t, y).any()
    jumped = y.copy()
    jumped[30:33] += [0.0, 0.0, 0.08]  # a 3-frame, 8 cm occlusion jump
    np.testing.assert_array_equal(np.flatnonzero(excursions(t, jumped)), [30, 31, 32])
    gappy = y.copy()
    gappy[20:40] = np.nan  # no lopsided window at the edges of a dropout or of the track
    assert not excursions(t, gappy).any()
    assert not excursions(t[:1], y[:1]).any()

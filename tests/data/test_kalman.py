"""The array filter and smoother (sandbox.data.kalman) against filterpy, the reference."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data import filtering, kalman, preprocess
from sandbox.data.filtering import (
    FilterConfig,
    filter_track,
    filter_track_reference,
    smooth_track,
    smooth_track_reference,
)
from sandbox.data.recorded import find_trials, load_trial

TOL = 1e-9


def assert_same_run(fast, ref) -> None:
    np.testing.assert_array_equal(fast.status, ref.status)
    for name in ("filtered", "means", "covs", "Fs", "Qs"):
        np.testing.assert_allclose(getattr(fast, name), getattr(ref, name), rtol=0, atol=TOL,
                                   err_msg=name)
    np.testing.assert_allclose(smooth_track(fast), smooth_track_reference(ref), rtol=0,
                               atol=TOL)


def glitchy_track(rng: np.random.Generator, n: int = 300):
    """A reach with bursts (equal stamps), dropouts, zeros, re-sent frames and jumps."""
    t = np.cumsum(rng.choice([0.0, 1 / 30, 2 / 30], size=n, p=[0.2, 0.6, 0.2]))
    s = np.clip(t / t[-1], 0, 1)
    y = np.array([1.1, -0.1, 0.25]) + (s**3 * (10 - 15 * s + 6 * s**2))[:, None] * [-0.4, 0.3, 0.1]
    y = y + rng.normal(0, 0.003, y.shape)
    y[rng.random(n) < 0.05] = np.nan
    y[rng.random(n) < 0.03] = 0.0
    resent = np.flatnonzero(rng.random(n) < 0.1)
    y[resent[resent > 3]] = y[resent[resent > 3] - 3]
    y[rng.integers(10, n, 8)] += rng.normal(0, 0.3, (8, 3))       # isolated jumps
    y[150:157] += 0.5                                              # the track moves: resets
    return t, y


def test_status_codes_are_those_of_filtering():
    assert (kalman.WAITING, kalman.MISSING, kalman.ACCEPTED, kalman.REJECTED, kalman.INIT,
            kalman.RESET, kalman.STALE) == (filtering.WAITING, filtering.MISSING,
                                            filtering.ACCEPTED, filtering.REJECTED,
                                            filtering.INIT, filtering.RESET, filtering.STALE)


@pytest.mark.parametrize("seed", range(6))
def test_matches_filterpy_on_glitchy_tracks(seed):
    rng = np.random.default_rng(seed)
    t, y = glitchy_track(rng)
    config = FilterConfig(accel_std=[1.0, 6.0, 3.0][seed % 3], max_rejects=1 + seed % 4,
                          time_jitter_std=[0.0, 0.01][seed % 2])
    fast, ref = filter_track(t, y, config), filter_track_reference(t, y, config)
    assert_same_run(fast, ref)
    counts = fast.counts()
    assert counts["missing"] and counts["stale"] and counts["accepted"]
    assert counts["rejected"] or counts["reset"]


def test_matches_filterpy_when_the_first_samples_are_missing():
    t = np.arange(6) / 30
    y = np.array([[np.nan] * 3, [0.0] * 3, [1.0, 0.0, 0.2], [1.0, 0.0, 0.2], [1.01, 0, 0.2],
                  [np.nan] * 3])
    fast, ref = filter_track(t, y), filter_track_reference(t, y)
    assert_same_run(fast, ref)
    assert fast.status[:3].tolist() == [kalman.WAITING, kalman.WAITING, kalman.INIT]


def test_a_track_without_any_sample_stays_nan():
    t = np.arange(4) / 30
    run = filter_track(t, np.full((4, 3), np.nan))
    assert np.isnan(run.filtered).all() and np.isnan(smooth_track(run)).all()


def test_bad_config_is_refused():
    with pytest.raises(ValueError, match="config: expected a FilterConfig"):
        filter_track([0.0, 0.1], np.zeros((2, 3)), config={"accel_std": 1})


def test_matches_filterpy_on_every_recorded_track(recorded_dir):
    """Every hand track of the 174 recordings, as the loader gives it (raw, all rows)."""
    checked = 0
    for _, path in find_trials(recorded_dir):
        demo = load_trial(path, preprocess="none")
        fast = filter_track(demo.times, demo.human)
        ref = filter_track_reference(demo.times, demo.human)
        assert_same_run(fast, ref)
        checked += 1
    assert checked == 174


@pytest.mark.parametrize("mode", ["causal", "smooth"])
def test_loaded_trials_are_those_of_the_filterpy_path(recorded_dir, monkeypatch, mode):
    """End to end: load_trial with the array path equals load_trial on filterpy, 1e-9."""
    paths = [p for _, p in find_trials(recorded_dir)][::15]
    fast = [load_trial(p, preprocess=mode, observe="hand,arm") for p in paths]
    monkeypatch.setattr(preprocess, "filter_track", filter_track_reference)
    monkeypatch.setattr(preprocess, "smooth_track", smooth_track_reference)
    ref = [load_trial(p, preprocess=mode, observe="hand,arm") for p in paths]
    for a, b in zip(fast, ref, strict=True):
        np.testing.assert_allclose(a.human, b.human, rtol=0, atol=TOL, equal_nan=True)
        np.testing.assert_array_equal(a.meta["human_measured"], b.meta["human_measured"])
        assert a.meta["report"] == b.meta["report"]

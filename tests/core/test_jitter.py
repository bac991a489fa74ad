"""The data's own jitter (issue 28 item 4): known answers on tracks of known noise, and the
noise floor IProMP(jitter_floor=k) takes from it."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.core.jitter import JITTER_FACTOR, jitter, residuals, track_jitter
from sandbox.data.demonstration import Demonstration


def reach(t: np.ndarray, duration: float = 2.0) -> np.ndarray:
    """A 40 cm minimum-jerk reach (T, 3) m, the kind of motion a hand makes."""
    s = np.clip(t / duration, 0.0, 1.0)
    p = 10 * s**3 - 15 * s**4 + 6 * s**5
    return np.array([0.9, 0.4, 0.0]) + p[:, None] * np.array([-0.3, 0.2, 0.2])


@pytest.mark.parametrize("sigma", [0.001, 0.02])
@pytest.mark.parametrize("rate", [30.0, 120.0])
def test_a_known_jitter_is_recovered(sigma, rate):
    rng = np.random.default_rng(1)
    t = np.arange(0.0, 10.0, 1.0 / rate)                  # a reach and a hold, 300+ samples
    track = reach(t) + rng.normal(0.0, sigma, (t.size, 3))
    estimate = jitter(t, track)
    assert np.allclose(estimate, sigma, rtol=0.2), estimate     # per dim: 300 samples
    assert track_jitter(t, track) == pytest.approx(sigma, rel=0.1)


def test_uneven_sampling_re_sent_frames_jumps_and_dropouts_do_not_bias_it():
    rng = np.random.default_rng(2)
    t = np.cumsum(rng.uniform(0.005, 0.02, 400))
    track = reach(t - t[0]) + rng.normal(0.0, 0.001, (t.size, 3))
    track[1::4] = track[0:-1:4]                    # a tracker re-sending its last frame
    track[50:53] += 0.2                           # a jump of 20 cm
    track[100:110] = np.nan                       # a dropout
    assert track_jitter(t, track) == pytest.approx(0.001, rel=0.15)


def test_a_smooth_motion_alone_has_almost_no_jitter():
    t = np.arange(0.0, 2.5, 0.01)
    assert track_jitter(t, reach(t)) < 1e-4          # curvature at 100 Hz: < 0.1 mm


def test_too_few_samples_give_no_estimate():
    t = np.arange(4) * 0.01
    assert residuals(t[:2], np.arange(2.0)).size == 0
    with pytest.raises(ValueError, match="values: expected shape"):
        residuals(t, np.arange(2.0))
    assert track_jitter(t[:3], np.ones((3, 3)) * np.arange(3)[:, None]) is None   # 3 residuals
    assert np.isnan(jitter(t, np.zeros((4, 2)) + np.arange(4)[:, None])).all()


def demos(sigma: float, n: int = 3, seed: int = 0) -> list[Demonstration]:
    """Unfiltered demos (two tasks) whose hand has tracker noise ``sigma`` (m)."""
    rng = np.random.default_rng(seed)
    out = []
    for task, sign in (("a", 1.0), ("b", -1.0)):
        for _ in range(n):
            duration = rng.uniform(1.8, 2.2)
            t = np.arange(0.0, duration, 0.01)
            hand = reach(t, duration) * [1, sign, 1] + rng.normal(0.0, sigma, (t.size, 3))
            robot = np.column_stack([np.linspace(0, 0.5 * sign, t.size)] * 7)
            out.append(Demonstration(t, hand, robot + rng.normal(0, 0.01, 7), task))
    return out


@pytest.mark.parametrize("sigma", [0.001, 0.02])
def test_the_floor_is_k_times_the_jitter_above_the_noise_floor(sigma):
    model = IProMP(n_basis=11, jitter_floor=3.0, noise_floor=0.002).fit(demos(sigma))
    assert np.allclose(model.floors_used, max(0.002, 3.0 * sigma), rtol=0.15)
    assert np.all(np.sqrt(model.noise) >= model.floors_used - 1e-12)
    default = IProMP(n_basis=11).fit(demos(sigma)).floors_used       # max(2 cm, 15 x jitter)
    assert np.allclose(default, max(0.02, JITTER_FACTOR * sigma), rtol=0.15)
    assert np.allclose(IProMP(n_basis=11, jitter_floor=None).fit(demos(sigma)).floors_used, 0.02)


def test_a_noisier_tracker_raises_the_default_floor_a_quieter_one_keeps_the_minimum():
    quiet, noisy = (IProMP(n_basis=11).fit(demos(s)).floors_used[0] for s in (0.0005, 0.004))
    assert quiet == 0.02 and noisy == pytest.approx(JITTER_FACTOR * 0.004, rel=0.15)


def test_auto_searches_without_the_jitter():
    fits = IProMP(n_basis=11, noise_floor="auto").fit(demos(0.004)).floors_used
    off = IProMP(n_basis=11, noise_floor="auto", jitter_floor=None).fit(demos(0.004)).floors_used
    assert np.array_equal(fits, off)


def test_the_jitter_a_loader_measured_wins_over_the_smoothed_track():
    raw = demos(0.0)
    told = [d.replace(meta={"report": {"modalities": {"hand": {"jitter_m": 0.004}}}})
            for d in raw]
    assert told[0].jitter == {"hand": 0.004}
    model = IProMP(n_basis=11, jitter_floor=2.0, noise_floor=0.002).fit(told)
    assert np.allclose(model.floors_used, 0.008)


def test_an_explicit_floor_still_wins_and_the_option_survives_the_file(tmp_path):
    model = IProMP(n_basis=11, jitter_floor=3.0, noise_floors={"hand": 0.05}).fit(demos(0.001))
    assert np.allclose(model.floors_used, 0.05)
    model.save(tmp_path / "m.npz")
    loaded = IProMP.load(tmp_path / "m.npz")
    assert loaded.jitter_floor == 3.0 and loaded.robot_space == "joint"
    IProMP(n_basis=11, jitter_floor=None).fit(demos(0.001)).save(tmp_path / "off.npz")
    assert IProMP.load(tmp_path / "off.npz").jitter_floor is None     # null, not the default


@pytest.mark.parametrize("bad", [0, -1.0, "3", float("nan"), True])
def test_a_bad_factor_is_refused(bad):
    with pytest.raises(ValueError, match="jitter_floor: expected"):
        IProMP(jitter_floor=bad)

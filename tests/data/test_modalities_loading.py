"""Loading several modalities: positions per tracked point, signals as envelopes."""

import numpy as np
import pytest

from sandbox.data import Demonstration
from sandbox.data.recorded import (
    ROBOT_COLUMNS,
    SkippedTrialWarning,
    TrialError,
    load_recorded,
    load_trial,
)
from sandbox.data.spec import ARM, EMG, HAND

from .test_recorded import write_csv

HEADER = ["t", *HAND.dims, *ARM.dims, *EMG.dims, *ROBOT_COLUMNS]


def rows(n_frames=45, seed=0, emg=None):
    """A 30 Hz skeleton re-sent in bursts, EMG at ~50 Hz, a smooth robot."""
    rng = np.random.default_rng(seed)
    out, t = [], 0.0
    for k in range(n_frames):
        hand = [1.1 - 0.01 * k, -0.1 + 0.008 * k, 0.25]
        elbow = [1.2 - 0.006 * k, 0.1, 0.25]
        shoulder = [1.35, 0.2 + 0.001 * k, 0.35]
        for repeat in range(3):
            level = 300 + 200 * np.sin(0.1 * k) if emg is None else emg
            channels = (level * (1 + 0.2 * rng.standard_normal(8))).round()
            out.append([round(t, 4), *hand, *elbow, *shoulder, *channels,
                        *(0.1 * np.arange(7) + 0.01 * t)])
            t += 0.0 if repeat == 0 else 0.011
    return out


@pytest.fixture
def trial(tmp_path):
    return write_csv(tmp_path / "set" / "reach" / "a.csv", HEADER, rows())


def test_three_modalities_load_in_order(trial):
    demo = load_trial(trial, observe="hand,arm,emg", preprocess="causal")
    assert [m.name for m in demo.modalities] == ["hand", "arm", "emg"]
    assert demo.human.shape[1] == 17 and demo.human_names == HAND.dims + ARM.dims + EMG.dims
    measured = demo.meta["modality_measured"]
    assert measured.shape == (demo.n_steps, 3)
    np.testing.assert_array_equal(demo.meta["human_measured"], measured.any(axis=1))
    for i, m in enumerate(demo.modalities):
        cols = demo.human[:, [demo.human_names.index(d) for d in m.dims]]
        assert np.isfinite(cols[measured[:, i]]).all() and np.isnan(cols[~measured[:, i]]).all()
    emg_t = demo.times[measured[:, 2]]
    assert np.diff(emg_t).min() >= 1 / 30 - 1e-9          # thinned to the tracker's rate
    assert set(demo.meta["report"]["modalities"]) == {"hand", "arm", "emg"}
    smooth = load_trial(trial, observe="hand,arm,emg")
    assert np.isfinite(smooth.human[5:-5]).all()
    assert (smooth.human[:, -8:][np.isfinite(smooth.human[:, -8:])] > 0).all()


def test_select_keeps_the_named_modalities(trial):
    demo = load_trial(trial, observe=["hand", "arm", "emg"])
    emg = demo.select("emg")
    assert [m.name for m in emg.modalities] == ["emg"] and emg.human.shape[1] == 8
    np.testing.assert_array_equal(emg.human, demo.human[:, 9:])
    both = demo.select(["emg", "hand"])
    np.testing.assert_array_equal(both.human[:, 8:], demo.human[:, :3])
    assert both.meta["modality_measured"].shape == (demo.n_steps, 2)
    with pytest.raises(ValueError, match=r"has \['hand', 'arm', 'emg'\].*\['eeg'\]"):
        demo.select("eeg")


def test_causal_envelope_uses_no_future_row(tmp_path):
    full = rows(seed=3)
    a = write_csv(tmp_path / "x" / "t" / "a.csv", HEADER, full)
    cut = len(full) // 2
    changed = [r[:10] + [v * 3 for v in r[10:18]] + r[18:] for r in full[cut:]]
    b = write_csv(tmp_path / "y" / "t" / "a.csv", HEADER, full[:cut] + changed)
    da = load_trial(a, observe="emg", preprocess="causal")
    db = load_trial(b, observe="emg", preprocess="causal")
    before = da.times < full[cut][0] - 1e-9
    np.testing.assert_array_equal(da.human[before], db.human[before])
    assert not np.allclose(da.human[~before], db.human[~before], equal_nan=True)


def test_missing_column_names_it_the_file_and_the_fix(tmp_path):
    header = [h for h in HEADER if h != "emg3"]
    path = write_csv(tmp_path / "s" / "t" / "a.csv", header,
                     [r[:13] + r[14:] for r in rows()])
    with pytest.raises(TrialError, match=r"a\.csv: missing column 'emg3'.*modality 'emg'.*"
                                         r"--spec FILE.*--observe"):
        load_trial(path, observe="hand,emg")
    assert load_trial(path, observe="hand,arm").human.shape[1] == 9


@pytest.mark.parametrize("level", [250.0, np.nan])
def test_constant_or_missing_emg_skips_the_trial_with_a_reason(tmp_path, level):
    root = tmp_path / "set"
    write_csv(root / "t" / "good.csv", HEADER, rows())
    bad = [r[:10] + [level] * 8 + r[18:] for r in rows(seed=1)]
    write_csv(root / "t" / "flat.csv", HEADER, bad)
    with pytest.warns(SkippedTrialWarning, match="flat.csv"):
        demos, skipped = load_recorded(root, observe="hand,emg")
    assert [d.source.endswith("good.csv") for d in demos] == [True]
    assert "modality 'emg'" in skipped[0][1] and "no signal" in skipped[0][1]
    kept, none = load_recorded(root, observe="hand")          # the hand alone is fine
    assert len(kept) == 2 and none == []


def test_demonstration_checks_modalities():
    t = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match="expected 3 human dims in all, got 17"):
        Demonstration(t, np.zeros((5, 3)), np.zeros((5, 7)), "a", modalities=(HAND, ARM, EMG))
    d = Demonstration(t, np.zeros((5, 3)), np.zeros((5, 7)), "a")
    assert d.modalities[0].name == "hand" and "observe=hand" in repr(d)


def test_recorded_set_all_modalities(recorded_dir):
    path = sorted((recorded_dir / "pencil_box").glob("*.csv"))[0]
    causal = load_trial(path, observe="hand,arm,emg", preprocess="causal")
    smooth = load_trial(path, observe="hand,arm,emg")
    report = causal.meta["report"]["modalities"]
    assert report["emg"]["signal_fresh_rows"] > 40 * causal.duration
    assert report["arm"]["new_frames"] > 2 * 25 * causal.duration        # two points
    rate = causal.meta["modality_measured"].sum(axis=0) / causal.duration
    assert 15 < rate[2] <= 31 and 20 < rate[0] < 35
    assert np.isfinite(smooth.human[10:-10]).mean() > 0.99

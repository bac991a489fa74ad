"""Synthetic sets that observe the arm: shared tracker frames, unchanged hand, loading."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.datasets import load_dataset
from sandbox.data.spec import ARM, HAND
from sandbox.data.synthetic import (
    DATASETS,
    ArmModel,
    TrackerModel,
    intent_switch_demo,
    make_dataset,
)
from sandbox.data.synthetic.base import sample_times
from sandbox.data.synthetic.observe import check_observe
from sandbox.data.synthetic.tracker import track_arm, track_hand

TIMES = sample_times(2.2, 100.0)
CLEAN = np.column_stack([1.1 - 0.3 * TIMES / 2.2, -0.1 + 0.3 * TIMES / 2.2, 0.2 + 0 * TIMES])
CLEAN_ARM = np.column_stack([CLEAN + [0.1, 0.2, 0.0], np.tile([1.35, 0.0, 0.34], (TIMES.size, 1))])


def _track(model: TrackerModel, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    hand, schedule = track_hand(TIMES, CLEAN, model, np.random.default_rng(seed))
    arm = track_arm(TIMES, CLEAN_ARM, model, schedule, np.random.default_rng(seed + 100))
    return hand, arm


def _stale(x: np.ndarray) -> np.ndarray:
    """Rows that repeat the previous row exactly (sample-and-hold)."""
    return np.r_[False, np.all(x[1:] == x[:-1], axis=1)]


@pytest.mark.parametrize("seed", range(5))
def test_hand_and_arm_share_the_tracker_frames(seed):
    hand, arm = _track(TrackerModel(), seed)
    stale = _stale(hand)
    assert 0.5 < stale.mean() < 0.8  # ~30 frames/s on 100 Hz rows
    assert np.array_equal(stale, _stale(arm[:, :3])) and np.array_equal(stale, _stale(arm[:, 3:]))


def test_a_lost_frame_loses_the_whole_skeleton():
    hand, arm = _track(TrackerModel(dropout_rate=0.2, zero_rate=0.1), 1)
    lost = np.isnan(hand).all(axis=1)
    zero = np.all(hand == 0.0, axis=1)
    assert lost.any() and zero.any()
    assert np.array_equal(lost, np.isnan(arm).all(axis=1))
    assert np.array_equal(zero, np.all(arm == 0.0, axis=1))
    assert not np.isnan(arm[~lost]).any()


def test_clean_tracker_reports_the_clean_arm():
    hand, arm = _track(TrackerModel.clean())
    assert np.array_equal(hand, CLEAN) and np.array_equal(arm, CLEAN_ARM)


def test_elbow_jitters_and_jumps_like_the_hand_the_shoulder_less():
    jumps = {"hand": 0, "elbow": 0, "shoulder": 0}
    for seed in range(40):
        hand, arm = _track(TrackerModel(), seed)
        for name, x, clean in (("hand", hand, CLEAN), ("elbow", arm[:, :3], CLEAN_ARM[:, :3]),
                               ("shoulder", arm[:, 3:], CLEAN_ARM[:, 3:])):
            jumps[name] += int(np.any(np.linalg.norm(x - clean, axis=1) >= 0.05))
    assert jumps["shoulder"] == 0
    # recorded: 74 % of trials show hand jumps, 50 % elbow jumps
    assert 0.5 * jumps["hand"] <= jumps["elbow"] <= jumps["hand"] + 5
    hand, arm = _track(TrackerModel(glitch_rate=0.0, frame_hz=None), 3)
    elbow_noise = np.std(arm[:, :3] - CLEAN_ARM[:, :3])
    shoulder_noise = np.std(arm[:, 3:] - CLEAN_ARM[:, 3:])
    assert elbow_noise == pytest.approx(0.002, rel=0.3)
    assert shoulder_noise == pytest.approx(0.4 * 0.002, rel=0.3)


@pytest.mark.parametrize("name", DATASETS)
def test_the_hand_is_bit_identical_with_and_without_the_arm(name):
    n = 2
    alone = make_dataset(name, n, np.random.default_rng(5))
    both = make_dataset(name, n, np.random.default_rng(5), observe="hand,arm")
    assert len(alone) == len(both)
    for a, b in zip(alone, both, strict=True):
        assert np.array_equal(a.human, b.human[:, :3], equal_nan=True)
        assert np.array_equal(a.robot, b.robot) and np.array_equal(a.times, b.times)
        assert [m.name for m in a.modalities] == ["hand"] and a.human_names == HAND.dims
        assert b.modalities == (HAND, ARM) and b.human.shape[1] == 9
        assert b.meta["clean_arm"].shape == (b.n_steps, 6)
        assert b.meta["clean_human"].shape == (b.n_steps, 3)
        assert "clean_arm" not in a.meta


def test_intent_switch_carries_the_arm_and_keeps_the_hand():
    alone, _ = intent_switch_demo("left", "up", 0.5, np.random.default_rng(2))
    both, truth = intent_switch_demo("left", "up", 0.5, np.random.default_rng(2),
                                     observe=("hand", "arm"))
    assert np.array_equal(alone.human, both.human[:, :3])
    assert both.modalities == (HAND, ARM) and both.meta["clean_arm"].shape == (both.n_steps, 6)
    assert truth.tasks == ("left", "up")


def test_arm_datasets_are_seeded_and_follow_the_observe_order():
    a = make_dataset("diverging", 1, np.random.default_rng(0), observe="hand,arm")
    b = make_dataset("diverging", 1, np.random.default_rng(0), observe=["hand", "arm"])
    c = make_dataset("diverging", 1, np.random.default_rng(1), observe="hand,arm")
    assert all(np.array_equal(x.human, y.human) for x, y in zip(a, b, strict=True))
    assert not np.allclose(a[0].meta["clean_arm"][0], c[0].meta["clean_arm"][0])
    arm_first = make_dataset("objects", 1, np.random.default_rng(0), observe="arm,hand")
    assert arm_first[0].modalities == (ARM, HAND)
    objects = make_dataset("objects", 1, np.random.default_rng(0), observe="hand,arm")
    assert np.array_equal(arm_first[0].human[:, :6], objects[0].human[:, 3:])
    only = make_dataset("two_task", 2, np.random.default_rng(0), observe="arm")
    assert only[0].modalities == (ARM,) and only[0].human.shape[1] == 6


@pytest.mark.parametrize(
    "observe, match",
    [
        ("hand,emg", "EMG is not simulated"),
        ("hand,hand", "distinct"),
        ("", "distinct"),
        ("wrist", "synthetic sets carry the hand and the arm"),
        (3, "observe"),
    ],
)
def test_bad_observe_is_refused(observe, match):
    with pytest.raises(ValueError, match=match):
        check_observe(observe)
    with pytest.raises(ValueError, match=match):
        make_dataset("two_task", 2, np.random.default_rng(0), observe=observe)


def test_load_dataset_gives_preprocessed_hand_and_arm():
    demos = load_dataset("synthetic:two_task", observe="hand,arm", n_per_task=2)
    assert len(demos) == 4
    for demo in demos:
        assert demo.modalities == (HAND, ARM) and demo.human.shape == (demo.n_steps, 9)
        assert np.isfinite(demo.human).all()
        assert set(demo.meta["report"]["modalities"]) == {"hand", "arm"}
        assert demo.meta["modality_measured"].shape == (demo.n_steps, 2)
    arm = load_dataset("synthetic:diverging", observe=["arm"], n_per_task=1, tasks=["left"],
                       preprocess="none")
    assert arm[0].modalities == (ARM,) and arm[0].human.shape[1] == 6
    hand = load_dataset("synthetic:diverging", n_per_task=1, tasks=["left"], preprocess="none")
    full = load_dataset("synthetic:diverging", observe="hand,arm", n_per_task=1, tasks=["left"],
                        preprocess="none")
    assert np.array_equal(hand[0].human, full[0].human[:, :3])
    assert np.array_equal(arm[0].human, full[0].human[:, 3:], equal_nan=True)


def test_load_dataset_refuses_emg_on_synthetic_sets():
    with pytest.raises(ValueError, match="EMG is not simulated: synthetic sets carry the hand"):
        load_dataset("synthetic:two_task", observe="hand,emg", n_per_task=2)


@pytest.mark.parametrize("name", DATASETS)
def test_the_arm_model_reaches_every_generator(name):
    demos = make_dataset(name, 2, np.random.default_rng(0), observe="hand,arm",
                         arm_model=ArmModel.still())
    for demo in demos:
        shoulder = demo.meta["clean_arm"][:, 3:]
        assert np.allclose(shoulder, shoulder[0])
    demo, _ = intent_switch_demo("box", "tape", 0.4, np.random.default_rng(0), family="objects",
                                 observe="hand,arm", arm_model=ArmModel.still())
    assert np.allclose(demo.meta["clean_arm"][:, 3:], demo.meta["clean_arm"][0, 3:])


def test_a_model_fits_on_the_synthetic_hand_and_arm(tmp_path, capsys):
    from sandbox.cli import main
    from sandbox.core import IProMP

    out = tmp_path / "m.npz"
    assert main(["fit", "--data", "synthetic:two_task", "--observe", "hand,arm",
                 "--n-per-task", "3", "--out", str(out)]) == 0
    model = IProMP.load(out)
    assert model.modalities == (HAND, ARM) and len(model.human_names) == 9
    assert "arm observation noise" in capsys.readouterr().out

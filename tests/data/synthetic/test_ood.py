"""Synthetic out-of-distribution families (sandbox.data.synthetic.ood): each differs from
the training family in the way its name says, and the training family is untouched."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.datasets import load_dataset
from sandbox.data.synthetic import DATASETS, TrackerModel, diverging_demos, make_dataset
from sandbox.data.synthetic.families import DIVERGING_VARIABILITY, diverging_specs
from sandbox.data.synthetic.ood import (
    MARGIN_M,
    OOD_FAMILIES,
    PAUSE_S,
    ood_demos,
    parse_name,
    pause_warp,
)

CLEAN = TrackerModel.clean()


def family(name: str, n: int = 3, seed: int = 0, **kw):
    return ood_demos(name, n, np.random.default_rng(seed), tracker=CLEAN, **kw)


@pytest.fixture(scope="module")
def normal():
    return diverging_demos(6, np.random.default_rng(0), tracker=CLEAN)


def speed(demo) -> np.ndarray:
    """Speed (m/s) of the clean hand between rows."""
    clean = demo.meta["clean_human"]
    return np.linalg.norm(np.diff(clean, axis=0), axis=1) / np.diff(demo.times)


def test_pause_has_a_stretch_of_zero_speed_mid_reach(normal):
    for d in family("pause"):
        start, end = d.meta["pause_time"]
        assert PAUSE_S[0] - 0.2 <= end - start <= PAUSE_S[1]
        inside = (d.times[1:] > start + 0.02) & (d.times[:-1] < end - 0.02)
        assert inside.sum() > 50 and np.all(speed(d)[inside] < 1e-6)
        before, after = d.times[1:] < start, d.times[:-1] > end
        assert speed(d)[before].max() > 0.1 and speed(d)[after].max() > 0.05
        assert start < d.meta["handover_time"] <= d.duration
    # a normal reach never holds still that long before it ends
    for d in normal:
        moving = d.times[1:] < d.meta["reach_time"][1] - 0.3
        assert speed(d)[moving & (d.times[1:] > 0.3)].min() > 1e-3


def test_pause_warp_stops_the_clock_and_keeps_the_rest():
    t = np.linspace(0.0, 5.0, 5001)
    clock = pause_warp(t, 1.0, 1.2, 0.15)
    rate = np.diff(clock) / np.diff(t)
    assert np.all(rate >= -1e-12) and np.all(rate <= 1 + 1e-9)
    assert np.allclose(clock[t < 1.0], t[t < 1.0])
    assert np.allclose(rate[(t[1:] > 1.2) & (t[1:] < 2.1)], 0.0, atol=1e-9)
    assert clock[-1] == pytest.approx(5.0 - 1.2, abs=1e-3)


def test_speed_durations_are_outside_the_demos_range(normal):
    lo, hi = DIVERGING_VARIABILITY.duration_range
    durations = [d.duration for d in family("speed")]
    assert all(t > hi or t < lo for t in durations)
    assert any(t > hi for t in durations) and any(t < lo for t in durations)
    assert all(lo <= d.duration <= hi for d in normal)


def test_endpoints_lie_outside_every_task(normal):
    ends = np.array([s.end + s.branch for s in diverging_specs()])
    for d in family("endpoint"):
        hand = d.meta["clean_human"][-1]
        assert np.linalg.norm(ends - d.meta["odd_end"], axis=1).min() >= MARGIN_M - 1e-9
        assert np.linalg.norm(ends - hand, axis=1).min() > 0.08
        assert d.task == "endpoint"
    for d in normal:          # a normal motion ends near its task's mean end
        assert np.linalg.norm(ends - d.meta["clean_human"][-1], axis=1).min() < 0.08


def test_other_is_another_family_with_its_own_tasks():
    other = family("other", n=2)
    assert {d.task for d in other} == {"box", "glasses_case", "tape"}
    assert {d.task for d in family("other", n=1, base="objects")} == {
        "left", "right", "up", "down", "straight"}
    assert all(d.source.startswith("synthetic-ood:other[") for d in other)


def test_still_hand_does_not_move_while_the_robot_does():
    for d in family("still"):
        assert np.all(speed(d) == 0.0)
        assert np.ptp(d.robot, axis=0).max() > 0.1
        assert d.task == "still" and 0 < d.meta["handover_time"] <= d.duration


@pytest.mark.parametrize("name", OOD_FAMILIES)
def test_every_family_has_the_training_format_and_is_seeded(name, normal):
    a, b = family(name, n=1, seed=3), family(name, n=1, seed=3)
    assert [d.source for d in a] == [d.source for d in b]
    assert all(np.array_equal(x.human, y.human, equal_nan=True) for x, y in zip(a, b))
    for d in a:
        assert d.human.shape[1] == normal[0].human.shape[1]
        assert d.robot_names == normal[0].robot_names
        assert [m.name for m in d.modalities] == ["hand"]
        assert d.meta["ood"] == name and d.source.startswith(f"synthetic-ood:{name}[")


def test_the_arm_is_observed_too():
    d = family("pause", n=1, observe="hand,arm")[0]
    assert d.human.shape[1] == 9 and [m.name for m in d.modalities] == ["hand", "arm"]


def test_ood_sets_leave_the_training_family_and_its_stream_untouched():
    assert not set(OOD_FAMILIES) & set(DATASETS)
    rng = np.random.default_rng(5)
    ood_demos("pause", 1, rng, tracker=CLEAN)
    after = diverging_demos(2, rng, tracker=CLEAN)
    fresh = diverging_demos(2, np.random.default_rng(5), tracker=CLEAN)
    assert all(np.array_equal(x.human, y.human) for x, y in zip(after, fresh))
    # the same seed does not replay a training demonstration's draw
    pause = family("pause", n=1, seed=5)[0]
    assert not np.allclose(pause.meta["clean_human"][0], fresh[0].meta["clean_human"][0])


def test_loaded_by_name_like_the_synthetic_sets():
    demos = load_dataset("synthetic-ood:speed@objects", n_per_task=1, preprocess="none")
    assert [d.task for d in demos] == ["box", "glasses_case", "tape"]
    normal = make_dataset("objects", 1, np.random.default_rng(0))
    assert [d.task for d in normal] == [d.task for d in demos]
    assert load_dataset("synthetic-ood:still", n_per_task=1, tasks=["still"])


@pytest.mark.parametrize("name, match", [("nope", "FAMILY one of"), ("pause@two_task", "BASE"),
                                         ("", "FAMILY")])
def test_bad_names_are_one_line_errors(name, match):
    with pytest.raises(ValueError, match=match):
        parse_name(name)
    with pytest.raises(ValueError, match=match):
        load_dataset(f"synthetic-ood:{name}", n_per_task=1)


@pytest.mark.parametrize("kwargs, match", [({"family": "x"}, "family"),
                                           ({"base": "two_task"}, "base"),
                                           ({"n_per_task": 0}, "n_per_task"),
                                           ({"rng": 3}, "rng")])
def test_bad_arguments_are_refused(kwargs, match):
    args = {"family": "pause", "n_per_task": 1, "rng": np.random.default_rng(0), **kwargs}
    with pytest.raises(ValueError, match=match):
        ood_demos(args.pop("family"), args.pop("n_per_task"), args.pop("rng"), **args)


def test_a_session_is_refused():
    with pytest.raises(ValueError, match="session"):
        load_dataset("synthetic-ood:pause", n_per_task=1, session=1)

"""Hand motions: synthetic (seeded) and recorded replays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandbox.data.recorded import load_trial
from sandbox.envs.sources import (
    FAMILIES,
    family_tasks,
    pick_trial,
    recorded_motion,
    recorded_trials,
    synthetic_motion,
)


def test_family_tasks():
    assert family_tasks("objects") == ("box", "glasses_case", "tape")
    assert family_tasks("diverging") == ("left", "right", "up", "down", "straight")
    assert FAMILIES == ("objects", "diverging")
    with pytest.raises(ValueError, match="family"):
        family_tasks("kitchen")


def test_synthetic_motion_is_seeded_and_of_its_task():
    a = synthetic_motion("diverging", "down", np.random.default_rng(3))
    b = synthetic_motion("diverging", "down", np.random.default_rng(3))
    c = synthetic_motion("diverging", "down", np.random.default_rng(4))
    assert a.task == "down" and a.times[0] == 0.0
    np.testing.assert_array_equal(a.true, b.true)
    np.testing.assert_array_equal(a.measured, b.measured)
    assert not np.array_equal(a.true, c.true)
    assert 1.7 <= a.duration <= 4.0
    # the tracker's measurements stay near the true path, but are not it
    err = np.linalg.norm(a.measured - a.true, axis=1)
    assert np.median(err) < 0.02 and err.max() > 0


def test_synthetic_handover_target_is_near_the_resting_hand():
    motion = synthetic_motion("objects", "glasses_case", np.random.default_rng(0))
    assert np.linalg.norm(motion.meta["handover_target"] - motion.true[-1]) < 0.08


def test_synthetic_refuses_unknown_tasks():
    with pytest.raises(ValueError, match="task: expected one of"):
        synthetic_motion("objects", "left", np.random.default_rng(0))
    with pytest.raises(ValueError, match="task"):
        synthetic_motion("diverging", "left", np.random.default_rng(0), switch_to="sideways")


def test_pick_trial():
    trials = [("a", Path("a/x1.csv")), ("a", Path("a/x2.csv")), ("b", Path("b/y.csv"))]
    rng = np.random.default_rng(0)
    assert pick_trial(trials, 1, rng) == trials[1]
    assert pick_trial(trials, "y", rng) == trials[2]
    assert pick_trial(trials, "x1.csv", rng) == trials[0]
    assert pick_trial(trials, None, rng) in trials
    for bad, match in ((3, "index in"), (-1, "index"), ("zz", "file name"), (1.5, "index, a")):
        with pytest.raises(ValueError, match=match):
            pick_trial(trials, bad, rng)


def test_recorded_replay(recorded_dir):
    rng = np.random.default_rng(0)
    trials = recorded_trials(recorded_dir, "pencil_box")
    motion = recorded_motion(recorded_dir, "pencil_box", 0, rng)
    assert motion.task == "pencil_box" and motion.source == str(trials[0][1])
    assert motion.times[0] == 0.0 and 1.5 < motion.duration < 5.0
    assert np.isfinite(motion.true).all()
    assert np.isnan(motion.measured).any()  # only accepted tracker frames
    valid = np.isfinite(motion.measured).all(axis=1)
    assert np.median(np.linalg.norm(motion.measured[valid] - motion.true[valid], axis=1)) < 0.02
    by_name = recorded_motion(recorded_dir, "pencil_box", trials[0][1].stem, rng)
    np.testing.assert_array_equal(by_name.true, motion.true)


def test_recorded_unknown_task(recorded_dir):
    with pytest.raises(ValueError, match="tasks: expected some of"):
        recorded_motion(recorded_dir, "juggling", None, np.random.default_rng(0))


def test_env_replays_a_recorded_trial(objects_env, recorded_dir):
    obs, info = objects_env.reset(seed=0, options={"source": str(recorded_dir),
                                                   "task": "screw_driver", "trial": 2})
    assert (info["task"], info["object"]) == ("screw_driver", "screwdriver")
    motion = objects_env.unwrapped.motion
    np.testing.assert_allclose(obs["hand"], motion.measurement(0.0))
    for _ in range(50):
        obs, *_ = objects_env.step(np.append(obs["q"], -1.0))
    np.testing.assert_allclose(obs["hand"], motion.measurement(1.0))


def test_synthetic_motion_carries_the_arm_of_its_demonstration():
    from sandbox.data.synthetic.families import DIVERGING_VARIABILITY, diverging_specs
    from sandbox.data.synthetic.generator import generate

    motion = synthetic_motion("diverging", "left", np.random.default_rng(5))
    spec = [s for s in diverging_specs() if s.name == "left"]
    (demo,) = generate(spec, 1, np.random.default_rng(5), family="diverging",
                       variability=DIVERGING_VARIABILITY, observe=("hand", "arm"))
    assert set(motion.body) == {"arm"}  # no EMG: it is not simulated
    np.testing.assert_array_equal(motion.body["arm"], demo.select("arm").human)
    np.testing.assert_array_equal(motion.measured, demo.select("hand").human)
    switch = synthetic_motion("diverging", "up", np.random.default_rng(1), switch_to="right")
    assert switch.body["arm"].shape == (switch.times.size, 6)


def test_recorded_replay_carries_the_causal_arm_and_emg(recorded_dir):
    motion = recorded_motion(recorded_dir, "gummed_paper", 0, np.random.default_rng(0))
    causal = load_trial(motion.source, task="gummed_paper", observe=("hand", "arm", "emg"),
                        preprocess="causal")
    np.testing.assert_array_equal(motion.body["arm"], causal.select("arm").human)
    np.testing.assert_array_equal(motion.body["emg"], causal.select("emg").human)
    np.testing.assert_array_equal(motion.measured, causal.select("hand").human)
    assert np.isnan(motion.body["arm"]).any()  # only accepted tracker frames


def test_recorded_trial_without_emg_columns_has_no_emg(recorded_dir, tmp_path):
    import csv

    source = recorded_trials(recorded_dir, "pencil_box")[0][1]
    with open(source, newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if not name.strip().startswith("emg")]
    assert len(keep) < len(rows[0])
    (tmp_path / "pencil_box").mkdir()
    with open(tmp_path / "pencil_box" / source.name, "w", newline="") as f:
        csv.writer(f).writerows([[r[i] for i in keep if i < len(r)] for r in rows])
    motion = recorded_motion(tmp_path, "pencil_box", 0, np.random.default_rng(0))
    full = recorded_motion(recorded_dir, "pencil_box", 0, np.random.default_rng(0))
    assert set(motion.body) == {"arm"} and set(full.body) == {"arm", "emg"}
    np.testing.assert_array_equal(motion.body["arm"], full.body["arm"])
    assert np.isnan(motion.body_measurement("emg", 1.0)).all()


def test_a_session_motion_is_the_tracked_hand_with_its_meeting_and_robot():
    from sandbox.data.synthetic import Variability
    from sandbox.data.synthetic.families import OBJECTS
    from sandbox.data.synthetic.generator import generate

    motion = synthetic_motion("objects", "tape", np.random.default_rng(2), session=4)
    again = synthetic_motion("objects", "tape", np.random.default_rng(2), session=4)
    np.testing.assert_array_equal(motion.true, again.true)
    np.testing.assert_array_equal(motion.measured, again.measured)
    (demo,) = generate([OBJECTS[2]], 1, np.random.default_rng(2), family="objects",
                       variability=Variability(), observe=("hand", "arm"), session=4)
    np.testing.assert_array_equal(motion.true, demo.meta["tracked_clean"])
    np.testing.assert_array_equal(motion.measured, demo.select("hand").human)
    np.testing.assert_array_equal(motion.meta["meeting_offset"], demo.meta["meeting_offset"])
    np.testing.assert_array_equal(motion.meta["robot"]["joints"], demo.robot)
    np.testing.assert_array_equal(motion.meta["robot"]["times"], motion.times)
    with pytest.raises(ValueError, match="^session: expected None with switch_to"):
        synthetic_motion("objects", "tape", np.random.default_rng(2), switch_to="box", session=1)


def test_without_a_session_the_meeting_offset_is_measured_on_the_true_hand():
    from sandbox.robot import TIP_LINK, BaxterKinematics

    for switch_to in (None, "box"):
        motion = synthetic_motion("objects", "tape", np.random.default_rng(2),
                                  switch_to=switch_to)
        assert "session" not in motion.meta
        tip = BaxterKinematics().fk(motion.meta["robot"]["joints"], link=TIP_LINK)
        gaps = np.linalg.norm(tip - motion.true - motion.meta["meeting_offset"], axis=1)
        assert gaps.min() < 1e-12                        # it is the offset at one of the rows
        assert np.linalg.norm(motion.meta["meeting_offset"]) < 0.1

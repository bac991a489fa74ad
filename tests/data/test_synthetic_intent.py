"""Intent switch: task a until the switch, then task b, with its ground truth."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic import IntentSwitch, TrackerModel, intent_switch_demo
from sandbox.robot import TIP_LINK, BaxterKinematics


def _demo(a, b, phase=0.6, seed=3, **kwargs):
    return intent_switch_demo(a, b, phase, np.random.default_rng(seed),
                              tracker=TrackerModel.clean(), **kwargs)


def test_ground_truth_says_which_task_at_which_time():
    demo, truth = _demo("left", "right", 0.6)
    assert isinstance(truth, IntentSwitch) and demo.meta["intent"] is truth
    assert truth.tasks == ("left", "right") and demo.task == "right"
    assert truth.switch_time == pytest.approx(0.6 * demo.duration)
    labels = truth.labels
    assert labels.shape == (demo.n_steps,)
    assert set(labels[demo.times < truth.switch_time]) == {"left"}
    assert set(labels[demo.times >= truth.switch_time]) == {"right"}
    assert truth.task_at(np.array([0.0, demo.duration])).tolist() == ["left", "right"]


def test_hand_follows_a_then_b_as_the_plain_tasks_would():
    demo, truth = _demo("left", "right", 0.6)
    only_a, _ = _demo("left", "left", 0.6)
    only_b, _ = _demo("right", "right", 0.6)
    before = demo.times <= truth.switch_time
    after = demo.times >= truth.switch_time + truth.blend_s
    assert np.allclose(demo.human[before], only_a.human[before])
    assert np.allclose(demo.human[after], only_b.human[after])
    assert np.allclose(demo.robot[after], only_b.robot[after])
    assert np.abs(np.diff(demo.human, axis=0)).max() < 0.03  # continuous at 100 Hz


def test_robot_ends_at_task_b_handover_point():
    kin = BaxterKinematics()
    for family, a, b in (("diverging", "up", "down"), ("objects", "box", "glasses_case")):
        demo, _ = _demo(a, b, 0.4, family=family)
        error = np.linalg.norm(kin.fk(demo.robot[-1], link=TIP_LINK)
                               - demo.meta["handover_target"])
        assert error <= 0.01


def test_a_switch_is_reproducible_from_the_seed():
    a, _ = intent_switch_demo("left", "up", 0.55, np.random.default_rng(9))
    b, _ = intent_switch_demo("left", "up", 0.55, np.random.default_rng(9))
    assert np.array_equal(a.human, b.human, equal_nan=True) and np.array_equal(a.robot, b.robot)


@pytest.mark.parametrize(
    "args, kwargs, match",
    [
        (("left", "sideways", 0.5), {}, "task"),
        (("box", "left", 0.5), {"family": "objects"}, "task"),
        (("left", "right", 0.5), {"family": "nope"}, "family"),
        (("left", "right", 0.0), {}, "switch_phase"),
        (("left", "right", 1.5), {}, "switch_phase"),
        (("left", "right", 0.5), {"blend_s": 0.0}, "blend_s"),
    ],
)
def test_bad_switch_arguments_are_refused(args, kwargs, match):
    with pytest.raises(ValueError, match=match):
        intent_switch_demo(*args, np.random.default_rng(0), **kwargs)
    with pytest.raises(ValueError, match="rng"):
        intent_switch_demo("left", "right", 0.5, 1)

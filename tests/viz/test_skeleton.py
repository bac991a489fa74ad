"""The tracked arm: beads and segments follow the arm, hidden while it is not valid."""

from __future__ import annotations

import meshcat
import numpy as np
import pytest

from sandbox.viz.scene import Scene, decompose
from sandbox.viz.skeleton import TrackedArm, segment_pose

ELBOW, SHOULDER, HAND = [1.1, 0.1, 0.2], [1.35, 0.0, 0.33], [1.0, -0.15, 0.25]


@pytest.fixture
def drawn():
    scene = Scene(fps=10)
    arm = TrackedArm(meshcat.Visualizer(window=scene)["arm"])
    return scene, arm


def _position(scene, part):
    return scene.timeline.tracks[f"/meshcat/arm/{part}"]["position"]


def _visible(scene, part):
    return scene.timeline.tracks[f"/meshcat/arm/{part}"]["visible"]


def test_the_scene_gets_beads_and_segments_hidden_until_shown(drawn):
    scene, arm = drawn
    for part in TrackedArm.PARTS:
        assert scene.nodes[f"/meshcat/arm/{part}/shape"].object is not None
    assert not any(arm.visible.values())


def test_beads_and_segments_follow_the_arm(drawn):
    scene, arm = drawn
    scene.set_time(0.0)
    assert arm.show(HAND, [*ELBOW, *SHOULDER]) == 4
    scene.set_time(0.1)
    moved = np.add([*ELBOW, *SHOULDER], 0.05)
    arm.show(HAND, moved)
    np.testing.assert_allclose(_position(scene, "elbow")[0], ELBOW)
    np.testing.assert_allclose(_position(scene, "shoulder")[0], SHOULDER)
    np.testing.assert_allclose(_position(scene, "elbow")[1], moved[:3])
    np.testing.assert_allclose(_position(scene, "shoulder")[1], moved[3:])
    np.testing.assert_allclose(_position(scene, "forearm")[0], np.add(ELBOW, HAND) / 2)
    assert all(arm.visible.values())
    assert _visible(scene, "upper") == {0: True, 1: True}


def test_segment_pose_maps_the_unit_cylinder_onto_the_segment():
    pose = segment_pose(SHOULDER, ELBOW)
    ends = pose @ np.array([[0, -0.5, 0, 1], [0, 0.5, 0, 1]]).T
    np.testing.assert_allclose(ends[:3].T, [SHOULDER, ELBOW], atol=1e-12)
    position, _, scale = decompose(pose)
    assert scale[0] == pytest.approx(1.0) and scale[2] == pytest.approx(1.0)
    assert scale[1] == pytest.approx(np.linalg.norm(np.subtract(ELBOW, SHOULDER)))
    np.testing.assert_allclose(segment_pose([0, 0, 0], [0, 0, 1])[:3, 1], [0, 0, 1])
    assert segment_pose(ELBOW, ELBOW) is None
    assert segment_pose(ELBOW, [np.nan] * 3) is None


@pytest.mark.parametrize("arm, valid", [(np.full(6, np.nan), True), (np.zeros(6), True),
                                        ([*ELBOW, *SHOULDER], False),
                                        ([*ELBOW, np.nan, 0.0, 0.3], True)])
def test_an_invalid_arm_is_hidden_not_drawn_at_the_origin(drawn, arm, valid):
    scene, tracked = drawn
    scene.set_time(0.0)
    tracked.show(HAND, [*ELBOW, *SHOULDER])
    scene.set_time(0.2)
    assert tracked.show(HAND, arm, valid=valid) == 0
    assert not any(tracked.visible.values())
    for part in TrackedArm.PARTS:
        assert _visible(scene, part) == {0: True, 2: False}
        assert len(_position(scene, part)) == 1  # no transform sent to the origin


def test_a_hand_dropout_hides_only_the_forearm(drawn):
    scene, arm = drawn
    assert arm.show([np.nan] * 3, [*ELBOW, *SHOULDER]) == 3
    assert arm.visible == {"shoulder": True, "elbow": True, "upper": True, "forearm": False}
    arm.show(None, [*ELBOW, *SHOULDER])
    assert not arm.visible["forearm"]


def test_update_reads_the_source_and_checks_the_arm():
    scene = Scene()
    state = {"arm": np.full(6, np.nan)}
    arm = TrackedArm(meshcat.Visualizer(window=scene)["arm"], lambda: (HAND, state["arm"]))
    assert arm.update() == 0 and not any(arm.visible.values())
    state["arm"] = np.array([*ELBOW, *SHOULDER])
    assert arm.update() == 4 and all(arm.visible.values())
    assert TrackedArm(meshcat.Visualizer(window=Scene())["arm"]).update() == 0
    with pytest.raises(ValueError, match="arm"):
        arm.show(HAND, [1.0, 2.0, 3.0])

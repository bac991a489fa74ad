"""Prediction overlays: incremental paths, one visible prediction, update markers, bars."""

from __future__ import annotations

import meshcat
import numpy as np
import pytest
import umsgpack

from sandbox.viz.overlays import OverlayStyle, PredictionOverlay, facing
from sandbox.viz.scene import Scene

TASKS = ("left", "right")


@pytest.fixture
def drawn():
    scene = Scene(fps=10)
    vis = meshcat.Visualizer(window=scene)
    overlay = PredictionOverlay(vis["overlays"], rng=np.random.default_rng(0), tasks=TASKS,
                                style=OverlayStyle(n_samples=8, max_steps=20))
    return scene, overlay


def _objects(scene, prefix):
    return sorted(k for k, n in scene.nodes.items() if n.object is not None and prefix in k)


def test_paths_are_sent_incrementally(drawn):
    scene, overlay = drawn
    path = np.stack([np.linspace(0, 1, 10), np.zeros(10), np.zeros(10)], 1)
    assert overlay.show_human(path[:4]) == 4
    assert overlay.show_human(path[:4]) == 0  # nothing new
    assert overlay.show_human(path[:7]) == 4  # 3 new points joined to the last one
    assert len(_objects(scene, "overlays/human/")) == 2
    with_gap = path.copy()
    with_gap[8] = np.nan  # a tracker dropout is skipped
    overlay.show_human(with_gap)
    assert len(_objects(scene, "overlays/human/")) == 3


def test_a_shorter_path_starts_over(drawn):
    scene, overlay = drawn
    path = np.random.default_rng(0).normal(size=(6, 3))
    overlay.show_executed(path)
    overlay.show_executed(path[:2])  # a new episode (not recording: the old one is deleted)
    assert len(_objects(scene, "overlays/executed/")) == 1


def test_prediction_path_is_the_forward_kinematics_of_the_mean(drawn):
    from sandbox.robot import BaxterKinematics, q_home

    _, overlay = drawn
    means = q_home() + np.linspace(0, 0.3, 50)[:, None]
    covs = np.tile(1e-4 * np.eye(7), (50, 1, 1))
    path = overlay.show_prediction(means, covs, "left")
    assert len(path) == 20  # thinned to style.max_steps
    kin = BaxterKinematics()
    np.testing.assert_allclose(path[0], kin.fk(means[0], link="left_gripper"))
    np.testing.assert_allclose(path[-1], kin.fk(means[-1], link="left_gripper"))


def test_only_the_latest_prediction_stays_visible_in_a_recording(drawn):
    scene, overlay = drawn
    means, covs = np.zeros((5, 7)), np.tile(1e-4 * np.eye(7), (5, 1, 1))
    scene.set_time(0.0)
    overlay.show_prediction(means, covs, "left")
    scene.set_time(0.5)
    overlay.show_prediction(means + 0.1, covs, "right")
    visible = {a["path"]: a["clip"]["tracks"][0]["keys"] for a in scene.timeline.lower()}
    first = visible["/meshcat/overlays/prediction/u0/path"]
    second = visible["/meshcat/overlays/prediction/u1/path"]
    assert [(k["time"], k["value"]) for k in first] == [(0, True), (5, False)]
    assert [(k["time"], k["value"]) for k in second] == [(0, False), (5, True)]


def test_bars_follow_probabilities_and_speed(drawn):
    scene, overlay = drawn
    overlay.show_tasks({"left": 0.25, "right": 0.75}, alpha=1.5)
    scales = [umsgpack.unpackb(scene.nodes[f"/meshcat/overlays/panel/c{i}/bar"]
                               .properties["scale"])["value"][2] for i in range(3)]
    np.testing.assert_allclose(scales, [0.25, 0.75, 0.75])  # alpha / 2 for the speed bar
    texts = [umsgpack.unpackb(scene.nodes[f"/meshcat/overlays/panel/c{i}/value0"].object)
             ["object"]["textures"][0]["text"] for i in range(3)]
    assert texts == ["25%", "75%", "x1.50"]


@pytest.mark.parametrize(
    "call, match",
    [(lambda o: o.show_tasks({"left": 1.5}, 1.0), "probability"),
     (lambda o: o.show_tasks({"left": 0.5}, 0.0), "alpha"),
     (lambda o: o.show_prediction(np.zeros((3, 7)), np.zeros((3, 7, 7)), "up"), "task"),
     (lambda o: o.show_prediction(np.zeros((3, 6)), np.zeros((3, 6, 6)), "left"), "means"),
     (lambda o: o.show_human(np.zeros((3, 2))), "human"),
     (lambda o: o.mark_update([0, 0], None, "left"), "human_point")],
)
def test_bad_inputs(drawn, call, match):
    with pytest.raises(ValueError, match=match):
        call(drawn[1])


def test_constructor_checks():
    vis = meshcat.Visualizer(window=Scene())
    with pytest.raises(ValueError, match="rng"):
        PredictionOverlay(vis, rng=0, tasks=TASKS)
    with pytest.raises(ValueError, match="tasks"):
        PredictionOverlay(vis, rng=np.random.default_rng(0), tasks=())


def test_facing_pose_is_a_rotation_looking_at_the_point():
    pose = facing([0, 0, 1], [3, 4, 7])
    np.testing.assert_allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(pose[:3, 0], [0.6, 0.8, 0])
    np.testing.assert_allclose(pose[:3, 2], [0, 0, 1])


@pytest.fixture(scope="module")
def streamed():
    """A dynamic predictor fed a held-out synthetic handover, shown every 1/30 s."""
    from sandbox.core import DynamicPredictor, IProMP
    from sandbox.data.synthetic import two_task_demos

    demos = two_task_demos(8, np.random.default_rng(0))
    predictor = DynamicPredictor(IProMP(n_basis=15).fit(demos[1:]), dow_t=0.25)
    scene = Scene(fps=30)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene), rng=np.random.default_rng(1),
                                tasks=predictor.model.tasks,
                                style=OverlayStyle(n_samples=6, max_steps=15))
    frame = -1
    for t, y in zip(demos[0].times, demos[0].human):
        predictor.observe(t, y)
        if int(t * 30) != frame:
            frame = int(t * 30)
            scene.set_time(t)
            overlay.show(predictor, t)
    return scene, overlay, predictor


def test_show_marks_every_update_and_keeps_one_prediction(streamed):
    scene, overlay, predictor = streamed
    n = len(predictor.updates)
    assert n >= 5
    assert len(_objects(scene, "/updates/")) == 2 * n  # hand and command markers
    predictions = {k.split("/")[3] for k in _objects(scene, "/prediction/")}
    assert len(predictions) == n + 1  # the prior plan, then one per update; all but one hide
    shown = [a for a in scene.timeline.lower()
             if a["path"].endswith("/path") and "/prediction/" in a["path"]]
    finals = [a["clip"]["tracks"][0]["keys"][-1]["value"] for a in shown]
    assert finals.count(True) == 1


def test_show_draws_the_observed_hand_path(streamed):
    scene, overlay, predictor = streamed
    _, human = predictor.observations()
    assert overlay._drawn["human"] == len(human)
    assert len(_objects(scene, "/human/")) > 10

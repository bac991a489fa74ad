"""The in-process scene: recording to animation tracks, visibility of late and deleted
objects, and the self-contained HTML."""

from __future__ import annotations

import base64
import re

import meshcat
import numpy as np
import pytest
import umsgpack

from sandbox.viz import objects
from sandbox.viz.scene import Scene, decompose, quaternion_xyzw


def _pose(x=0.0, angle=0.0, scale=1.0):
    c, s = np.cos(angle), np.sin(angle)
    pose = np.array([[c, -s, 0, x], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    pose[:3, :3] *= scale
    return pose


def _commands(html: str) -> list[dict]:
    blobs = re.findall(r'^"([A-Za-z0-9+/=]+)"', html, flags=re.M)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in blobs]


@pytest.fixture
def scene():
    scene = Scene(fps=10)
    return scene, meshcat.Visualizer(window=scene)


def test_quaternion_and_decomposition_round_trip():
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        x, y, z, w = q
        rot = np.array([
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ])
        got = quaternion_xyzw(rot)
        np.testing.assert_allclose(got * np.sign(got[3]), q * np.sign(q[3]), atol=1e-9)
    position, quaternion, scale = decompose(_pose(0.5, 0.3, 2.0))
    np.testing.assert_allclose(position, [0.5, 0, 0])
    np.testing.assert_allclose(scale, [2, 2, 2])
    np.testing.assert_allclose(quaternion, [0, 0, np.sin(0.15), np.cos(0.15)])


def test_transforms_become_tracks_at_their_frames(scene):
    scene, vis = scene
    vis["a"].set_object(objects.box([1, 1, 1], [1, 0, 0, 1]))
    vis["still"].set_transform(_pose(1.0))
    for k, t in enumerate([0.0, 0.1, 0.2]):
        scene.set_time(t)
        vis["a"].set_transform(_pose(0.1 * k))
        vis["still"].set_transform(_pose(1.0))
    (clip,) = [a for a in scene.timeline.lower() if a["path"] == "/meshcat/a"]
    assert clip["clip"]["fps"] == 10
    tracks = {t["name"]: t for t in clip["clip"]["tracks"]}
    assert set(tracks) == {".position"}  # constant rotation and unit scale: no track
    assert [k["time"] for k in tracks[".position"]["keys"]] == [0, 1, 2]
    np.testing.assert_allclose(tracks[".position"]["keys"][2]["value"], [0.2, 0, 0])
    # a node whose transform never changes gets no animation
    assert all(a["path"] != "/meshcat/still" for a in scene.timeline.lower())


def test_scaled_transforms_and_scale_properties_are_tracked(scene):
    scene, vis = scene
    scene.set_time(0.0)
    vis["bar"].set_property("scale", [1, 1, 0.1])
    scene.set_time(0.5)
    vis["bar"].set_property("scale", [1, 1, 0.9])
    vis["big"].set_transform(_pose(scale=3.0))
    tracks = {a["path"]: a["clip"]["tracks"] for a in scene.timeline.lower()}
    (bar,) = tracks["/meshcat/bar"]
    assert bar["name"] == ".scale" and [k["time"] for k in bar["keys"]] == [0, 5]
    assert {t["name"] for t in tracks["/meshcat/big"]} == {".position", ".quaternion", ".scale"}


def test_late_objects_appear_and_deleted_ones_hide(scene):
    scene, vis = scene
    scene.set_time(0.0)
    vis["early"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    scene.set_time(0.3)
    vis["late"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    scene.set_time(0.6)
    vis["early"].delete()
    tracks = {a["path"]: a["clip"]["tracks"][0] for a in scene.timeline.lower()}
    late, early = tracks["/meshcat/late"], tracks["/meshcat/early"]
    assert late["name"] == ".visible" and late["type"] == "boolean"
    assert [(k["time"], k["value"]) for k in late["keys"]] == [(0, False), (3, True)]
    assert [(k["time"], k["value"]) for k in early["keys"]] == [(0, True), (6, False)]
    assert "/meshcat/early" in scene.nodes  # kept for the replay


def test_deleting_a_group_hides_each_object_and_a_redrawn_one_shows_again(scene):
    scene, vis = scene
    scene.set_time(0.0)
    vis["g/a"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    vis["g/b"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    scene.set_time(0.2)
    vis["g"].delete()
    scene.set_time(0.4)
    vis["g/a"].set_object(objects.sphere(0.2, [1, 1, 1, 1]))
    keys = {a["path"]: [(k["time"], k["value"]) for k in a["clip"]["tracks"][0]["keys"]]
            for a in scene.timeline.lower()}
    assert keys["/meshcat/g/a"] == [(0, True), (2, False), (4, True)]
    assert keys["/meshcat/g/b"] == [(0, True), (2, False)]
    assert "/meshcat/g" not in keys


def test_without_recording_delete_removes(scene):
    scene, vis = scene
    vis["g/a"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    vis["g"].delete()
    assert not any(k.startswith("/meshcat/g") for k in scene.nodes)
    assert scene.timeline.lower() == []


def test_html_is_self_contained_and_replays_the_commands(scene):
    scene, vis = scene
    vis["a"].set_object(objects.box([1, 1, 1], [1, 0, 0, 1]))
    scene.set_time(0.0)
    vis["a"].set_transform(_pose(0.0))
    scene.set_time(1.0)
    vis["a"].set_transform(_pose(1.0))
    html = scene.static_html()
    assert "MeshCat.Viewer" in html and len(html) > 500_000  # the viewer's JavaScript inlined
    assert "file://" not in html and "http://" not in html.split("<script>", 1)[0]
    commands = _commands(html)
    assert [c["type"] for c in commands] == ["set_object", "set_transform", "set_animation"]
    assert commands[-1]["animations"][0]["path"] == "/meshcat/a"


def test_live_server_receives_the_same_commands():
    class Recorder:
        def __init__(self):
            self.sent = []

        def send(self, kind, path, packed):
            self.sent.append((kind, path, umsgpack.unpackb(packed)))
            return True

    live = Recorder()
    scene = Scene(live)
    vis = meshcat.Visualizer(window=scene)
    vis["x"].set_transform(_pose(2.0))
    vis["x"].delete()
    assert [(k, p) for k, p, _ in live.sent] == [("set_transform", "/meshcat/x"),
                                                ("delete", "/meshcat/x")]


def test_bad_times_and_rates():
    with pytest.raises(ValueError, match="fps"):
        Scene(fps=0)
    with pytest.raises(ValueError, match="t:"):
        Scene().set_time(-1.0)


def test_restart_forgets_the_recording_and_hidden_objects(scene):
    scene, vis = scene
    scene.set_time(0.0)
    vis["kept"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    vis["gone"].set_object(objects.sphere(0.1, [1, 1, 1, 1]))
    scene.set_time(0.5)
    vis["gone"].delete()
    vis["kept"].set_transform(_pose(1.0))
    scene.restart()
    assert not scene.recording and scene.timeline.lower() == []
    assert "/meshcat/kept" in scene.nodes and "/meshcat/gone" not in scene.nodes


def test_held_tracks_step_and_stay_held_after_a_restart():
    from sandbox.viz.scene import DISCRETE

    scene = Scene(fps=10)
    vis = meshcat.Visualizer(window=scene)
    scene.hold("/meshcat/panel")
    for restart in (False, True):
        if restart:
            scene.restart()
        for t, height in ((0.0, 0.2), (1.0, 0.8)):
            scene.set_time(t)
            vis["panel"]["bar"].set_property("scale", [1.0, 1.0, height])
            vis["other"].set_property("scale", [1.0, 1.0, height])
        tracks = {a["path"]: a["clip"]["tracks"][0] for a in scene.timeline.lower()}
        assert tracks["/meshcat/panel/bar"]["interpolation"] == DISCRETE
        assert "interpolation" not in tracks["/meshcat/other"]  # three.js default: linear

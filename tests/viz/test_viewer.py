"""The viewer without a browser: frame throttling, recording, bodies, files, arguments."""

from __future__ import annotations

import base64
import re

import numpy as np
import pytest
import umsgpack

from sandbox.viz import Viewer


@pytest.fixture(scope="module")
def viewer(baxter):
    viewer = Viewer(fps=10)
    viewer.add_baxter(baxter)
    return viewer


def test_one_update_per_frame(viewer, baxter):
    from sandbox.robot import q_home
    from sandbox.robot.bullet import reset_arm

    sent = []
    for t in np.arange(0.0, 0.5, 0.02):  # 50 Hz simulation, 10 fps viewer
        reset_arm(baxter, q_home() + t + 0.01)
        sent.append(viewer.update(t))
    shown = [n for n in sent if n > 0]
    assert len(shown) == 5 + 1  # frames 0..5 (0.48 s rounds to frame 5)
    assert sent.count(0) == len(sent) - len(shown)
    # 0.48 s fell in the frame shown at 0.46 s: forcing it sends what moved since
    assert viewer.update(0.48, force=True) > 0
    assert viewer.update(0.48, force=True) == 0  # nothing moved since
    reset_arm(baxter, q_home())


def test_recorded_frames_become_the_replay(viewer, tmp_path):
    path = viewer.save_html(tmp_path / "sub" / "replay.html")
    blobs = re.findall(r'^"([A-Za-z0-9+/=]+)"', path.read_text(), flags=re.M)
    last = umsgpack.unpackb(base64.b64decode(blobs[-1]))
    assert last["type"] == "set_animation"
    paths = {a["path"] for a in last["animations"]}
    assert "/meshcat/bodies/baxter/left_wrist" in paths
    assert "/meshcat/bodies/baxter/torso" not in paths  # never moved
    assert viewer.scene.timeline.n_frames >= 5
    assert path.stat().st_size > 1_000_000  # meshes and the viewer inlined
    with pytest.raises(ValueError, match=".html"):
        viewer.save_html(tmp_path / "replay.png")


def test_duplicate_and_unknown_bodies(viewer, baxter):
    with pytest.raises(ValueError, match="already"):
        viewer.add_baxter(baxter)
    with pytest.raises(ValueError, match="expected one of"):
        viewer.remove_body("nobody")


def test_add_simulation_skips_known_bodies_and_filters_baxter(baxter):
    import pybullet

    class Sim:  # what envs.pybullet.Simulation offers a viewer
        client = baxter.client
        bodies = {"baxter": baxter.body}

    box = baxter.client.createVisualShape(pybullet.GEOM_BOX, halfExtents=[0.1, 0.1, 0.1])
    Sim.bodies["box"] = baxter.client.createMultiBody(0, -1, box, basePosition=[1, 0, 0])
    try:
        viewer = Viewer()
        added = viewer.add_simulation(Sim)
        assert [m.name for m in added] == ["baxter", "box"]
        assert "left_hand_link" not in viewer.bodies["baxter"].links  # collision fallback
        assert viewer.add_simulation(Sim) == []
        viewer.remove_body("box")
        assert "box" not in viewer.bodies
    finally:
        baxter.client.removeBody(Sim.bodies["box"])


def test_overlay_hangs_its_panel_on_the_camera():
    viewer = Viewer()
    overlay = viewer.add_overlay(["a", "b"], rng=np.random.default_rng(0))
    assert viewer.overlay is overlay
    panel = [k for k in viewer.scene.nodes if "overlay_panel" in k]
    assert panel and all(k.startswith("/Cameras/default/rotated/<object>/") for k in panel)
    again = viewer.add_overlay(["a"], rng=np.random.default_rng(0))
    assert viewer.overlay is again


@pytest.mark.parametrize(
    "kwargs, match",
    [({"camera": [1, 2]}, "camera"), ({"target": [0, 0, np.inf]}, "target"),
     ({"fov": 0}, "fov"), ({"fps": -1}, "fps")],
)
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Viewer(**kwargs)


def test_bad_times():
    viewer = Viewer()
    for t in (-0.1, np.nan):
        with pytest.raises(ValueError, match="t:"):
            viewer.update(t)


@pytest.fixture
def fake_clock(monkeypatch):
    """The viewer's clock and sleeps, faked: ``({"now": s}, slept)``."""
    import sandbox.viz.viewer as module

    clock, slept = {"now": 100.0}, []
    monkeypatch.setattr(module.time, "monotonic", lambda: clock["now"])
    monkeypatch.setattr(module.time, "sleep", lambda s: slept.append(s))
    return clock, slept


def test_realtime_pacing_sleeps_until_the_frame_is_due(fake_clock):
    clock, slept = fake_clock
    viewer = Viewer(realtime=True, fps=10)
    viewer.update(0.0)
    clock["now"] += 0.05  # 50 ms of work
    viewer.update(0.3)
    assert slept == [pytest.approx(0.25)]
    clock["now"] += 1.0  # late: no sleep
    viewer.update(0.4)
    viewer.update(0.0)  # time went back (new episode): pacing restarts, no sleep
    assert len(slept) == 1


def test_restart_pacing_after_a_pause(fake_clock):
    clock, slept = fake_clock
    viewer = Viewer(realtime=True, fps=10)
    viewer.update(0.0)
    clock["now"] += 10.0  # paused for 10 s: without a restart the next 10 s would not sleep
    viewer.restart_pacing()
    viewer.update(0.1)  # paced from here
    viewer.update(0.5)
    assert slept == [pytest.approx(0.4)]


def test_slow_motion_rate_stretches_the_pacing(fake_clock):
    clock, slept = fake_clock
    viewer = Viewer(realtime=True, fps=10)
    viewer.update(0.0)
    viewer.update(0.5)  # real time: 0.5 s of simulation take 0.5 s
    clock["now"] += slept[-1]
    viewer.set_rate(0.25)  # slow motion from the next frame on
    viewer.update(0.6)  # shown now (the pace restarts here)
    viewer.update(1.0)  # 0.4 s of simulation take 1.6 s
    clock["now"] += slept[-1]
    viewer.set_rate(1.0)
    viewer.update(1.1)
    viewer.update(1.5)
    assert slept == [pytest.approx(0.5), pytest.approx(1.6), pytest.approx(0.4)]
    with pytest.raises(ValueError, match="rate"):
        viewer.set_rate(0.0)


def test_restart_recording_begins_a_new_replay(baxter):
    viewer = Viewer(fps=10)
    viewer.vis["probe"].set_transform(np.eye(4))
    viewer.update(0.0)
    viewer.update(0.5)
    assert viewer.scene.recording
    viewer.restart_recording()
    assert not viewer.scene.recording and viewer.scene.timeline.n_frames == 0
    assert viewer.update(0.0) == 0 and viewer.scene.recording  # frame 0 is new again


def test_tracked_arm_is_redrawn_by_update_and_removable():
    state = {"arm": np.array([1.1, 0.1, 0.2, 1.35, 0.0, 0.33])}
    viewer = Viewer(fps=10)
    arm = viewer.add_tracked_arm(lambda: ([1.0, -0.15, 0.25], state["arm"]))
    assert viewer.bodies["tracked_arm"] is arm
    with pytest.raises(ValueError, match="already"):
        viewer.add_tracked_arm(lambda: None)
    assert viewer.update(0.0) == 4  # beads and segments, nothing else mirrored
    state["arm"] = state["arm"] + 0.1
    viewer.update(0.1)
    track = viewer.scene.timeline.tracks["/meshcat/bodies/tracked_arm/elbow"]["position"]
    np.testing.assert_allclose(track[1], [1.2, 0.2, 0.3])
    state["arm"] = np.full(6, np.nan)  # e.g. a teleop episode
    assert viewer.update(0.2) == 0 and not any(arm.visible.values())
    viewer.remove_body("tracked_arm")
    assert "tracked_arm" not in viewer.bodies


def test_the_floor_grid_stays_4_mm_under_the_simulated_floor():
    """Regression (issue 16 item 2): the floor has one height, sandbox.robot.FLOOR_Z; the
    grid keeps its place (-0.93 m), under the floor slab's top so the slab hides it."""
    from sandbox.robot import FLOOR_Z
    from sandbox.viz.viewer import GRID_Z

    assert GRID_Z == -0.93 and FLOOR_Z - GRID_Z == pytest.approx(0.004)

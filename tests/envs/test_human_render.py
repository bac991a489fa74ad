"""``render_mode="human"``: a live meshcat viewer on localhost while the episode runs, its
replay, and a server that stops with the environment or with the process."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from sandbox.envs import BaxterHandoverEnv
from sandbox.robot import Q_HOME
from tests.viz.test_server import _alive, _servers_watching, _wait_gone

pytestmark = pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc (Linux)")


@pytest.fixture(scope="module")
def human_env():
    """A diverging env in "human" mode, not paced to real time (faster tests)."""
    env = gym.make("sandbox/BaxterHandoverDiverging-v1", render_mode="human",
                   viewer_options={"realtime": False})
    yield env
    env.close()


@pytest.mark.filterwarnings("ignore:.*symmetric and normalized")  # targets are in rad, by design
def test_human_mode_is_listed_and_check_env_passes(human_env):
    assert "human" in BaxterHandoverEnv.metadata["render_modes"]
    check_env(human_env.unwrapped, skip_render_check=False)  # builds every listed mode


def test_reset_starts_a_local_server_reused_across_episodes(human_env):
    human_env.reset(seed=0)
    viewer = human_env.unwrapped.viewer
    assert viewer is not None and viewer.server.alive and _alive(viewer.server.pid)
    assert viewer.url.startswith("http://127.0.0.1:")
    human_env.reset(seed=1)  # the same viewer and server for the next episodes
    assert human_env.unwrapped.viewer is viewer


def test_url_is_printed_at_the_first_reset(capfd):
    env = BaxterHandoverEnv(family="diverging", render_mode="human",
                            viewer_options={"realtime": False})
    try:
        env.reset(seed=0)
        assert "meshcat viewer: http://127.0.0.1:" in capfd.readouterr().out
        pid = env.viewer.server.pid
    finally:
        env.close()
    assert _wait_gone(pid), "the server outlived env.close()"
    env.close()  # twice is fine


def test_steps_move_the_mirrored_scene_and_render_returns_none(human_env, tmp_path):
    human_env.reset(seed=2, options={"task": "left"})
    viewer = human_env.unwrapped.viewer
    for _ in range(40):
        human_env.step(np.append(Q_HOME, -1.0))
    assert human_env.render() is None
    assert viewer.scene.timeline.n_frames >= 20  # 0.8 s at 30 fps, recorded as it ran
    hand = [keys["position"] for path, keys in viewer.scene.timeline.tracks.items()
            if "human_hand" in path and "position" in keys]
    assert hand and any(len({tuple(v) for v in track.values()}) > 10 for track in hand)
    html = viewer.save_html(tmp_path / "episode.html").read_text()
    assert len(html) > 100_000  # the scene with its meshes and the animation


def test_reset_starts_a_new_recording(human_env):
    human_env.reset(seed=3)
    for _ in range(30):
        human_env.step(np.append(Q_HOME, -1.0))
    long = human_env.unwrapped.viewer.scene.timeline.n_frames
    human_env.reset(seed=4)
    for _ in range(5):
        human_env.step(np.append(Q_HOME, -1.0))
    assert human_env.unwrapped.viewer.scene.timeline.n_frames < long


def test_render_before_reset_is_refused():
    env = BaxterHandoverEnv(family="diverging", render_mode="human")
    try:
        with pytest.raises(RuntimeError, match="reset"):
            env.render()
        assert env.viewer is None  # nothing started
    finally:
        env.close()


def test_server_stops_when_the_process_ends_without_close(tmp_path):
    script = textwrap.dedent("""
        import os, gymnasium as gym, sandbox.envs
        env = gym.make("sandbox/BaxterHandoverDiverging-v1", render_mode="human")
        env.reset(seed=0)
        print("PIDS", os.getpid(), env.unwrapped.viewer.server.pid, flush=True)
    """)  # no env.close()
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=120, cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    parent, server = (int(v) for v in out.stdout.split("PIDS")[1].split())
    assert _wait_gone(server), "the meshcat server outlived its process"
    assert _servers_watching(parent) == []


def _arm_track(viewer, part, prop):
    return viewer.scene.timeline.tracks[f"/meshcat/bodies/tracked_arm/{part}"][prop]


def test_the_tracked_arm_follows_the_observation_and_hides_without_one(human_env):
    from sandbox.envs.sources import waypoint_motion

    obs, _ = human_env.reset(seed=5, options={"task": "left"})
    for _ in range(20):
        obs, *_ = human_env.step(np.append(Q_HOME, -1.0))
    viewer = human_env.unwrapped.viewer
    assert obs["arm_valid"][0] == 1
    arm = viewer.bodies["tracked_arm"]
    assert all(arm.visible.values())
    for part, dims in (("elbow", slice(0, 3)), ("shoulder", slice(3, 6))):
        track = _arm_track(viewer, part, "position")
        np.testing.assert_allclose(track[max(track)], obs["arm"][dims], atol=1e-6)
    motion = waypoint_motion([0.0, 1.0], [[1.1, 0.0, 0.2], [0.8, 0.1, 0.2]],
                             np.random.default_rng(0))
    human_env.reset(seed=0, options={"motion": motion})  # scripted: no arm
    human_env.step(np.append(Q_HOME, -1.0))
    assert not any(arm.visible.values())
    for part in arm.PARTS:
        assert not any(_arm_track(viewer, part, "visible").values())
        assert "position" not in viewer.scene.timeline.tracks[
            f"/meshcat/bodies/tracked_arm/{part}"]  # nothing drawn at the origin


def test_the_arm_shapes_survive_an_episode_that_ended_hidden(human_env, tmp_path):
    human_env.reset(seed=0, options={"source": "teleop"})  # no arm: hidden to the end
    human_env.step(np.append(Q_HOME, -1.0))
    human_env.reset(seed=6)  # a new recording, with an arm
    for _ in range(5):
        human_env.step(np.append(Q_HOME, -1.0))
    viewer = human_env.unwrapped.viewer
    for part in viewer.bodies["tracked_arm"].PARTS:
        assert viewer.scene.nodes[f"/meshcat/bodies/tracked_arm/{part}/shape"].object
    assert all(viewer.bodies["tracked_arm"].visible.values())

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

from sandbox.data.synthetic.base import Q_HOME
from sandbox.envs import BaxterHandoverEnv
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

"""The teleop's live view in a real browser (headless Chromium), issue 26 item 2.

After ``n`` (a new episode) the panel showed the previous episode's time, belief
and speed (``t = 9.4 s``, ``right 100 %``, ``x1.31``) until the clock ran again;
and a tab opened or reloaded mid-session showed meshcat's default far camera,
and no panel, for seconds (the server sent the robot's meshes before the
camera). A script in the page logs, at every WebSocket message, the meshes
already in the scene and the camera's position, before meshcat handles it.
"""

from __future__ import annotations

import numpy as np
import pytest

#: Logs [meshes in the scene, camera position] as each WebSocket message arrives.
HOOK = """
window.__frames = [];
(() => {
  const Native = window.WebSocket;
  function Logged(...args) {
    const ws = new Native(...args);
    ws.addEventListener("message", () => {
      let meshes = 0, camera = null;
      if (window.viewer) {
        viewer.scene.traverse(o => { if (o.isMesh) meshes++; });
        const p = viewer.camera.position;
        camera = [p.x, p.y, p.z];
      }
      window.__frames.push([meshes, camera]);
    });
    return ws;
  }
  Logged.prototype = Native.prototype;
  window.WebSocket = Logged;
})();
"""
#: What the page shows once the scene has come: the log, and the panel's nodes and bars.
STATE = """
(() => {
  const panel = viewer.scene_tree.find(["Cameras", "default", "rotated", "<object>",
                                        "overlay_panel"]);
  const names = (node) => Object.keys(node.children).sort();
  const columns = Object.keys(panel.children).filter(n => /^c\\d+$/.test(n)).sort();
  const p = viewer.camera.position;
  return {frames: window.__frames, time: names(panel.children["time"]),
          bars: columns.map(c => panel.children[c].children["bar"].object.scale.z),
          values: columns.map(c => names(panel.children[c]).filter(n => n.startsWith("value"))),
          camera: [p.x, p.y, p.z]};
})()
"""


class _Keys:
    """Space, ``w`` and 60 steps of the hand moving, then ``n``; the panel is noted just
    before ``n``; then ``q``."""

    def __init__(self, env) -> None:
        self.env, self.closed = env, False
        self.script = [" ", "w", *[""] * 60, "n"]
        self.before: dict = {}

    def read(self, timeout: float = 0.0) -> list[str]:
        if not self.script:
            return ["q"]
        key = self.script.pop(0)
        if key == "n":
            board = self.env.unwrapped.viewer.overlay.board
            self.before = {"shown": dict(board.shown), "version": board.version}
        return [key]


@pytest.fixture(scope="module")
def after_new_episode(chromium, tmp_path_factory):
    """A teleop session after ``n``, and what a tab opened then (and reloaded) shows."""
    import gymnasium as gym

    import sandbox.envs  # noqa: F401
    from sandbox.episodes.keyboard import run_teleop
    from sandbox.episodes.policies import IProMPPolicy, fit_family_model
    from tests.viz.browser import live_probe

    model = fit_family_model("diverging", n_per_task=4, seed=0)
    policy = IProMPPolicy(model, dow_t=0.2)
    env = gym.make("sandbox/BaxterHandoverDiverging-v1", render_mode="human",
                   viewer_options={"realtime": False})
    try:
        keys = _Keys(env)
        assert run_teleop(env, policy, keys, out=lambda line: None) == 2
        viewer = env.unwrapped.viewer
        if viewer.url is None:
            pytest.skip("the live viewer is offline")
        pages = live_probe(chromium, viewer.url, tmp_path_factory.mktemp("profile"),
                           hook=HOOK, expression=STATE, reloads=1)
        yield env.unwrapped, model, keys.before, pages
    finally:
        env.close()


@pytest.mark.slow
def test_the_panel_resets_with_a_new_episode(after_new_episode):
    env, model, before, pages = after_new_episode
    board = env.viewer.overlay.board
    assert before["shown"]["time"] != "t = 0.0 s" and before["version"] >= 1
    assert board.shown["time"] == "t = 0.0 s" and board.version > before["version"]
    prior = [float(p) for p in model.priors]
    for page in pages:       # the browser shows that panel, not the last episode's
        assert page["time"] == [f"v{board._versions['time']}"]
        assert page["values"] == [[f"value{board.version}"]] * (len(prior) + 1)
        np.testing.assert_allclose(page["bars"], [*prior, 0.5], atol=1e-9)   # alpha 1: 1 / 2


@pytest.mark.slow
def test_a_tab_gets_the_framed_camera_before_any_mesh(after_new_episode):
    env, _, _, pages = after_new_episode
    x, y, z = env.viewer.camera - env.viewer.target
    framed = [x, z, -y]      # the camera's parent frame is y-up
    for page in pages:       # opened mid-session, then reloaded
        first = next(camera for meshes, camera in page["frames"] if meshes > 0)
        np.testing.assert_allclose(first, framed, atol=1e-9)
        np.testing.assert_allclose(page["camera"], framed, atol=1e-9)


def test_the_scene_replay_sends_the_camera_first_and_each_property_once():
    """What a new tab is sent (no browser): the camera's subtree before the robot's meshes,
    and of a property set many times (a bar's height) only its last value."""
    import umsgpack
    from meshcat.servers.tree import SceneTree, find_node

    from sandbox.viz.server import scene_messages

    def prop(name, value):
        return umsgpack.packb({"type": "set_property", "path": "", "property": name,
                               "value": value})

    tree = SceneTree()
    find_node(tree, ["meshcat"]).transform = b"shift"
    find_node(tree, ["meshcat", "bodies", "baxter"]).object = b"mesh"
    camera = find_node(tree, ["Cameras", "default", "rotated", "<object>"])
    camera.properties = [prop("position", [1, 2, 3]), prop("fov", 40.0)]
    bar = find_node(tree, ["Cameras", "default", "rotated", "<object>", "overlay_panel", "bar"])
    bar.properties = [prop("scale", [1, 1, h]) for h in (0.1, 0.9, 0.2)]
    bar.object = b"bar"
    assert scene_messages(tree) == [camera.properties[0], camera.properties[1], b"bar",
                                    bar.properties[-1], b"shift", b"mesh"]

"""The saved HTML replay in a real browser (headless Chromium): the robot is drawn, and the
recorded animation moves it. Opened from file:// with networking disabled."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from sandbox.viz import Viewer

#: Every test here renders pages in headless Chromium (about 10 s a screenshot).
pytestmark = pytest.mark.slow
SIZE = (640, 480)


def _screenshot(chromium: str, html: Path, tmp_path: Path, fragment: str = "") -> np.ndarray:
    """RGB pixels (h, w, 3) of ``html`` rendered by headless Chromium with a fresh profile."""
    from PIL import Image

    out = tmp_path / f"{html.stem}{fragment.replace('#', '_').replace('=', '')}.png"
    profile = tmp_path / f"profile-{out.stem}"
    command = [
        chromium, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--no-first-run", "--hide-scrollbars", f"--user-data-dir={profile}",
        f"--screenshot={out}", f"--window-size={SIZE[0]},{SIZE[1]}",
        "--virtual-time-budget=4000", html.resolve().as_uri() + fragment,
    ]
    run = subprocess.run(command, capture_output=True, text=True, timeout=180)
    assert out.is_file(), f"no screenshot (exit {run.returncode}): {run.stderr[-2000:]}"
    return np.asarray(Image.open(out).convert("RGB"), dtype=np.int16)


def _project(viewer: Viewer, point) -> tuple[int, int]:
    """Pixel (column, row) of a world point in the viewer's initial camera."""
    camera = viewer.camera - viewer.target
    p = np.asarray(point, dtype=float) - viewer.target - camera
    forward = -camera / np.linalg.norm(camera)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    depth, tan = p @ forward, np.tan(np.radians(viewer.fov) / 2)
    x = (p @ right) / (depth * tan * SIZE[0] / SIZE[1])
    y = (p @ up) / (depth * tan)
    return int((x + 1) / 2 * SIZE[0]), int((1 - y) / 2 * SIZE[1])


def _changed(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(a - b).sum(axis=2) > 60


def _window(mask: np.ndarray, pixel: tuple[int, int], half: int = 40) -> np.ndarray:
    col, row = pixel
    return mask[max(row - half, 0): row + half, max(col - half, 0): col + half]


@pytest.fixture(scope="module")
def replays(baxter, tmp_path_factory):
    """An empty scene, and Baxter moving its left arm for 1 s, both as saved replays."""
    from sandbox.robot import q_home
    from sandbox.robot.bullet import reset_arm

    folder = tmp_path_factory.mktemp("replays")
    empty = Viewer()
    scene = Viewer()
    scene.add_baxter(baxter)
    start, end = q_home(), q_home() + np.array([0.6, -0.4, 0.0, -0.6, 0.0, 0.5, 0.0])
    try:
        for t in np.arange(0.0, 1.0 + 1e-9, 1 / 30):
            reset_arm(baxter, start + (end - start) * t)
            scene.update(t)
    finally:
        reset_arm(baxter, q_home())
    return (empty, empty.save_html(folder / "empty.html"),
            scene, scene.save_html(folder / "baxter.html"), (start, end))


def test_screenshot_shows_the_robot(chromium, replays, tmp_path):
    empty, empty_html, scene, scene_html, _ = replays
    background = _screenshot(chromium, empty_html, tmp_path)
    robot = _screenshot(chromium, scene_html, tmp_path)
    assert background.shape == robot.shape == (SIZE[1], SIZE[0], 3)
    changed = _changed(background, robot)
    assert changed.mean() > 0.03, "the robot barely shows"
    torso = _project(scene, [0.0, 0.0, 0.3])
    assert _window(changed, torso).mean() > 0.5, "nothing drawn where Baxter's torso stands"
    corner = changed[: SIZE[1] // 8, -SIZE[0] // 8:]  # the sky above the robot's right
    assert corner.mean() < 0.05


def test_replay_animation_moves_the_arm(chromium, replays, tmp_path):
    from sandbox.robot import BaxterKinematics

    _, _, scene, scene_html, (start, end) = replays
    first = _screenshot(chromium, scene_html, tmp_path, "#t=0")
    last = _screenshot(chromium, scene_html, tmp_path, "#t=1")
    changed = _changed(first, last)
    kin = BaxterKinematics()
    for q in (start, end):  # the forearm left one place and arrived at the other
        pixel = _project(scene, kin.fk(q, link="left_lower_forearm"))
        assert _window(changed, pixel, 25).mean() > 0.25, f"no change at the forearm {pixel}"
    pedestal = _project(scene, [0.0, 0.0, -0.6])
    assert _window(changed, pedestal, 20).mean() < 0.02  # what does not move stays


class _ScriptedKeys:
    """Keys for :func:`~sandbox.episodes.keyboard.run_teleop`: ``script[k]`` at its k-th read,
    then ``q``."""

    def __init__(self, script: list[str]) -> None:
        self.script, self.closed = list(script), False

    def read(self, timeout: float = 0.0) -> list[str]:
        return [self.script.pop(0)] if self.script else ["q"]


@pytest.fixture(scope="module")
def live_teleop():
    """The live view of a teleop episode after 0.8 s of the hand moving toward Baxter."""
    import gymnasium as gym

    import sandbox.envs  # noqa: F401
    from sandbox.episodes.keyboard import run_teleop
    from sandbox.episodes.policies import IProMPPolicy, fit_family_model

    model = fit_family_model("diverging", n_per_task=4, seed=0)
    policy = IProMPPolicy(model, dow_t=0.2)
    env = gym.make("sandbox/BaxterHandoverDiverging-v1", render_mode="human",
                   viewer_options={"realtime": False})
    try:
        run_teleop(env, policy, _ScriptedKeys([" ", "w", *[""] * 40]), out=lambda line: None)
        yield env.unwrapped
    finally:
        env.close()


def test_live_teleop_view_shows_the_panel_and_a_large_hand(chromium, live_teleop, tmp_path):
    from tests.viz.browser import live_screenshot

    viewer = live_teleop.viewer
    shown = live_screenshot(chromium, viewer.url, tmp_path / "shown", size=SIZE)
    viewer.overlay.panel.set_property("visible", False)
    viewer.vis["bodies"]["human_hand"].set_property("visible", False)
    try:
        hidden = live_screenshot(chromium, viewer.url, tmp_path / "hidden", size=SIZE)
    finally:
        viewer.overlay.panel.set_property("visible", True)
        viewer.vis["bodies"]["human_hand"].set_property("visible", True)
    changed = _changed(shown, hidden)
    panel = changed[: int(0.45 * SIZE[1]), : int(0.45 * SIZE[0])]  # where HUD_POSE puts it
    assert panel.mean() > 0.2, f"the panel covers {panel.mean():.0%} of the upper left"
    hand = changed.copy()
    hand[: int(0.45 * SIZE[1]), : int(0.45 * SIZE[0])] = False
    rows, cols = np.nonzero(hand)
    assert len(rows) > 400, f"the hand covers {len(rows)} pixels"
    col, row = _project(viewer, live_teleop.motion.position(live_teleop._t))
    assert abs(np.median(cols) - col) < 60 and abs(np.median(rows) - row) < 60, (
        "the hand is not where the replay's camera sees it")  # the live view uses that camera


def _banner(pixels: np.ndarray) -> float:
    """Share of the top 20 rows in the #bad-time banner's red (#c0392b)."""
    top = pixels[:20].reshape(-1, 3)
    return float((np.abs(top - [192, 57, 43]).sum(axis=1) < 40).mean())


@pytest.mark.parametrize("fragment, bad", [("#t=0.5", False), ("#t=abc", True),
                                           ("#t=99", True), ("#t=-1", True)])
def test_a_time_outside_the_recording_is_said_not_shown_as_the_last_frame(
        chromium, replays, tmp_path, fragment, bad):
    """Issue 27: a malformed or out-of-range #t= silently showed the last frame."""
    _, _, scene, html, _ = replays
    pixels = _screenshot(chromium, html, tmp_path, fragment)
    assert (_banner(pixels) > 0.5) == bad
    if fragment == "#t=abc":     # the first frame, not the last
        first = _screenshot(chromium, html, tmp_path, "#t=0")
        last = _screenshot(chromium, html, tmp_path, "#t=1.0")
        assert _changed(pixels[40:-40], first[40:-40]).mean() < 0.01
        assert _changed(pixels[40:-40], last[40:-40]).mean() > 0.01

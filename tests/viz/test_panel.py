"""The overlays' panel: bars that change with their labels, time, true task, warning, legend."""

from __future__ import annotations

import re

import meshcat
import numpy as np
import pytest
import umsgpack

from sandbox.viz.overlays import OverlayStyle, PredictionOverlay
from sandbox.viz.panel import UNSURE
from sandbox.viz.scene import DISCRETE, Scene

TASKS = ("left", "right")


@pytest.fixture
def drawn():
    scene = Scene(fps=10)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene)["overlays"],
                                rng=np.random.default_rng(0), tasks=TASKS,
                                style=OverlayStyle(n_samples=4, max_steps=10))
    return scene, overlay


def _text(scene, path) -> str:
    return umsgpack.unpackb(scene.nodes[path].object)["object"]["textures"][0]["text"]


def _texts(scene, under: str) -> list[str]:
    """Texts of the labels drawn under ``under`` (in the order they were made)."""
    return [_text(scene, k) for k, n in scene.nodes.items()
            if k.startswith(under) and n.object is not None
            and b"_text" in n.object]


def _at(keys: list[dict], frame: int, step: bool):
    """Value of a track at ``frame``: the last key at or before it, or interpolated."""
    times = [k["time"] for k in keys]
    i = int(np.searchsorted(times, frame, side="right")) - 1
    if step or i < 0 or i + 1 >= len(keys):
        return keys[max(i, 0)]["value"]
    w = (frame - times[i]) / (times[i + 1] - times[i])
    return (1 - w) * np.asarray(keys[i]["value"]) + w * np.asarray(keys[i + 1]["value"])


def test_replayed_bars_and_their_labels_agree_at_every_frame(drawn):
    scene, overlay = drawn
    for t, p in ((0.0, 0.95), (0.6, 0.1), (1.5, 0.65)):  # updates 0.6 s and 0.9 s apart
        scene.set_time(t)
        overlay.show_tasks({"left": p, "right": 1 - p}, alpha=1.0)
    clips = {a["path"]: {tr["name"]: tr for tr in a["clip"]["tracks"]}
             for a in scene.timeline.lower()}
    bar = clips["/meshcat/overlays/panel/c0/bar"][".scale"]
    assert bar.get("interpolation") == DISCRETE  # held, not interpolated between updates
    labels = {path: track[".visible"]["keys"] for path, track in clips.items()
              if re.fullmatch(r"/meshcat/overlays/panel/c0/value\d+", path)}
    for frame in range(scene.timeline.n_frames + 5):
        shown = [p for p, keys in labels.items() if _at(keys, frame, step=True)]
        assert len(shown) == 1, f"frame {frame}: {len(shown)} value labels shown"
        height = _at(bar["keys"], frame, step=True)[2]
        assert _text(scene, shown[0]) == f"{100 * height:.0f}%", f"frame {frame}"


def test_a_linear_bar_would_not_agree_with_its_label(drawn):
    """The check above can fail: interpolated, the bar is at 52 % when the label says 10 %."""
    scene, overlay = drawn
    for t, p in ((0.0, 0.95), (0.6, 0.1)):
        scene.set_time(t)
        overlay.show_tasks({"left": p, "right": 1 - p}, alpha=1.0)
    bar = next(a for a in scene.timeline.lower() if a["path"].endswith("c0/bar"))
    keys = bar["clip"]["tracks"][0]["keys"]
    assert _at(keys, 3, step=False)[2] == pytest.approx(0.525)  # what three.js drew before
    assert _at(keys, 3, step=True)[2] == pytest.approx(0.95)


def test_time_readout_changes_every_tenth_of_a_second(drawn):
    scene, overlay = drawn
    assert overlay.show_time(1.23)
    assert not overlay.show_time(1.24)  # same text: nothing sent
    assert overlay.show_time(1.26)
    assert _texts(scene, "/meshcat/overlays/panel/time/") == ["t = 1.3 s"]  # 1.2 deleted
    with pytest.raises(ValueError, match="t: expected a finite time"):
        overlay.show_time(float("nan"))


def test_true_task_and_intent_switch(drawn):
    scene, overlay = drawn
    hand = np.array([0.9, 0.1, 0.2])
    assert not overlay.show_truth("left", 0.1, hand)
    assert _texts(scene, "/meshcat/overlays/panel/truth/") == ["human: left"]
    assert overlay.show_truth("right", 0.84, hand)
    assert _texts(scene, "/meshcat/overlays/panel/truth/") == [
        "human: right (switched from left at 0.84 s)"]
    cube = scene.nodes["/meshcat/overlays/switch/m0"]
    pose = np.reshape(umsgpack.unpackb(cube.transform)["matrix"], (4, 4)).T
    np.testing.assert_allclose(pose[:3, 3], hand)
    color = umsgpack.unpackb(cube.object)["object"]["materials"][0]["color"]
    assert color == _hex(overlay.colors["right"])  # in the new task's colour
    overlay.show_truth(None, 1.0)  # unknown (e.g. teleop): the row is cleared
    assert _texts(scene, "/meshcat/overlays/panel/truth/") == []
    # a source that knows its switch time: the panel says it, not the frame's time
    overlay.show_truth("left", 1.1, hand)
    assert overlay.show_truth("up", 1.4, hand, since=1.34)
    assert _texts(scene, "/meshcat/overlays/panel/truth/") == [
        "human: up (switched from left at 1.34 s)"]


def _hex(rgba) -> int:
    r, g, b = (int(round(255 * v)) for v in rgba[:3])
    return (r << 16) | (g << 8) | b


def test_legend_swatches_have_the_colours_drawn(drawn):
    scene, overlay = drawn
    legend = _texts(scene, "/meshcat/overlays/panel/legend/")
    assert any("hand path" in t for t in legend) and any("tube" in t for t in legend)
    assert any("bead" in t for t in legend) and any("switch" in t for t in legend)
    fills = [umsgpack.unpackb(n.object)["object"]["materials"][0]["color"]
             for k, n in scene.nodes.items() if k.endswith("/fill")]
    assert _hex(overlay.style.human) in fills and _hex(overlay.style.executed) in fills


def test_title_is_replaced(drawn):
    scene, overlay = drawn
    assert _texts(scene, "/meshcat/overlays/panel/title/") == ["handover-sandbox"]
    overlay.set_title("up, then right")
    assert _texts(scene, "/meshcat/overlays/panel/title/") == ["up, then right"]


# -- from a real predictor -----------------------------------------------------------------


@pytest.fixture(scope="module")
def fitted():
    from sandbox.core import IProMP
    from sandbox.data.synthetic import two_task_demos

    demos = two_task_demos(6, np.random.default_rng(0))
    return IProMP(n_basis=10).fit(demos[1:]), demos[0]


def _predictor(fitted, familiar):
    """A real DynamicPredictor fed half a demo; ``familiar`` set by a test double subclass
    (the attribute the predictors gain: None before an update, False on unknown motions)."""
    from sandbox.core import DynamicPredictor

    class Double(DynamicPredictor):
        pass

    Double.familiar = familiar
    model, demo = fitted
    predictor = Double(model, dow_t=0.25)
    for t, y in zip(demo.times[: len(demo.times) // 2], demo.human):
        predictor.observe(t, y)
    return predictor


@pytest.mark.parametrize("familiar, warned", [(False, True), (True, False), (None, False)])
def test_unsure_warning_follows_familiar(fitted, familiar, warned):
    scene = Scene(fps=10)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene), rng=np.random.default_rng(0),
                                tasks=fitted[0].tasks, style=OverlayStyle(n_samples=4))
    predictor = _predictor(fitted, familiar)
    overlay.show(predictor, float(predictor.observations()[0][-1]))
    assert (_texts(scene, "/meshcat/panel/warning/") == [UNSURE]) == warned
    assert ("/meshcat/panel/warning_box" in scene.nodes) == warned


def test_the_warning_goes_when_the_motion_is_familiar_again(fitted):
    scene = Scene(fps=10)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene), rng=np.random.default_rng(0),
                                tasks=fitted[0].tasks, style=OverlayStyle(n_samples=4))
    predictor = _predictor(fitted, False)
    overlay.show(predictor, 1.0)
    type(predictor).familiar = True
    overlay.show(predictor, 1.1)
    assert _texts(scene, "/meshcat/panel/warning/") == []
    assert "/meshcat/panel/warning_box" not in scene.nodes


RECORDED = ("gummed_paper", "measurement_tape", "pencil_box", "screw_driver")


def _plane_width(scene, path) -> float:
    return umsgpack.unpackb(scene.nodes[path].object)["object"]["geometries"][0]["width"]


def test_long_task_names_keep_their_height_and_their_column():
    """Issue 27: 'measurement_tape' was squeezed into its bar's column (about 4 px tall)."""
    from sandbox.viz.panel import CHAR_WIDTH, text

    scene = Scene(fps=10)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene)["overlays"],
                                rng=np.random.default_rng(0), tasks=RECORDED)
    board, height = overlay.board, overlay.style.label_height
    for i, name in enumerate(RECORDED):
        width = _plane_width(scene, f"/meshcat/overlays/panel/c{i}/name")
        assert width == pytest.approx(text(name, height)[1])     # characters `height` tall
        assert width >= CHAR_WIDTH * height * len(name) - 1e-12
        assert width <= board.pitch                              # never into the next column
    short = PredictionOverlay(meshcat.Visualizer(window=Scene(fps=10))["overlays"],
                              rng=np.random.default_rng(0), tasks=TASKS).board
    assert short.pitch == pytest.approx(short.style.bar_width + short.style.bar_gap)


def test_a_long_title_fits_the_board():
    scene = Scene(fps=10)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene)["overlays"],
                                rng=np.random.default_rng(0), tasks=TASKS)
    title = "recorded measurement tape handover of trial 17, replayed with the dynamic policy"
    overlay.set_title(title)
    (path,) = [k for k in scene.nodes if k.startswith("/meshcat/overlays/panel/title/")
               and scene.nodes[k].object is not None]
    side = _plane_width(scene, path)
    assert side == pytest.approx(overlay.board.width - 0.04)     # was wider than the board
    overlay.set_title("short")                                    # short: the usual size
    assert _texts(scene, "/meshcat/overlays/panel/title/")[-1] == "short"


def test_legend_names_the_arm_and_the_parked_objects_in_their_own_colours():
    from sandbox.viz.geometry import PALETTE
    from sandbox.viz.panel import ARM
    from sandbox.viz.skeleton import ArmStyle

    scene = Scene(fps=10)
    PredictionOverlay(meshcat.Visualizer(window=scene)["overlays"],
                      rng=np.random.default_rng(0), tasks=RECORDED)
    legend = _texts(scene, "/meshcat/overlays/panel/legend/")
    assert "arm (tracker, when seen)" in legend and "objects far behind: unused" in legend
    assert ArmStyle().color == ARM
    # no task colour is near the arm's (it was the second task's orange)
    assert np.min(np.linalg.norm(PALETTE[:, :3] - np.array(ARM[:3]), axis=1)) > 0.3


def test_the_warning_covers_no_value_label():
    """Issue 27: "unsure / unknown motion" was drawn over the row of % labels."""
    from sandbox.viz.panel import VALUE_LIFT

    scene = Scene(fps=10)
    overlay = PredictionOverlay(meshcat.Visualizer(window=scene)["overlays"],
                                rng=np.random.default_rng(0), tasks=TASKS)
    overlay.show_tasks({"left": 1.0, "right": 0.0}, alpha=1.0)
    assert overlay.show_familiar(False)
    box = scene.nodes["/meshcat/overlays/panel/warning_box"]
    z = np.reshape(umsgpack.unpackb(box.transform)["matrix"], (4, 4)).T[2, 3]
    height = umsgpack.unpackb(box.object)["object"]["geometries"][0]["depth"]
    style = overlay.style
    labels_top = style.bar_height + VALUE_LIFT + style.label_height / 2
    assert z - height / 2 > labels_top + 0.01

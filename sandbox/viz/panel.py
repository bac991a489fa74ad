"""The overlays' panel: what the robot believes, what the human does, and a legend.

A board (meshcat node, by default hung on the camera by :class:`~sandbox.viz.Viewer`)
in its own frame: x toward the viewer, y to the right, z up; lengths in m
before the node's scale. From top to bottom:

=============  ===================================================================
``title``      what the scene shows (:meth:`Panel.set_title`)
``time``       the replay or live time, ``t = 1.2 s`` (:meth:`Panel.show_time`)
``truth``      what the human actually pursues, when the source knows it, with the
               time of an intent switch (:meth:`Panel.show_truth`)
``warning``    "unsure / unknown motion" on an orange box when the predictor finds
               the motion unlike its training demos (:meth:`Panel.show_warning`)
``c<i>``       one bar per task (height = probability) and the speed factor alpha
               (height = alpha / 2), value labels above, names below
               (:meth:`Panel.show_tasks`)
``legend``     the colours of the scene's paths, tube and beads
=============  ===================================================================

Text that changes is a new node per value (``<name>/v<k>``), the previous one
deleted: in a recording each value appears and hides at the frame it was set.
The bars are replayed as steps (:meth:`~sandbox.viz.scene.Scene.hold`), so a
bar and its value label always change at the same frame.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from sandbox.validation import check_positive
from sandbox.viz import objects

#: Colour (RGBA) of the board, of the unsure warning, of a task the panel has no colour for.
BOARD = (0.95, 0.95, 0.95, 1.0)
WARNING = (1.0, 0.55, 0.1, 1.0)
NEUTRAL = (0.2, 0.2, 0.2, 1.0)
#: Text of the warning shown when the predictor reports an unfamiliar motion.
UNSURE = "unsure / unknown motion"
#: Colour (RGBA) of the tracked arm (:class:`~sandbox.viz.skeleton.ArmStyle`): a crimson
#: no task colour (:data:`~sandbox.viz.geometry.PALETTE`) comes near.
ARM = (0.80, 0.10, 0.25, 1.0)
#: Swatch of the unused objects, parked on the floor behind the robot.
PARKED = (0.55, 0.55, 0.55, 1.0)
#: Rows of the legend (two entries per row).
LEGEND_ROWS = 4
#: Height (m) of the bars' value labels' centre above the bars' full height.
VALUE_LIFT = 0.03
#: Average width of a character in units of the font size (sans-serif), to size labels.
CHAR_WIDTH = 0.55


def translation(p: ArrayLike) -> np.ndarray:
    """Pose (4, 4) translating by ``p`` (3,) m."""
    pose = np.eye(4)
    pose[:3, 3] = np.asarray(p, dtype=np.float64)[:3]
    return pose


def text(line: str, height: float):
    """A label whose characters are about ``height`` m tall whatever its length.

    meshcat draws a label on a 256-pixel canvas and shrinks long text to fit
    its width, so a long line gets a wider (square, transparent) label.
    Returns the meshcat object and the side of its square (m).
    """
    side = float(height) * max(256.0 / 96.0, CHAR_WIDTH * len(line))
    return objects.label(line, height=side * 96.0 / 256.0), side


class Panel:
    """Bars, labels and legend on one board.

    Parameters
    ----------
    node : meshcat.Visualizer
        Node the board is built under (its pose is set to ``pose``).
    tasks : sequence of str
        Task names (bar order).
    colors : dict of str to array_like
        RGBA colour (4,) of each task.
    pose : array_like, shape (4, 4)
        Pose of the board in the node's parent.
    style : OverlayStyle
        Bar sizes and colours of the paths (the legend's swatches).
    title : str
        First line of the board.
    """

    def __init__(self, node, tasks, colors: dict, pose: ArrayLike, style, *,
                 title: str = "handover-sandbox") -> None:
        self.node, self.tasks, self.colors, self.style = node, tuple(tasks), colors, style
        self.version = -1
        self.shown: dict[str, str | None] = {}
        self._versions: dict[str, int] = {}
        node.set_transform(np.asarray(pose, dtype=np.float64))
        window = getattr(node, "window", None)
        if hasattr(window, "hold"):  # replay the bars as steps, as their labels change
            window.hold(node.path.lower())
        self._build()
        self.set_title(title)

    # -- layout ------------------------------------------------------------------------------

    @property
    def pitch(self) -> float:
        """Distance (m) between columns: a bar and its gap, or the longest task name
        at the full label height (names are never shrunk to fit their column)."""
        longest = max([len(n) for n in self.tasks] + [len("speed")])
        name = CHAR_WIDTH * self.style.label_height * longest + 0.2 * self.style.bar_gap
        return max(self.style.bar_width + self.style.bar_gap, name)

    def _column_y(self, i: int) -> float:
        return i * self.pitch

    @property
    def left(self) -> float:
        """y (m) of the board's left margin."""
        return -self.pitch / 2

    @property
    def width(self) -> float:
        """Width (m) of the board: the columns, at least the legend."""
        columns = self._column_y(len(self.tasks)) + self.pitch / 2
        return max(columns - self.left, 0.8)

    def _z(self, row: str) -> float:
        line = self.style.label_height
        # the warning's box clears the value labels above the bars (it covered them)
        warning = self.style.bar_height + VALUE_LIFT + 0.6 * line + 0.6 * line + 0.02
        rows = {"warning": warning, "truth": warning + 1.7 * line,
                "time": warning + 3.4 * line, "title": warning + 5.3 * line,
                "legend": -0.05 - 0.9 * line}
        return rows[row]

    def _build(self) -> None:
        s = self.style
        bottom = self._z("legend") - LEGEND_ROWS * 1.2 * s.label_height
        top = self._z("title") + 1.4 * s.label_height
        centre = [-0.01, self.left + self.width / 2, (top + bottom) / 2]
        self.node["board"].set_object(objects.box([0.004, self.width, top - bottom], BOARD))
        self.node["board"].set_transform(translation(centre))
        for i, name in enumerate([*self.tasks, "speed"]):
            column = self.node[f"c{i}"]
            column.set_transform(translation([0.0, self._column_y(i), 0.0]))
            rgba = self.colors.get(name, NEUTRAL)
            column["bar"]["box"].set_object(objects.box([0.02, s.bar_width, s.bar_height], rgba))
            column["bar"]["box"].set_transform(translation([0.0, 0.0, s.bar_height / 2]))
            column["bar"].set_property("scale", [1.0, 1.0, 1e-3])
            label, _ = text(name, s.label_height)        # characters label_height tall
            column["name"].set_object(label)
            column["name"].set_transform(translation([0.01, 0.0, -0.03]))
        self._build_legend()

    def _build_legend(self) -> None:
        s = self.style
        task = self.colors[self.tasks[0]] if self.tasks else NEUTRAL
        entries = [("hand path (tracker)", s.human, "line"),
                   ("gripper path (done)", s.executed, "line"),
                   ("plan: mean, goal", task, "line"),
                   (f"plan: ±{s.n_sigma:g}σ tube", [*task[:3], s.tube_alpha], "box"),
                   ("bead: update (hand)", task, "bead"),
                   ("intent switch", NEUTRAL, "cube"),
                   ("arm (tracker, when seen)", ARM, "line"),
                   ("objects far behind: unused", PARKED, "box")]
        half = self.width / 2
        for k, (line, rgba, kind) in enumerate(entries):
            y = self.left + 0.03 + half * (k % 2)
            z = self._z("legend") - 1.2 * s.label_height * (k // 2)
            self._swatch(self.node["legend"][f"e{k}"], rgba, kind, [0.005, y, z])
            self._place(self.node["legend"][f"t{k}"], line, y + 0.03, z, 0.75 * s.label_height)

    def _swatch(self, node, rgba, kind: str, at) -> None:
        size = {"line": [0.006, 0.04, 0.008], "box": [0.006, 0.04, 0.02],
                "bead": [0.006, 0.02, 0.02], "cube": [0.006, 0.025, 0.025]}[kind]
        node["back"].set_object(objects.box([0.004, size[1] + 0.006, size[2] + 0.006],
                                            (0.35, 0.35, 0.35, 1.0)))
        node["back"].set_transform(translation(at))
        node["fill"].set_object(objects.box(size, rgba))
        node["fill"].set_transform(translation(np.add(at, [0.002, 0.0, 0.0])))

    def _place(self, node, line: str, y_left: float, z: float, height: float) -> None:
        """Set ``node`` to text ``line`` starting at ``y_left`` (m), centred on height ``z``."""
        label, side = text(line, height)
        node.set_object(label)
        node.set_transform(translation([0.012, y_left + side / 2, z]))

    # -- changing text -----------------------------------------------------------------------

    def _set_text(self, name: str, line: str | None, *, height: float | None = None) -> bool:
        """Show ``line`` in row ``name`` (None: nothing); return whether anything was sent."""
        if self.shown.get(name) == line:
            return False
        version = self._versions.get(name, -1)
        if version >= 0:
            self.node[name][f"v{version}"].delete()
        self.shown[name] = line
        if line is None:
            return True
        self._versions[name] = version + 1
        height = self.style.label_height if height is None else height
        self._place(self.node[name][f"v{version + 1}"], line, self.left + 0.02, self._z(name),
                    height)
        return True

    def set_title(self, title: str) -> None:
        """Replace the first line of the board (smaller type if it would not fit its width)."""
        title = str(title)
        room = (self.width - 0.04) / (CHAR_WIDTH * max(len(title), 1))
        self._set_text("title", title, height=min(1.2 * self.style.label_height, room))

    def show_time(self, t: float) -> bool:
        """Show ``t = ... s`` (one decimal); return whether the shown text changed."""
        if not np.isfinite(t) or t < 0:
            raise ValueError(f"t: expected a finite time >= 0 (s), got {t!r}")
        return self._set_text("time", f"t = {float(t):.1f} s")

    def show_truth(self, task: str | None, switch: tuple[str, float] | None = None) -> bool:
        """Show what the human pursues (None: unknown, the row is cleared).

        ``switch`` is ``(previous task, time (s))`` of the latest intent switch,
        shown as ``human: right (switched from up at 0.84 s)``.
        """
        if task is None:
            return self._set_text("truth", None)
        line = f"human: {task}"
        if switch is not None:
            line += f" (switched from {switch[0]} at {switch[1]:.2f} s)"
        return self._set_text("truth", line)

    def show_warning(self, on: bool) -> bool:
        """Show or hide the :data:`UNSURE` warning (an orange box behind the text)."""
        if self.shown.get("warning") == (UNSURE if on else None):
            return False
        box = self.node["warning_box"]
        if on:
            label, side = text(UNSURE, self.style.label_height)
            box.set_object(objects.box([0.003, side * 0.75, self.style.label_height * 1.2],
                                       WARNING))
            box.set_transform(translation([0.004, self.left + 0.02 + side * 0.375,
                                           self._z("warning")]))
        else:
            box.delete()
        return self._set_text("warning", UNSURE if on else None)

    def show_tasks(self, posterior: dict, alpha: float) -> None:
        """Set the bars: each task's probability and the speed factor (new value labels)."""
        alpha = check_positive(alpha, "alpha")
        values = []
        for name in self.tasks:
            p = float(posterior.get(name, 0.0))
            if not np.isfinite(p) or not 0.0 <= p <= 1.0 + 1e-9:
                raise ValueError(
                    f"posterior[{name!r}]: expected a probability in [0, 1], got {p!r}"
                )
            values.append((min(p, 1.0), f"{100 * p:.0f}%"))
        values.append((min(alpha / 2.0, 1.0), f"x{alpha:.2f}"))
        old = self.version
        self.version += 1
        for i, (height, value) in enumerate(values):
            column = self.node[f"c{i}"]
            column["bar"].set_property("scale", [1.0, 1.0, max(height, 1e-3)])
            if old >= 0:
                column[f"value{old}"].delete()
            label = column[f"value{self.version}"]
            label.set_object(objects.label(value, height=self.style.label_height))
            label.set_transform(translation([0.01, 0.0, self.style.bar_height + VALUE_LIFT]))

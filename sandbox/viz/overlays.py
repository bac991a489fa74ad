"""Prediction overlays: what the predictor sees, expects and decided, drawn in the scene.

Under the overlay's node (``/meshcat/overlays`` in a :class:`~sandbox.viz.Viewer`):

==========================  ================================================================
``human/s<k>``              observed human hand path, one line segment per call (yellow)
``executed/s<k>``           path the gripper has executed (white)
``prediction/u<k>``         the plan after update k: gripper mean path (task colour), its
                            ``n_sigma`` uncertainty tube (translucent) and goal (sphere);
                            the previous one is removed when a new one is drawn
``updates/m<k>``            markers where update k happened: on the human path (small
                            sphere, task colour) and on the gripper command (ring of
                            the jump it caused)
``panel``                   task probabilities as bars (height = p) and the speed factor
                            alpha (height = alpha / 2), with text labels
==========================  ================================================================

Everything is built from arrays (:meth:`PredictionOverlay.show_human`,
:meth:`~PredictionOverlay.show_prediction`, ...). :meth:`PredictionOverlay.show`
reads a predictor (``plan()``, ``observations()``, ``updates``,
``task_posterior``, ``alpha``, ``command(t)``) and calls them. In a recording,
segments and markers appear at the time they were drawn and removed objects
are hidden from then on (see :class:`~sandbox.viz.scene.Scene`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from sandbox.core.validation import check_array, check_positive
from sandbox.viz import objects
from sandbox.viz.geometry import FloatArray, polyline_tube, sample_paths, task_colors, tube


@dataclass(frozen=True)
class OverlayStyle:
    """Colours (RGBA) and sizes (m) of the overlays."""

    human: tuple = (1.0, 0.85, 0.1, 1.0)
    executed: tuple = (1.0, 1.0, 1.0, 1.0)
    tube_alpha: float = 0.25
    n_sigma: float = 2.0
    n_samples: int = 40
    max_steps: int = 60
    path_radius: float = 0.003
    marker_radius: float = 0.012
    goal_radius: float = 0.02
    bar_width: float = 0.06
    bar_gap: float = 0.05
    bar_height: float = 0.3
    label_height: float = 0.035


def _translation(p: ArrayLike) -> FloatArray:
    pose = np.eye(4)
    pose[:3, 3] = np.asarray(p, dtype=np.float64)[:3]
    return pose


def facing(position: ArrayLike, toward: ArrayLike) -> FloatArray:
    """Pose (4, 4) at ``position`` whose x axis points horizontally toward ``toward``, z up."""
    position = np.asarray(position, dtype=np.float64)
    normal = np.asarray(toward, dtype=np.float64) - position
    normal[2] = 0.0
    norm = np.linalg.norm(normal)
    normal = normal / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
    pose = _translation(position)
    pose[:3, 0], pose[:3, 2] = normal, [0.0, 0.0, 1.0]
    pose[:3, 1] = np.cross(pose[:3, 2], normal)
    return pose


class PredictionOverlay:
    """Draws the predictor's inputs and outputs under a meshcat node.

    Parameters
    ----------
    vis : meshcat.Visualizer
        Node to draw under.
    rng : numpy.random.Generator
        Draws the joint samples of the uncertainty tube.
    tasks : sequence of str
        Task names (fixes their colours and bar order).
    kinematics : BaxterKinematics, optional
        Forward kinematics for joint-space plans (default: a new one).
    link : str
        Link whose path is drawn (default the gripper's fingertip point).
    panel : meshcat.Visualizer, optional
        Node of the bar panel (default ``vis["panel"]``; a :class:`Viewer` hangs
        it on the camera, so it stays in view).
    panel_pose : array_like, shape (4, 4), optional
        Pose of the panel in its parent (its x axis toward the viewer, z up);
        default beside Baxter, facing the front-left.
    style : OverlayStyle
    """

    def __init__(self, vis, *, rng: np.random.Generator, tasks, kinematics=None,
                 link: str = "left_gripper", panel=None, panel_pose: ArrayLike | None = None,
                 style: OverlayStyle = OverlayStyle()) -> None:
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
        if kinematics is None:
            from sandbox.robot import BaxterKinematics

            kinematics = BaxterKinematics()
        self.vis, self.rng, self.style, self.link = vis, rng, style, link
        self.kinematics = kinematics
        self.tasks = tuple(tasks)
        if not self.tasks:
            raise ValueError("tasks: expected at least one task name, got none")
        self.colors = task_colors(self.tasks)
        self._drawn = {"human": 0, "executed": 0}
        self._last_point: dict[str, FloatArray] = {}
        self._segments = {"human": 0, "executed": 0}
        self._prediction = -1
        self._panel_version = -1
        self._n_updates = 0
        self._executed: list[FloatArray] = []
        self.panel = vis["panel"] if panel is None else panel
        pose = facing([0.25, -0.75, 0.35], [2.0, 1.0, 0.5]) if panel_pose is None else panel_pose
        self._panel_pose = check_array(pose, "panel_pose", 2, shape=(4, 4))
        self._build_panel()

    def reset(self) -> None:
        """Remove the paths, predictions and markers (a new episode); the panel stays."""
        for kind in ("human", "executed", "prediction", "updates"):
            self.vis[kind].delete()
        self._drawn = {"human": 0, "executed": 0}
        self._last_point = {}
        self._executed = []
        self._prediction = -1
        self._n_updates = 0

    # -- paths -------------------------------------------------------------------------------

    def _extend(self, kind: str, points: ArrayLike, rgba) -> int:
        points = check_array(points, f"{kind} points", 2, shape=(None, 3), allow_nan=True)
        points = points[np.all(np.isfinite(points), axis=1)]
        if len(points) < self._drawn[kind]:  # a new episode: start over
            self.vis[kind].delete()
            self._drawn[kind] = 0
            self._last_point.pop(kind, None)
        new = points[self._drawn[kind]:]
        if len(new) == 0:
            return 0
        if kind in self._last_point:
            new = np.vstack([self._last_point[kind], new])
        if len(new) >= 2:
            vertices, faces = polyline_tube(new, self.style.path_radius)
            self.vis[kind][f"s{self._segments[kind]}"].set_object(
                objects.tube_object(vertices, faces, rgba))
            self._segments[kind] += 1
        self._drawn[kind] = len(points)
        self._last_point[kind] = points[-1]
        return len(new)

    def show_human(self, points: ArrayLike) -> int:
        """Draw the observed hand path so far, ``points`` (n, 3) m (NaN rows skipped).

        Only the points beyond those already drawn are sent; a shorter path
        than last time starts a new one. Returns the number of points sent.
        """
        return self._extend("human", points, self.style.human)

    def show_executed(self, points: ArrayLike) -> int:
        """Draw the gripper path executed so far, ``points`` (n, 3) m (as :meth:`show_human`)."""
        return self._extend("executed", points, self.style.executed)

    # -- prediction --------------------------------------------------------------------------

    def gripper_paths(self, means: ArrayLike, covs: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Mean gripper path (n, 3) and sampled paths (s, n, 3) m of a joint-space plan.

        ``means`` (n, 7) rad and ``covs`` (n, 7, 7) rad² are thinned to at most
        ``style.max_steps`` evenly spaced steps (the last one always kept).
        """
        means = check_array(means, "means", 2, shape=(None, 7), min_len=1)
        covs = check_array(covs, "covs", 3, shape=(len(means), 7, 7))
        keep = np.unique(np.linspace(0, len(means) - 1, self.style.max_steps).round().astype(int))
        means, covs = means[keep], covs[keep]
        fk = lambda q: self.kinematics.fk(q, link=self.link)  # noqa: E731
        samples = sample_paths(fk, means, covs, self.style.n_samples, self.rng)
        return fk(means), samples

    def show_prediction(self, means: ArrayLike, covs: ArrayLike, task: str) -> FloatArray:
        """Draw a joint-space plan: gripper mean path, uncertainty tube, goal; hide the last one.

        Parameters
        ----------
        means : array_like, shape (n, 7)
            Planned joint means (rad), e.g. the future part of ``predictor.plan()``.
        covs : array_like, shape (n, 7, 7)
            Their covariances (rad²).
        task : str
            Task the plan is for (its colour).

        Returns
        -------
        ndarray, shape (m, 3)
            The mean gripper path drawn (m).
        """
        color = self._color(task)
        path, samples = self.gripper_paths(means, covs)
        if self._prediction >= 0:
            self.vis["prediction"][f"u{self._prediction}"].delete()
        self._prediction += 1
        node = self.vis["prediction"][f"u{self._prediction}"]
        if len(path) >= 2:
            vertices, faces = polyline_tube(path, self.style.path_radius)
            node["path"].set_object(objects.tube_object(vertices, faces, color))
        if len(path) >= 2 and self.style.n_samples >= 2:
            vertices, faces = tube(samples, n_sigma=self.style.n_sigma)
            node["tube"].set_object(objects.tube_object(
                vertices, faces, [*color[:3], self.style.tube_alpha]))
        node["goal"].set_object(objects.sphere(self.style.goal_radius, color))
        node["goal"].set_transform(_translation(path[-1]))
        return path

    def mark_update(self, human_point: ArrayLike | None, robot_point: ArrayLike | None,
                    task: str) -> int:
        """Mark an update at the hand position and at the gripper command; return its index."""
        k = self._n_updates
        self._n_updates += 1
        color = self._color(task)
        node = self.vis["updates"][f"m{k}"]
        for name, point, radius in (("human", human_point, self.style.marker_radius),
                                    ("robot", robot_point, self.style.marker_radius * 0.7)):
            if point is None:
                continue
            point = check_array(point, f"{name}_point", 1, shape=(3,))
            node[name].set_object(objects.sphere(radius, color))
            node[name].set_transform(_translation(point))
        return k

    # -- task probabilities and speed ---------------------------------------------------------

    def _bar_y(self, i: int) -> float:
        return i * (self.style.bar_width + self.style.bar_gap)

    def _build_panel(self) -> None:
        s, panel = self.style, self.panel
        panel.set_transform(self._panel_pose)
        columns = [*self.tasks, "speed"]
        width = self._bar_y(len(columns) - 1) + s.bar_width + 2 * s.bar_gap
        board = _translation([-0.01, width / 2 - s.bar_gap - s.bar_width / 2, s.bar_height / 2])
        panel["board"].set_object(objects.box([0.004, width, s.bar_height + 0.12],
                                              [0.95, 0.95, 0.95, 1.0]))
        panel["board"].set_transform(board)
        for i, name in enumerate(columns):
            column = panel[f"c{i}"]
            column.set_transform(_translation([0.0, self._bar_y(i), 0.0]))
            rgba = self.colors.get(name, [0.2, 0.2, 0.2, 1.0])
            column["bar"]["box"].set_object(objects.box([0.02, s.bar_width, s.bar_height], rgba))
            column["bar"]["box"].set_transform(_translation([0.0, 0.0, s.bar_height / 2]))
            column["bar"].set_property("scale", [1.0, 1.0, 1e-3])
            column["name"].set_object(objects.label(name, height=s.label_height))
            column["name"].set_transform(_translation([0.01, 0.0, -0.03]))

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
        panel, old = self.panel, self._panel_version
        self._panel_version += 1
        for i, (height, text) in enumerate(values):
            column = panel[f"c{i}"]
            column["bar"].set_property("scale", [1.0, 1.0, max(height, 1e-3)])
            if old >= 0:
                column[f"value{old}"].delete()
            value = column[f"value{self._panel_version}"]
            value.set_object(objects.label(text, height=self.style.label_height))
            value.set_transform(_translation([0.01, 0.0, self.style.bar_height + 0.03]))

    def _color(self, task: str) -> FloatArray:
        if task not in self.colors:
            raise ValueError(f"task: expected one of {list(self.tasks)}, got {task!r}")
        return self.colors[task]

    # -- from a predictor ---------------------------------------------------------------------

    def show(self, predictor, t: float, *, executed_q: ArrayLike | None = None,
             human_to_world: ArrayLike | None = None) -> int:
        """Draw the state of a predictor at time ``t``; return the number of new updates.

        Parameters
        ----------
        predictor : DynamicPredictor or StaticPredictor
            Read only (``observations``, ``updates``, ``plan``, ``command``,
            ``task_posterior``, ``alpha``).
        t : float
            Current time (s).
        executed_q : array_like, shape (7,), optional
            The robot's actual joints now (rad); default: the predictor's command at ``t``.
        human_to_world : array_like, shape (4, 4), optional
            Pose of the human observations' frame (default: Baxter's base = world).
        """
        times, human = predictor.observations()
        human = _apply(human_to_world, human[:, :3]) if len(human) else np.zeros((0, 3))
        if len(human) < self._drawn["human"] or len(predictor.updates) < self._n_updates:
            self.reset()  # the predictor was reset: a new episode
        self.show_human(human)
        q = predictor.command(t)[0] if executed_q is None else check_array(
            executed_q, "executed_q", 1, shape=(7,))
        self._executed.append(self.kinematics.fk(q, link=self.link))
        self.show_executed(np.array(self._executed))
        new = predictor.updates[self._n_updates:]
        for update in new:
            seen = times <= update.time
            hand = human[np.flatnonzero(seen)[-1]] if seen.any() else None
            command = self.kinematics.fk(predictor.command(update.time)[0], link=self.link)
            self.mark_update(hand, command, update.task)
        if new or self._panel_version < 0:
            plan_t, means, covs = predictor.plan()
            start = new[-1].time if new else t
            future = plan_t >= start
            if future.sum() >= 2:
                self.show_prediction(means[future], covs[future], predictor.task)
            self.show_tasks(predictor.task_posterior, predictor.alpha)
        return len(new)


def _apply(pose: ArrayLike | None, points: FloatArray) -> FloatArray:
    if pose is None:
        return points
    pose = check_array(pose, "human_to_world", 2, shape=(4, 4))
    return points @ pose[:3, :3].T + pose[:3, 3]


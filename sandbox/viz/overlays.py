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
``switch/m<k>``             intent switch k of the human (when the source knows it): a cube
                            at the hand, in the new task's colour
``panel``                   title, time, the human's true task, the "unsure / unknown
                            motion" warning, task probabilities as bars (height = p) and
                            the speed factor alpha (height = alpha / 2) with value labels,
                            and a legend (:class:`~sandbox.viz.panel.Panel`)
==========================  ================================================================

Everything is built from arrays (:meth:`PredictionOverlay.show_human`,
:meth:`~PredictionOverlay.show_prediction`, ...). :meth:`PredictionOverlay.show`
reads a predictor (``plan()``, ``observations()``, ``updates``,
``task_posterior``, ``alpha``, ``command(t)``, and ``familiar`` when it has
it) and calls them. In a recording,
segments and markers appear at the time they were drawn and removed objects
are hidden from then on (see :class:`~sandbox.viz.scene.Scene`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from sandbox.robot import TIP_LINK
from sandbox.validation import check_array
from sandbox.viz import objects
from sandbox.viz.geometry import FloatArray, polyline_tube, sample_paths, task_colors, tube
from sandbox.viz.panel import NEUTRAL, Panel
from sandbox.viz.panel import translation as _translation

#: Colour (RGBA) of the prior plan, drawn before any task is recognised.
PRIOR_COLOR = np.array([0.6, 0.6, 0.6, 1.0])


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
    switch_size: float = 0.04


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
        Link whose path is drawn (default :data:`~sandbox.robot.TIP_LINK`, the fingertip point).
    panel : meshcat.Visualizer, optional
        Node of the bar panel (default ``vis["panel"]``; a :class:`Viewer` hangs
        it on the camera, so it stays in view).
    panel_pose : array_like, shape (4, 4), optional
        Pose of the panel in its parent (its x axis toward the viewer, z up);
        default beside Baxter, facing the front-left.
    style : OverlayStyle
    title : str
        Title line of the panel (:meth:`set_title` changes it).
    """

    def __init__(self, vis, *, rng: np.random.Generator, tasks, kinematics=None,
                 link: str = TIP_LINK, panel=None, panel_pose: ArrayLike | None = None,
                 style: OverlayStyle = OverlayStyle(), title: str = "handover-sandbox") -> None:
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
        if kinematics is None:
            from sandbox.robot import BaxterKinematics

            kinematics = BaxterKinematics()
        self.vis, self.rng, self.style, self.link = vis, rng, style, link
        self.kinematics = kinematics
        #: ``q (dof,) -> fingertip (3,)`` m in the world for another arm than Baxter (None:
        #: the executed joints are Baxter's, through :attr:`kinematics`).
        self.executed_tip: Any = None
        self.tasks = tuple(tasks)
        if not self.tasks:
            raise ValueError("tasks: expected at least one task name, got none")
        self.colors = task_colors(self.tasks)
        self._drawn = {"human": 0, "executed": 0}
        self._last_point: dict[str, FloatArray] = {}
        self._segments = {"human": 0, "executed": 0}
        self._prediction = -1
        self._n_updates = 0
        self._executed: list[FloatArray] = []
        self._truth: str | None = None
        self._switch: tuple[str, float] | None = None
        self._fresh = False
        self._n_switches = 0
        self.panel = vis["panel"] if panel is None else panel
        pose = facing([0.25, -0.75, 0.35], [2.0, 1.0, 0.5]) if panel_pose is None else panel_pose
        pose = check_array(pose, "panel_pose", 2, shape=(4, 4))
        self.board = Panel(self.panel, self.tasks, self.colors, pose, style, title=str(title))

    def reset(self) -> None:
        """Remove the paths, predictions and markers (a new episode); the panel stays, and
        the next :meth:`show` redraws its bars (the prior's) even without an update."""
        self._fresh = True
        for kind in ("human", "executed", "prediction", "updates", "switch"):
            self.vis[kind].delete()
        self._drawn = {"human": 0, "executed": 0}
        self._last_point = {}
        self._executed = []
        self._prediction = -1
        self._n_updates = 0
        self._truth, self._switch, self._n_switches = None, None, 0

    def restart(self, predictor, **options) -> None:
        """A new episode shown at once, before its first step: no paths, and the panel at
        t = 0 with the (reset) predictor's prior belief (``options`` as :meth:`show`'s)."""
        self.reset()
        self.show(predictor, 0.0, **options)

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

    def _tip(self, x: FloatArray) -> FloatArray:
        """World gripper points (..., 3) m: Baxter joints (..., 7) rad through :attr:`kinematics`,
        or a task-space plan's positions (..., 3) m as they are."""
        x = np.asarray(x, dtype=float)
        return x if x.shape[-1] == 3 else self.kinematics.fk(x, link=self.link)

    def gripper_paths(self, means: ArrayLike, covs: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Mean gripper path (n, 3) and sampled paths (s, n, 3) m of a joint-space plan.

        ``means`` (n, 7) rad and ``covs`` (n, 7, 7) rad² are thinned to at most
        ``style.max_steps`` evenly spaced steps (the last one always kept).
        """
        means = np.asarray(means, dtype=float)
        dims = 3 if means.ndim == 2 and means.shape[1] == 3 else 7   # a task-space plan (m)
        means = check_array(means, "means", 2, shape=(None, dims), min_len=1)
        covs = check_array(covs, "covs", 3, shape=(len(means), dims, dims))
        keep = np.unique(np.linspace(0, len(means) - 1, self.style.max_steps).round().astype(int))
        means, covs = means[keep], covs[keep]
        fk = self._tip
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
            Task the plan is for (its colour); ``""`` for the prior plan, before
            any task is recognised (grey).

        Returns
        -------
        ndarray, shape (m, 3)
            The mean gripper path drawn (m).
        """
        color = self._color(task) if task else PRIOR_COLOR
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

    # -- the panel ---------------------------------------------------------------------------

    def show_tasks(self, posterior: dict, alpha: float) -> None:
        """Set the bars: each task's probability and the speed factor (new value labels)."""
        self.board.show_tasks(posterior, alpha)

    def set_title(self, title: str) -> None:
        """Replace the panel's title line."""
        self.board.set_title(title)

    def show_truth(self, task: str | None, t: float,
                   hand_point: ArrayLike | None = None, since: float | None = None) -> bool:
        """Show what the human pursues at time ``t`` (s); return whether it switched.

        A change from one known task to another is an intent switch: the
        panel says since when (``since``, the source's own switch time in s,
        when it knows it; else ``t``, the frame that first shows it), and a cube
        (``switch/m<k>``, the new task's colour) marks ``hand_point`` (3,) m, if
        given. ``None`` (unknown) clears the row.
        """
        switched = task is not None and self._truth is not None and task != self._truth
        if switched:
            self._switch = (self._truth, float(t if since is None else since))
            if hand_point is not None:
                point = check_array(hand_point, "hand_point", 1, shape=(3,))
                node = self.vis["switch"][f"m{self._n_switches}"]
                size = self.style.switch_size
                node.set_object(objects.box([size] * 3, self.colors.get(task, NEUTRAL)))
                node.set_transform(_translation(point))
            self._n_switches += 1
        if task is None:
            self._switch = None
        self._truth = task
        self.board.show_truth(task, self._switch)
        return switched

    def show_time(self, t: float) -> bool:
        """Show the time ``t`` (s) on the panel; return whether the shown text changed."""
        return self.board.show_time(t)

    def show_familiar(self, familiar: bool | None) -> bool:
        """Show "unsure / unknown motion" when ``familiar`` is False (None: not known)."""
        return self.board.show_warning(familiar is False)

    def _color(self, task: str) -> FloatArray:
        if task not in self.colors:
            raise ValueError(f"task: expected one of {list(self.tasks)}, got {task!r}")
        return self.colors[task]

    # -- from a predictor ---------------------------------------------------------------------

    def show(self, predictor, t: float, *, executed_q: ArrayLike | None = None,
             human_to_world: ArrayLike | None = None, truth: str | None = None,
             truth_since: float | None = None) -> int:
        """Draw the state of a predictor at time ``t``; return the number of new updates.

        Parameters
        ----------
        predictor : DynamicPredictor or StaticPredictor
            Read only (``observations``, ``updates``, ``plan``, ``command``,
            ``task_posterior``, ``alpha``; ``familiar`` if it has it: False shows
            "unsure / unknown motion").
        t : float
            Current time (s).
        executed_q : array_like, shape (7,) or (dof,), optional
            The robot's actual joints now (rad); default: the predictor's command at ``t``.
            Another arm's joints need :attr:`executed_tip` (their fingertip in the world).
        human_to_world : array_like, shape (4, 4), optional
            Pose of the human observations' frame (default: Baxter's base = world).
        truth : str, optional
            The task the human actually pursues at ``t``, when the source knows it
            (e.g. ``env.unwrapped.human_intent()``); a change is marked as an intent
            switch. None: unknown (nothing shown).
        truth_since : float, optional
            When the source's intent switched (s), if it knows: the panel's
            switch time is then the same clock as the summary's.
        """
        times, human = predictor.observations()
        human = _apply(human_to_world, human[:, :3]) if len(human) else np.zeros((0, 3))
        if len(human) < self._drawn["human"] or len(predictor.updates) < self._n_updates:
            self.reset()  # the predictor was reset: a new episode
        self.show_human(human)
        self.show_time(t)
        self.show_truth(truth, t, human[-1] if len(human) else None, since=truth_since)
        self.show_familiar(getattr(predictor, "familiar", None))
        if executed_q is not None and self.executed_tip is not None:   # another arm than Baxter
            self._executed.append(self.executed_tip(check_array(executed_q, "executed_q", 1)))
        else:
            q = predictor.command(t)[0] if executed_q is None else check_array(
                executed_q, "executed_q", 1, shape=(7,))
            self._executed.append(self._tip(q))
        self.show_executed(np.array(self._executed))
        new = predictor.updates[self._n_updates:]
        for update in new:
            seen = times <= update.time
            hand = human[np.flatnonzero(seen)[-1]] if seen.any() else None
            command = self._tip(predictor.command(update.time)[0])
            self.mark_update(hand, command, update.task)
        if new or self._fresh or self.board.version < 0:
            self._fresh = False
            plan_t, means, covs = predictor.plan()
            start = new[-1].time if new else t
            future = plan_t >= start
            if future.sum() >= 2:
                self.show_prediction(means[future], covs[future],
                                     predictor.task if predictor.updates else "")
            self.show_tasks(predictor.task_posterior, predictor.alpha)
        return len(new)


def _apply(pose: ArrayLike | None, points: FloatArray) -> FloatArray:
    if pose is None:
        return points
    pose = check_array(pose, "human_to_world", 2, shape=(4, 4))
    return points @ pose[:3, :3].T + pose[:3, 3]


"""The tracked human arm: shoulder and elbow beads, segments shoulder-elbow-hand.

Under the arm's node (``/meshcat/bodies/tracked_arm`` when added by
:meth:`sandbox.viz.Viewer.add_tracked_arm`):

==============  ==================================================================
``shoulder``    bead at the tracked shoulder
``elbow``       bead at the tracked elbow
``upper``       thin segment shoulder -> elbow
``forearm``     thin segment elbow -> tracked hand (hidden while the hand drops out)
==============  ==================================================================

Each part is a group (pose, ``visible``) holding its shape (``<part>/shape``).

Everything is hidden (``visible`` false, recorded in a replay) while the arm is
not valid: no arm in the source (teleop, scripted, hand-only synthetic), a
tracker dropout (NaN) or the all-zero placeholder of an observation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from sandbox.validation import check_array
from sandbox.viz import objects
from sandbox.viz.geometry import FloatArray
from sandbox.viz.panel import ARM

#: Shortest segment drawn (m); a shorter one is hidden.
MIN_LENGTH = 1e-6


@dataclass(frozen=True)
class ArmStyle:
    """Colour (RGBA) and sizes (m) of the tracked arm."""

    color: tuple = ARM          # the panel's legend entry; no task colour is near it
    bead_radius: float = 0.02
    segment_radius: float = 0.006


def segment_pose(start: ArrayLike, end: ArrayLike) -> FloatArray | None:
    """Pose (4, 4) mapping a unit cylinder along y (centred) onto ``start`` -> ``end``.

    The y column is scaled by the segment's length; ``None`` for a segment
    shorter than :data:`MIN_LENGTH` or with a non-finite end.
    """
    start, end = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    axis = end - start
    length = float(np.linalg.norm(axis))
    if not np.isfinite(length) or length < MIN_LENGTH:
        return None
    y = axis / length
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = x, y * length, np.cross(x, y)
    pose[:3, 3] = (start + end) / 2
    return pose


def _translation(p: FloatArray) -> FloatArray:
    pose = np.eye(4)
    pose[:3, 3] = p
    return pose


class TrackedArm:
    """Draws the tracked elbow and shoulder (and the segments to the hand) under a node.

    Parameters
    ----------
    vis : meshcat.Visualizer
        Node to draw under (its objects are created here, hidden until shown).
    source : callable, optional
        Returns ``(hand, arm)`` now: tracked hand (3,) and arm (6,: elbow then
        shoulder x/y/z) m, NaN where not measured; read by :meth:`update`.
    style : ArmStyle
    """

    PARTS = ("shoulder", "elbow", "upper", "forearm")

    def __init__(self, vis, source: Callable[[], tuple] | None = None, *,
                 style: ArmStyle = ArmStyle()) -> None:
        self.node, self.source, self.style = vis, source, style
        # each shape hangs under a group that is moved and shown/hidden: a recording that
        # ends with the arm hidden then keeps the shapes (see Scene.restart)
        for bead in ("shoulder", "elbow"):
            vis[bead]["shape"].set_object(objects.sphere(style.bead_radius, style.color))
        for segment in ("upper", "forearm"):
            vis[segment]["shape"].set_object(
                objects.cylinder(1.0, style.segment_radius, style.color))
        self.visible = dict.fromkeys(self.PARTS, False)
        self._hide(self.PARTS)

    def show(self, hand: ArrayLike | None, arm: ArrayLike, valid: bool = True) -> int:
        """Draw the arm at ``arm`` (6,) m, the forearm to ``hand`` (3,) m; return transforms sent.

        Hidden when ``valid`` is false, ``arm`` has a NaN or is all zero; the
        forearm alone is hidden when ``hand`` is ``None`` or not finite.
        """
        arm = check_array(arm, "arm", 1, shape=(6,), allow_nan=True)
        if not valid or not np.isfinite(arm).all() or not arm.any():
            self._hide(self.PARTS)
            return 0
        elbow, shoulder = arm[:3], arm[3:]
        hand = np.full(3, np.nan) if hand is None else check_array(
            hand, "hand", 1, shape=(3,), allow_nan=True)
        poses = {"shoulder": _translation(shoulder), "elbow": _translation(elbow),
                 "upper": segment_pose(shoulder, elbow), "forearm": segment_pose(elbow, hand)}
        for name, pose in poses.items():
            if pose is not None:
                self.node[name].set_transform(pose)
            self._set_visible(name, pose is not None)
        return sum(pose is not None for pose in poses.values())

    def update(self) -> int:
        """Draw what :attr:`source` returns now (as :meth:`show`); 0 without a source."""
        return 0 if self.source is None else self.show(*self.source())

    def _hide(self, names) -> None:
        for name in names:
            self._set_visible(name, False)

    def _set_visible(self, name: str, visible: bool) -> None:
        # sent every frame: a new recording then starts with the right visibility
        self.node[name].set_property("visible", bool(visible))
        self.visible[name] = bool(visible)

"""The ``frame:`` key of a spec: a rigid transform from a recording's world to the robot base.

A recording's positions (already in metres, see the spec's ``units``) are
brought into the robot's base frame (Baxter's ``base``: x forward, y to the
robot's left, z up, m) by

.. math::

    p_{\\mathrm{base}} = R \\, U \\, p_{\\mathrm{world}} + t

where :math:`U` levels the recording's up axis to z (``up: z``: identity;
``up: y``, a Y-up world such as many motion-capture and game-engine frames: a
+90 degree turn about x, so :math:`(x, y, z) \\mapsto (x, -z, y)`), :math:`R` is
the rotation given by ``yaw`` (degrees about the levelled z), ``rpy`` (roll,
pitch, yaw in degrees about the fixed x, y, z axes, as in URDF:
:math:`R = R_z(yaw) R_y(pitch) R_x(roll)`) or ``quaternion`` (``[w, x, y, z]``,
scalar first, unit norm) and :math:`t` is ``translation`` (m, in the base frame).
At most one of ``yaw``, ``rpy`` and ``quaternion`` may be given. In YAML::

    frame:
      translation: [0.9, 0.2, -0.1]     # m, where the recording's origin lands
      yaw: 180                          # degrees; or rpy: [r, p, y]; or quaternion: [w, x, y, z]
      up: z                             # the recording's up axis: y or z (default z)

A tracked point that is exactly (0, 0, 0) (a tracker's "person lost" row) is
left at zero so that the loader still recognises it.

:func:`suggest_frame` places a set's meeting region in front of Baxter (see
its docstring); ``python -m sandbox data summary`` prints its suggestion as a
``frame:`` block (:func:`frame_yaml`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.validation import FloatArray, check_number

#: The keys of a ``frame:`` mapping.
FRAME_KEYS = ("translation", "yaw", "rpy", "quaternion", "up")
#: The up axes a recording may have.
UP_AXES = ("y", "z")
#: Levelling of each up axis: the recording's (x, y, z) to a z-up frame.
_LEVEL = {"z": np.eye(3), "y": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])}


def _vector(value: Any, key: str, n: int, what: str) -> FloatArray:
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__") \
            or len(value) != n:
        raise ValueError(f"{key}: expected {what}, got {value!r}")
    return np.array([check_number(v, key) for v in value])


def rotation_rpy(roll: float, pitch: float, yaw: float) -> FloatArray:
    """``R_z(yaw) R_y(pitch) R_x(roll)`` (3, 3) for angles in radians (URDF's convention)."""
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def rotation_quaternion(q: FloatArray, key: str = "quaternion") -> FloatArray:
    """Rotation matrix (3, 3) of a unit quaternion ``[w, x, y, z]`` (norm within 1e-3 of 1)."""
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > 1e-3:
        raise ValueError(f"{key}: expected a unit quaternion [w, x, y, z], got norm {norm:.4g}")
    w, x, y, z = q / norm
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@dataclass(frozen=True)
class Frame:
    """A rigid transform from a recording's world frame to the robot base frame.

    Parameters
    ----------
    translation : array_like, shape (3,)
        Where the levelled, rotated world origin lands in the base frame (m).
    rotation : dict
        The rotation as given: ``{}`` (none), ``{"yaw": deg}``, ``{"rpy": [r, p, y]}``
        (degrees) or ``{"quaternion": [w, x, y, z]}``.
    up : {"y", "z"}
        The recording's up axis.
    """

    translation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: Mapping[str, Any] = field(default_factory=dict)
    up: str = "z"

    @property
    def matrix(self) -> FloatArray:
        """:math:`R U` (3, 3): levelling, then the rotation."""
        return self.rotation_matrix @ _LEVEL[self.up]

    @property
    def rotation_matrix(self) -> FloatArray:
        """:math:`R` (3, 3), the rotation alone."""
        r = self.rotation
        if "yaw" in r:
            rot = rotation_rpy(0.0, 0.0, np.radians(r["yaw"]))
        elif "rpy" in r:
            rot = rotation_rpy(*np.radians(r["rpy"]))
        elif "quaternion" in r:
            rot = rotation_quaternion(np.asarray(r["quaternion"], dtype=float))
        else:
            rot = np.eye(3)
        return rot

    def apply(self, points: FloatArray) -> FloatArray:
        """Points (..., 3) m in the world frame -> (..., 3) m in the base frame (a new array).

        NaN stays NaN; a point exactly (0, 0, 0) stays (0, 0, 0) (a lost-person row).
        """
        p = np.asarray(points, dtype=float)
        out = p @ self.matrix.T + np.asarray(self.translation)
        zero = np.all(p == 0.0, axis=-1)
        out[zero] = 0.0
        return out

    def levelled(self, points: FloatArray) -> FloatArray:
        """Base-frame points (..., 3) back to the levelled recording frame :math:`U p` (m)."""
        return (np.asarray(points, dtype=float) - np.asarray(self.translation)) \
            @ self.rotation_matrix

    def to_dict(self) -> dict:
        """The ``frame:`` mapping (inverse of :func:`parse_frame`)."""
        return {"translation": list(self.translation), **{k: (list(v) if isinstance(v, tuple)
                                                              else v)
                                                          for k, v in self.rotation.items()},
                "up": self.up}


def parse_frame(value: Any, key: str = "frame") -> Frame:
    """A :class:`Frame` from a spec's ``frame:`` mapping; ``ValueError`` naming ``key``."""
    if not isinstance(value, Mapping):
        raise ValueError(f"{key}: expected a mapping with some of {list(FRAME_KEYS)}, "
                         f"got {value!r}")
    unknown = sorted(set(value) - set(FRAME_KEYS))
    if unknown:
        raise ValueError(f"{key}: unknown keys {unknown}; expected some of {list(FRAME_KEYS)}")
    given = [k for k in ("yaw", "rpy", "quaternion") if k in value]
    if len(given) > 1:
        raise ValueError(f"{key}: expected one of yaw, rpy or quaternion, got {given}")
    up = value.get("up", "z")
    if up not in UP_AXES:
        raise ValueError(f"{key}.up: expected one of {list(UP_AXES)}, got {up!r}")
    translation = tuple(_vector(value.get("translation", (0, 0, 0)), f"{key}.translation", 3,
                                "3 numbers [x, y, z] (m)").tolist())
    rotation: dict[str, Any] = {}
    if "yaw" in value:
        rotation["yaw"] = check_number(value["yaw"], f"{key}.yaw (degrees)")
    elif "rpy" in value:
        rotation["rpy"] = tuple(_vector(value["rpy"], f"{key}.rpy", 3,
                                        "3 angles [roll, pitch, yaw] (degrees)").tolist())
    elif "quaternion" in value:
        q = _vector(value["quaternion"], f"{key}.quaternion", 4, "4 numbers [w, x, y, z]")
        rotation_quaternion(q, f"{key}.quaternion")
        rotation["quaternion"] = tuple((q / np.linalg.norm(q)).tolist())
    return Frame(translation, rotation, up)


def meeting_target() -> tuple[FloatArray, FloatArray]:
    """Baxter's demonstrated handover: the hand's start and meeting points (3,), (3,) m.

    The meeting point is where the recorded hands rested at the handover: the
    gripper tip (:data:`~sandbox.robot.TIP_LINK`) at the recordings' median
    final configuration (:data:`sandbox.data.synthetic.robot.Q_HANDOVER`) minus
    :data:`~sandbox.robot.GRASP_OFFSET`; the start is the synthetic reaches'
    :data:`~sandbox.data.synthetic.base.HAND_START`.
    """
    from sandbox.data.synthetic.base import HAND_START
    from sandbox.data.synthetic.robot import Q_HANDOVER, kinematics
    from sandbox.robot import GRASP_OFFSET, TIP_LINK

    tip = kinematics().fk(Q_HANDOVER, link=TIP_LINK)
    return np.array(HAND_START, dtype=float), np.asarray(tip - GRASP_OFFSET, dtype=float)


def suggest_frame(starts: FloatArray, ends: FloatArray, up: str = "z") -> Frame:
    """A placement that puts a set's meeting region where Baxter's demonstrations met the hand.

    Parameters
    ----------
    starts, ends : ndarray, shape (n, 3)
        The observed hand at each demonstration's start and end (m), in the
        recording's frame levelled by ``up`` (any rotation already given ignored).
    up : {"y", "z"}
        The recording's up axis, kept in the suggestion.

    Returns
    -------
    Frame
        A turn about the vertical (``yaw``, whole degrees) that points the
        demos' mean horizontal reach (start to end) the way the recorded
        reaches go toward Baxter, and a ``translation`` (cm-rounded) that puts
        the mean end point on Baxter's demonstrated meeting point
        (:func:`meeting_target`), which its left arm reaches. A set with no
        horizontal reach keeps yaw 0.
    """
    start, meet = meeting_target()
    s = np.nanmean(np.asarray(starts, dtype=float), axis=0)
    e = np.nanmean(np.asarray(ends, dtype=float), axis=0)
    reach, want = (e - s)[:2], (meet - start)[:2]
    yaw = 0.0
    if np.linalg.norm(reach) > 1e-3:
        yaw = float(np.round(np.degrees(np.arctan2(want[1], want[0])
                                        - np.arctan2(reach[1], reach[0]))))
        yaw = (yaw + 180.0) % 360.0 - 180.0
    rotated = rotation_rpy(0.0, 0.0, np.radians(yaw)) @ e
    translation = np.round(meet - rotated, 2) + 0.0
    return Frame(tuple(translation.tolist()), {"yaw": yaw}, up)


def frame_yaml(frame: Frame) -> str:
    """``frame:`` as a YAML block to paste into a spec file."""
    t = ", ".join(f"{v:g}" for v in frame.translation)
    lines = ["frame:", f"  translation: [{t}]    # m"]
    for k, v in frame.rotation.items():
        shown = f"[{', '.join(f'{x:g}' for x in v)}]" if isinstance(v, (tuple, list)) else f"{v:g}"
        lines.append(f"  {k}: {shown}" + ("    # degrees" if k != "quaternion" else ""))
    lines.append(f"  up: {frame.up}")
    return "\n".join(lines)


def suggest_for(demos, spec) -> Frame | None:
    """:func:`suggest_frame` for loaded demonstrations (None without a 3-D ``hand``).

    Parameters
    ----------
    demos : sequence of Demonstration
        Loaded with ``spec``; their ``hand`` modality's first and last finite
        rows are the start and end points.
    spec : DataSpec
        The spec they were loaded with: its frame for the hand, if any, is undone
        (the suggestion replaces it; its ``up`` is kept).
    """
    hand = spec.modalities.get("hand")
    if hand is None or hand.kind != "position" or hand.size != 3:
        return None
    given = spec.layout.frame_of("hand")
    starts, ends = [], []
    for demo in demos:
        names = [m.name for m in demo.modalities]
        if "hand" not in names:
            continue
        j = sum(m.size for m in demo.modalities[:names.index("hand")])
        points = np.asarray(demo.human[:, j:j + 3], dtype=float)
        ok = np.flatnonzero(np.isfinite(points).all(axis=1))
        if ok.size:
            starts.append(points[ok[0]])
            ends.append(points[ok[-1]])
    if not starts:
        return None
    if given is not None:
        starts, ends = given.levelled(np.array(starts)), given.levelled(np.array(ends))
    return suggest_frame(np.array(starts), np.array(ends), "z" if given is None else given.up)

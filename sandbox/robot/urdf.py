"""A minimal URDF reader: the joint tree, enough for forward kinematics.

Only what kinematics needs is read (joint type, parent and child link, origin,
axis, position and speed limits); inertia, geometry and transmissions are ignored. Pure numpy and
the standard library.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class UrdfJoint:
    """One URDF joint.

    Attributes
    ----------
    name, type, parent, child : str
        Joint name, URDF type (``revolute``, ``prismatic``, ``fixed``...),
        parent and child link names.
    origin : ndarray, shape (4, 4)
        Pose of the joint frame in the parent link frame (m).
    axis : ndarray, shape (3,)
        Unit joint axis in the joint frame.
    lower, upper : float
        Position limits (rad or m); ``-inf``/``inf`` when absent.
    velocity : float
        Speed limit (rad/s or m/s), ``<limit velocity>``; ``inf`` when absent.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: FloatArray
    axis: FloatArray
    lower: float
    upper: float
    velocity: float = np.inf


def rpy_matrix(rpy: FloatArray) -> FloatArray:
    """Rotation matrix (3, 3) of URDF roll-pitch-yaw angles (rad): ``Rz(y) Ry(p) Rx(r)``."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _floats(text: str | None, default: tuple[float, ...]) -> FloatArray:
    return np.array([float(v) for v in text.split()] if text else default, dtype=np.float64)


def _origin(element: ET.Element | None) -> FloatArray:
    pose = np.eye(4)
    if element is not None:
        pose[:3, :3] = rpy_matrix(_floats(element.get("rpy"), (0.0, 0.0, 0.0)))
        pose[:3, 3] = _floats(element.get("xyz"), (0.0, 0.0, 0.0))
    return pose


def _joint(element: ET.Element) -> UrdfJoint:
    axis = _floats(
        element.find("axis").get("xyz") if element.find("axis") is not None else None,
        (1.0, 0.0, 0.0),
    )
    limit = element.find("limit")
    lower = float(limit.get("lower", "-inf")) if limit is not None else -np.inf
    upper = float(limit.get("upper", "inf")) if limit is not None else np.inf
    velocity = float(limit.get("velocity", "inf")) if limit is not None else np.inf
    return UrdfJoint(
        name=element.get("name", ""),
        type=element.get("type", ""),
        parent=element.find("parent").get("link", ""),
        child=element.find("child").get("link", ""),
        origin=_origin(element.find("origin")),
        axis=axis / np.linalg.norm(axis) if np.linalg.norm(axis) > 0 else axis,
        lower=lower,
        upper=upper,
        velocity=velocity,
    )


def _robot(path: str | Path) -> ET.Element:
    """The ``<robot>`` root element of a URDF file."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as error:
        raise ValueError(
            f"{path}: expected a URDF (XML) file, got a parse error: {error}"
        ) from error
    if root.tag != "robot":
        raise ValueError(f"{path}: expected a <robot> root element, got <{root.tag}>")
    return root


def read_joints(path: str | Path) -> dict[str, UrdfJoint]:
    """Read every joint of a URDF file.

    Parameters
    ----------
    path : str or pathlib.Path
        URDF file.

    Returns
    -------
    dict of str to UrdfJoint
        Joints keyed by the name of their CHILD link (each link has one parent).

    Raises
    ------
    ValueError
        If the file is not a URDF (no ``<robot>`` root or a malformed joint).
    """
    root = _robot(path)
    joints = {}
    for element in root.iter("joint"):
        if element.find("parent") is None or element.find("child") is None:
            continue  # <joint> references inside <transmission> or <gazebo>
        joint = _joint(element)
        joints[joint.child] = joint
    return joints


def chain_to(joints: dict[str, UrdfJoint], link: str) -> list[UrdfJoint]:
    """Joints from the root link to ``link``, root first.

    Raises
    ------
    ValueError
        If ``link`` is not the child of any joint (unknown or the root).
    """
    if link not in joints:
        raise ValueError(f"link: expected a link of the URDF below its root, got {link!r}")
    chain = []
    while link in joints:
        chain.append(joints[link])
        link = joints[link].parent
        if len(chain) > len(joints):
            raise ValueError("the URDF's joints form a loop")
    return chain[::-1]


@dataclass(frozen=True)
class UrdfVisual:
    """One ``<visual>`` element of a link (what a viewer draws).

    Attributes
    ----------
    link : str
        Link the geometry is attached to.
    kind : str
        ``"mesh"``, ``"box"``, ``"cylinder"`` or ``"sphere"``.
    filename : str
        Mesh file as written in the URDF (``""`` for primitives).
    size : ndarray
        Mesh scale (3,); box sizes (3,) m; cylinder (radius, length) m; sphere (radius,) m.
    origin : ndarray, shape (4, 4)
        Pose of the geometry in the link frame (m).
    rgba : ndarray, shape (4,), or None
        Inline material colour, if any.
    """

    link: str
    kind: str
    filename: str
    size: FloatArray
    origin: FloatArray
    rgba: FloatArray | None


def _visual(link: str, element: ET.Element) -> UrdfVisual | None:
    geometry = element.find("geometry")
    shape = geometry[0] if geometry is not None and len(geometry) else None
    if shape is None:
        return None
    sizes = {
        "mesh": lambda: _floats(shape.get("scale"), (1.0, 1.0, 1.0)),
        "box": lambda: _floats(shape.get("size"), (0.0, 0.0, 0.0)),
        "cylinder": lambda: np.array(
            [float(shape.get("radius", 0)), float(shape.get("length", 0))]
        ),
        "sphere": lambda: np.array([float(shape.get("radius", 0))]),
    }
    if shape.tag not in sizes:
        return None
    color = element.find("material/color")
    return UrdfVisual(
        link=link,
        kind=shape.tag,
        filename=shape.get("filename", ""),
        size=sizes[shape.tag](),
        origin=_origin(element.find("origin")),
        rgba=_floats(color.get("rgba"), (0.5, 0.5, 0.5, 1.0)) if color is not None else None,
    )


def read_visuals(path: str | Path) -> list[UrdfVisual]:
    """Every visual geometry of a URDF file, in file order.

    Raises
    ------
    ValueError
        If the file is not a URDF.
    """
    root = _robot(path)
    visuals = []
    for link in root.iter("link"):
        for element in link.findall("visual"):
            visual = _visual(link.get("name", ""), element)
            if visual is not None:
                visuals.append(visual)
    return visuals

"""What a PyBullet simulation says about its bodies' looks: visual shapes and frame poses.

The only module of :mod:`sandbox.viz` that talks to PyBullet, always through
the ``BulletClient`` it is given. It returns plain arrays, so the meshcat side
never sees PyBullet.

Frames. ``getVisualShapeData`` gives each visual's pose in its link's URDF
frame (for links and the base alike); ``getLinkState`` gives the world pose of
a link's URDF frame (entries 4, 5), but ``getBasePositionAndOrientation``
gives the base's *inertial* frame, so the base's URDF frame is that pose times
the inverse of the base's local inertial frame (``getDynamicsInfo``).

Sizes (``dimensions`` of ``getVisualShapeData``): a box's full extents (m); a
sphere's radius; a cylinder's or capsule's (length, radius); a mesh's scale.
PyBullet also lists a link's collision shapes as visuals when the URDF gives
the link no visual: filter links with ``links=`` if that is unwanted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sandbox.robot.pybullet_quiet import BulletClient, pybullet

FloatArray = NDArray[np.float64]

KINDS = {
    pybullet.GEOM_BOX: "box",
    pybullet.GEOM_SPHERE: "sphere",
    pybullet.GEOM_CYLINDER: "cylinder",
    pybullet.GEOM_CAPSULE: "capsule",
    pybullet.GEOM_MESH: "mesh",
    pybullet.GEOM_PLANE: "plane",
}


@dataclass(frozen=True)
class VisualShape:
    """One visual shape of a body, as PyBullet reports it.

    Attributes
    ----------
    link : int
        Link index (-1 for the base).
    link_name : str
        Link name (the base's name from the URDF).
    kind : str
        ``"box"``, ``"sphere"``, ``"cylinder"``, ``"capsule"``, ``"mesh"`` or ``"plane"``.
    size : ndarray, shape (3,)
        Box extents (m); sphere (radius, 0, 0); cylinder/capsule (length,
        radius, 0) m; mesh scale factors.
    filename : str
        Mesh file (``""`` for primitives).
    origin : ndarray, shape (4, 4)
        Pose of the shape in the link's URDF frame (m).
    rgba : ndarray, shape (4,)
        Colour in [0, 1].
    """

    link: int
    link_name: str
    kind: str
    size: FloatArray
    filename: str
    origin: FloatArray
    rgba: FloatArray


def _check_client(client) -> None:
    if not isinstance(client, BulletClient):
        raise ValueError(
            f"client: expected a pybullet_utils BulletClient, got {type(client).__name__}"
        )


def _check_body(client: BulletClient, body: int) -> int:
    if isinstance(body, bool) or int(body) != body or int(body) not in _body_ids(client):
        raise ValueError(
            f"body: expected one of the body ids of this client {_body_ids(client)}, got {body!r}"
        )
    return int(body)


def _body_ids(client: BulletClient) -> list[int]:
    return [client.getBodyUniqueId(i) for i in range(client.getNumBodies())]


def pose_matrix(positions: FloatArray, quaternions: FloatArray) -> FloatArray:
    """Poses (..., 4, 4) from positions (..., 3) and quaternions (..., 4) ordered (x, y, z, w)."""
    p = np.asarray(positions, dtype=np.float64)
    q = np.asarray(quaternions, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q, -1, 0)
    out = np.zeros(q.shape[:-1] + (4, 4))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - z * w)
    out[..., 0, 2] = 2 * (x * z + y * w)
    out[..., 1, 0] = 2 * (x * y + z * w)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - x * w)
    out[..., 2, 0] = 2 * (x * z - y * w)
    out[..., 2, 1] = 2 * (y * z + x * w)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    out[..., :3, 3] = p
    out[..., 3, 3] = 1.0
    return out


def link_names(client: BulletClient, body: int) -> dict[int, str]:
    """Link index -> name of a body (the base, -1, named after the URDF's root link)."""
    _check_client(client)
    body = _check_body(client, body)
    names = {-1: client.getBodyInfo(body)[0].decode("utf-8", "replace")}
    for index in range(client.getNumJoints(body)):
        names[index] = client.getJointInfo(body, index)[12].decode("utf-8", "replace")
    return names


def visual_shapes(client: BulletClient, body: int) -> list[VisualShape]:
    """Every visual shape of ``body`` in PyBullet's order.

    Parameters
    ----------
    client : BulletClient
        The simulation holding the body.
    body : int
        Body unique id.

    Returns
    -------
    list of VisualShape
        Shapes of unknown geometry types are left out.
    """
    names = link_names(client, body)
    shapes = []
    for row in client.getVisualShapeData(body):
        kind = KINDS.get(row[2])
        if kind is None:
            continue
        filename = row[4].decode("utf-8", "replace") if isinstance(row[4], bytes) else str(row[4])
        shapes.append(
            VisualShape(
                link=int(row[1]),
                link_name=names.get(int(row[1]), str(row[1])),
                kind=kind,
                size=np.array(row[3], dtype=np.float64),
                filename=filename if kind == "mesh" else "",
                origin=pose_matrix(row[5], row[6]),
                rgba=np.clip(np.array(row[7], dtype=np.float64), 0.0, 1.0),
            )
        )
    return shapes


class FrameReader:
    """Reads the world poses of some links' URDF frames of one body, fast.

    Parameters
    ----------
    client : BulletClient
        The simulation.
    body : int
        Body unique id.
    links : sequence of int
        Link indices (-1 for the base).
    """

    def __init__(self, client: BulletClient, body: int, links) -> None:
        _check_client(client)
        self.client = client
        self.body = _check_body(client, body)
        self.links = tuple(int(i) for i in links)
        self._moving = [i for i in self.links if i >= 0]
        self._has_base = -1 in self.links
        inertial = client.getDynamicsInfo(self.body, -1)
        self._base_inertial_inv = np.linalg.inv(pose_matrix(inertial[3], inertial[4]))

    def read(self) -> FloatArray:
        """World poses (n_links, 4, 4) of the links' URDF frames, in the order of ``links``."""
        poses = np.empty((len(self.links), 4, 4))
        if self._moving:
            states = self.client.getLinkStates(
                self.body, self._moving, computeForwardKinematics=True
            )
            moved = pose_matrix([s[4] for s in states], [s[5] for s in states])
        row = 0
        for k, link in enumerate(self.links):
            if link < 0:
                position, quaternion = self.client.getBasePositionAndOrientation(self.body)
                poses[k] = pose_matrix(position, quaternion) @ self._base_inertial_inv
            else:
                poses[k] = moved[row]
                row += 1
        return poses

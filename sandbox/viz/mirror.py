"""Mirror PyBullet bodies into a meshcat scene: geometry once, then only transforms.

Scene layout under the mirror's root path (default ``/meshcat/bodies``)::

    <body name>/<link name>            world pose of the link's URDF frame (updated)
    <body name>/<link name>/v<k>       k-th visual: its pose in the link (set once)
    <body name>/<link name>/v<k>/p<j>  its j-th coloured part (meshes) or the primitive

:meth:`BodyMirror.update` reads every drawn link's pose from PyBullet and sends
a transform only for the links that moved since the last call, so a still
torso costs nothing per frame.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from sandbox.viz import objects
from sandbox.viz.bodies import FrameReader, VisualShape, visual_shapes
from sandbox.viz.meshes import DEFAULT_RESOLUTION, load_mesh, supported

FloatArray = NDArray[np.float64]
COLOR_MODES = ("mesh", "bullet")
#: Change (m, or unitless for rotation entries) below which a link counts as still.
MOVE_TOLERANCE = 1e-7
_Y_TO_Z = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])


def _scaled(origin: FloatArray, scale: FloatArray) -> FloatArray:
    out = np.array(origin, dtype=np.float64)
    out[:3, :3] = out[:3, :3] * np.asarray(scale, dtype=np.float64)[None, :3]
    return out


def shape_objects(
    shape: VisualShape, *, colors: str = "mesh", resolution: float | None = DEFAULT_RESOLUTION
) -> list[tuple[object, FloatArray]]:
    """meshcat objects drawing one visual shape and their poses in the shape's frame.

    Parameters
    ----------
    shape : VisualShape
        From :func:`sandbox.viz.bodies.visual_shapes`.
    colors : {"mesh", "bullet"}
        ``"mesh"``: a mesh file's own material colours where it has them (Baxter's
        red and black parts), PyBullet's colour otherwise; ``"bullet"``: always
        PyBullet's colour.
    resolution : float or None
        Mesh simplification grid (m), see :func:`sandbox.viz.meshes.load_mesh`.

    Returns
    -------
    list of (meshcat object, ndarray (4, 4))
        Empty (with a warning) for a mesh file that cannot be read.
    """
    rgba = shape.rgba
    if shape.kind == "mesh":
        if not supported(shape.filename) or not Path(shape.filename).is_file():
            warnings.warn(f"mesh {shape.filename!r} cannot be drawn (missing or unsupported)",
                          RuntimeWarning, stacklevel=2)
            return []
        parts = load_mesh(shape.filename, resolution)
        scale = _scaled(np.eye(4), shape.size)
        return [(objects.mesh_object(p, p.rgba if colors == "mesh" and p.rgba is not None
                                     else rgba), scale) for p in parts]
    if shape.kind == "box":
        return [(objects.box(shape.size, rgba), np.eye(4))]
    if shape.kind == "sphere":
        return [(objects.sphere(shape.size[0], rgba), np.eye(4))]
    if shape.kind == "cylinder":
        return [(objects.cylinder(shape.size[0], shape.size[1], rgba), _Y_TO_Z)]
    if shape.kind == "capsule":
        length, radius = shape.size[0], shape.size[1]
        caps = [np.eye(4), np.eye(4)]
        caps[0][2, 3], caps[1][2, 3] = length / 2, -length / 2
        return [(objects.cylinder(length, radius, rgba), _Y_TO_Z),
                *[(objects.sphere(radius, rgba), c) for c in caps]]
    return [(objects.box([4.0, 4.0, 0.001], rgba), np.eye(4))]  # plane


class BodyMirror:
    """One PyBullet body drawn in a meshcat scene.

    Parameters
    ----------
    vis : meshcat.Visualizer
        The node to draw under (the body becomes ``vis[name]``).
    client : BulletClient
        The simulation.
    body : int
        Body unique id.
    name : str
        Node name of the body.
    links : iterable of str, optional
        Only draw these links (names); default every link with a visual. Use it
        to hide the collision shapes PyBullet shows for links without visuals.
    colors, resolution
        See :func:`shape_objects`.

    Attributes
    ----------
    links : tuple of str
        Names of the drawn links.
    n_triangles : int
        Triangles sent for the body's meshes.
    """

    def __init__(self, vis, client, body: int, name: str, *, links: Iterable[str] | None = None,
                 colors: str = "mesh", resolution: float | None = DEFAULT_RESOLUTION) -> None:
        if colors not in COLOR_MODES:
            raise ValueError(f"colors: expected one of {list(COLOR_MODES)}, got {colors!r}")
        if not isinstance(name, str) or not name or "/" in name:
            raise ValueError(f"name: expected a non-empty node name without '/', got {name!r}")
        shapes = visual_shapes(client, body)
        if links is not None:
            wanted = set(links)
            unknown = wanted - {s.link_name for s in shapes}
            if unknown:
                raise ValueError(
                    f"links: expected names of links with visuals, got {sorted(unknown)}"
                )
            shapes = [s for s in shapes if s.link_name in wanted]
        self.name = name
        self.node = vis[name]
        self.n_triangles = 0
        indices = sorted({s.link for s in shapes})
        names = {s.link: s.link_name for s in shapes}
        self.links = tuple(names[i] for i in indices)
        self._reader = FrameReader(client, body, indices)
        self._last = np.full((len(indices), 4, 4), np.nan)
        self._draw(shapes, colors, resolution)
        self.update()

    def _draw(self, shapes: list[VisualShape], colors: str, resolution: float | None) -> None:
        counts: dict[str, int] = {}
        for shape in shapes:
            k = counts.get(shape.link_name, 0)
            counts[shape.link_name] = k + 1
            visual = self.node[shape.link_name][f"v{k}"]
            visual.set_transform(shape.origin)
            for j, (obj, pose) in enumerate(
                shape_objects(shape, colors=colors, resolution=resolution)
            ):
                visual[f"p{j}"].set_object(obj)
                if not np.allclose(pose, np.eye(4)):
                    visual[f"p{j}"].set_transform(pose)
                geometry = getattr(obj, "geometry", None)
                self.n_triangles += len(getattr(geometry, "faces", ()))

    def poses(self) -> dict[str, FloatArray]:
        """Current world poses (4, 4) of the drawn links, by name."""
        return dict(zip(self.links, self._reader.read()))

    def update(self, *, force: bool = False) -> int:
        """Send the transforms of the links that moved (all if ``force``); return how many."""
        poses = self._reader.read()
        moved = np.abs(poses - self._last).reshape(len(poses), 16).max(axis=1, initial=0.0)
        sent = 0
        for k, name in enumerate(self.links):
            if force or not moved[k] <= MOVE_TOLERANCE:  # NaN (first call) counts as moved
                self.node[name].set_transform(poses[k])
                self._last[k] = poses[k]
                sent += 1
        return sent

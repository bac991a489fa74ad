"""meshcat objects built from numpy arrays: triangle meshes, lines, points, text labels.

meshcat 0.3.2 has no compact indexed mesh (its ``TriangularMeshGeometry``
always sends 32-bit indices), no text texture on the Python side and no way to
name a colour from an RGBA array; this module adds those. Every function takes
arrays (m, RGBA in [0, 1]) and returns a ``meshcat.geometry.Object``.
"""

from __future__ import annotations

import numpy as np
import umsgpack
from meshcat import geometry as g
from numpy.typing import ArrayLike

from sandbox.viz.collada import MeshPart

#: msgpack extension codes of the typed arrays meshcat's viewer decodes.
_EXT = {np.dtype(np.uint16): (0x14, "Uint16Array"), np.dtype(np.uint32): (0x16, "Uint32Array"),
        np.dtype(np.float32): (0x17, "Float32Array"), np.dtype(np.uint8): (0x12, "Uint8Array")}


def hex_color(rgba: ArrayLike) -> int:
    """``0xRRGGBB`` of an RGB(A) colour in [0, 1]."""
    rgb = np.clip(np.asarray(rgba, dtype=np.float64)[:3], 0.0, 1.0)
    r, gr, b = (int(round(255 * v)) for v in rgb)
    return (r << 16) | (gr << 8) | b


def _typed(array: np.ndarray, item_size: int) -> dict:
    code, name = _EXT[array.dtype]
    return {"itemSize": item_size, "type": name, "normalized": False,
            "array": umsgpack.Ext(code, np.ascontiguousarray(array).tobytes())}


class IndexedMesh(g.Geometry):
    """A ``BufferGeometry``: float32 positions and 16- or 32-bit triangle indices.

    Parameters
    ----------
    vertices : array_like, shape (n, 3)
        Positions (m).
    faces : array_like, shape (m, 3)
        Vertex indices per triangle.
    """

    def __init__(self, vertices: ArrayLike, faces: ArrayLike) -> None:
        super().__init__()
        self.vertices = np.asarray(vertices, dtype=np.float32).reshape(-1, 3)
        index_type = np.uint16 if len(self.vertices) <= 65535 else np.uint32
        self.faces = np.asarray(faces).astype(index_type).reshape(-1, 3)

    def lower(self, object_data: dict) -> dict:
        """The meshcat (three.js JSON) description of this geometry."""
        return {
            "uuid": self.uuid,
            "type": "BufferGeometry",
            "data": {
                "attributes": {"position": _typed(self.vertices.ravel(), 3)},
                "index": _typed(self.faces.ravel(), 1),
            },
        }


class TextTexture(g.Texture):
    """Text drawn on a 256x256 canvas by the viewer (meshcat's ``_text`` texture)."""

    def __init__(self, text: str, font_size: int = 96, font_face: str = "sans-serif") -> None:
        super().__init__()
        self.text, self.font_size, self.font_face = str(text), int(font_size), str(font_face)

    def lower(self, object_data: dict) -> dict:
        """The meshcat (three.js JSON) description of this geometry."""
        return {"uuid": self.uuid, "type": "_text", "text": self.text,
                "font_size": self.font_size, "font_face": self.font_face}


def material(rgba: ArrayLike, *, flat: bool = True) -> g.MeshPhongMaterial:
    """Phong material of an RGBA colour (transparent when alpha < 1); flat-shaded meshes."""
    rgba = np.asarray(rgba, dtype=np.float64)
    alpha = float(rgba[3]) if rgba.size > 3 else 1.0
    options = {"flatShading": True} if flat else {}
    return g.MeshPhongMaterial(color=hex_color(rgba), opacity=alpha, transparent=alpha < 1.0,
                               depthWrite=alpha >= 1.0, **options)


def mesh_object(part: MeshPart, rgba: ArrayLike) -> g.Mesh:
    """A flat-shaded mesh of one :class:`~sandbox.viz.collada.MeshPart` in colour ``rgba``."""
    return g.Mesh(IndexedMesh(part.vertices, part.faces), material(rgba))


def line(points: ArrayLike, rgba: ArrayLike, *, width: float = 2.0) -> g.Line:
    """A polyline through ``points`` (n, 3) m (WebGL draws lines 1 pixel wide on most systems)."""
    points = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    return g.Line(g.PointsGeometry(points.T),
                  g.LineBasicMaterial(color=hex_color(rgba), linewidth=float(width)))


def points(positions: ArrayLike, rgba: ArrayLike, *, size: float = 0.01) -> g.Points:
    """Square points of ``size`` (m) at ``positions`` (n, 3), one colour."""
    positions = np.asarray(positions, dtype=np.float32).reshape(-1, 3)
    colors = np.tile(np.asarray(rgba, dtype=np.float32)[:3], (len(positions), 1))
    return g.Points(g.PointsGeometry(positions.T, colors.T), g.PointsMaterial(size=float(size)))


class Plane(g.Geometry):
    """three.js ``PlaneGeometry``: ``width`` along x, ``height`` along y, facing +z."""

    def __init__(self, width: float, height: float) -> None:
        super().__init__()
        self.width, self.height = float(width), float(height)

    def intrinsic_transform(self) -> np.ndarray:
        """The 4x4 transform that turns the plane to face +x (transposed for meshcat)."""
        # turn it to face +x, texture right -> +y, up -> +z; meshcat flattens this matrix
        # row by row and three.js reads it column by column, hence the transpose
        rotation = np.array([[0.0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
        return rotation.T

    def lower(self, object_data: dict) -> dict:
        """The meshcat (three.js JSON) description of this geometry."""
        return {"uuid": self.uuid, "type": "PlaneGeometry", "width": self.width,
                "height": self.height, "widthSegments": 1, "heightSegments": 1}


def label(text: str, *, height: float = 0.03) -> g.Mesh:
    """Black text about ``height`` m tall, centred on its frame, readable from +x (z up).

    The viewer draws the text on a 256-pixel canvas (font 96 px, shrunk to
    fit the width), shown on a transparent square of side ``height * 256 / 96``
    m that is invisible from behind.
    """
    side = float(height) * 256.0 / 96.0
    return g.Mesh(Plane(side, side),
                  g.MeshBasicMaterial(map=TextTexture(text), transparent=True, opacity=1.0,
                                      color=0xFFFFFF, depthWrite=False, side=0))


def tube_object(vertices: ArrayLike, faces: ArrayLike, rgba: ArrayLike) -> g.Mesh:
    """A smooth-shaded mesh (tubes: :func:`sandbox.viz.geometry.polyline_tube`)."""
    return g.Mesh(IndexedMesh(vertices, faces), material(rgba, flat=False))


def sphere(radius: float, rgba: ArrayLike) -> g.Mesh:
    """A sphere of ``radius`` m."""
    return g.Mesh(g.Sphere(float(radius)), material(rgba, flat=False))


def box(size: ArrayLike, rgba: ArrayLike) -> g.Mesh:
    """A box of full extents ``size`` (3,) m, centred on its frame."""
    return g.Mesh(g.Box([float(v) for v in np.asarray(size, dtype=np.float64)[:3]]),
                  material(rgba, flat=False))


def cylinder(length: float, radius: float, rgba: ArrayLike) -> g.Mesh:
    """A cylinder along its frame's **y** axis (three.js convention), centred."""
    return g.Mesh(g.Cylinder(float(length), float(radius)), material(rgba, flat=False))

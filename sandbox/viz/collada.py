"""A small COLLADA (``.dae``) reader: triangles and diffuse colours, numpy only.

Enough for robot meshes exported by Blender, SolidWorks or MeshLab (Baxter's
files in ``example-robot-data``): ``<triangles>``, ``<polylist>`` and
``<polygons>`` primitives (polygons are fan-triangulated), the node hierarchy
of the visual scene (``<matrix>``, ``<translate>``, ``<rotate>``, ``<scale>``),
``<unit meter=...>`` and the diffuse colour of each primitive's material.
Textures, skinning and animation are ignored.

The ``<up_axis>`` tag is ignored on purpose: ROS robot packages store meshes
in the link frame whatever the tag says (Baxter's ``base_link.DAE`` says
``Y_UP`` yet its coordinates are z-up like its collision mesh).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class MeshPart:
    """Triangles sharing one colour.

    Attributes
    ----------
    vertices : ndarray, shape (n, 3)
        Vertex positions in the mesh file's frame (m).
    faces : ndarray, shape (m, 3)
        Vertex indices of each triangle (counter-clockwise seen from outside).
    rgba : ndarray, shape (4,), or None
        Diffuse colour in [0, 1] if the file gives one.
    """

    vertices: FloatArray
    faces: IntArray
    rgba: FloatArray | None


def _strip_namespaces(root: ET.Element) -> ET.Element:
    for element in root.iter():
        if isinstance(element.tag, str) and "}" in element.tag:
            element.tag = element.tag.split("}", 1)[1]
    return root


def _numbers(text: str | None, dtype: type = np.float64) -> NDArray:
    if not text or not text.strip():
        return np.zeros(0, dtype=dtype)
    return np.array(text.split(), dtype=np.float64).astype(dtype, copy=False)


def _by_id(root: ET.Element) -> dict[str, ET.Element]:
    return {e.get("id"): e for e in root.iter() if e.get("id")}


def _ref(url: str | None) -> str:
    return (url or "").lstrip("#")


def _source_array(source: ET.Element) -> FloatArray:
    """Values of a ``<source>`` as rows (count, stride)."""
    values = _numbers(source.findtext("float_array"))
    accessor = source.find("technique_common/accessor")
    stride = int(accessor.get("stride", "1")) if accessor is not None else 3
    return values[: values.size - values.size % stride].reshape(-1, stride)


def _positions(mesh: ET.Element, ids: dict[str, ET.Element], url: str) -> FloatArray:
    """Resolve an input ``source`` (a ``<vertices>`` or a ``<source>``) to positions (n, 3)."""
    element = ids.get(_ref(url))
    if element is None:
        raise ValueError(f"COLLADA: input source {url!r} not found")
    if element.tag == "vertices":
        for child in element.findall("input"):
            if child.get("semantic") == "POSITION":
                return _positions(mesh, ids, child.get("source"))
        raise ValueError(f"COLLADA: <vertices id={element.get('id')!r}> has no POSITION input")
    return _source_array(element)[:, :3]


def _primitive_triangles(prim: ET.Element) -> tuple[str, IntArray]:
    """``(vertex source url, triangles (m, 3) of position indices)`` of one primitive."""
    inputs = prim.findall("input")
    stride = 1 + max((int(i.get("offset", "0")) for i in inputs), default=0)
    vertex = next((i for i in inputs if i.get("semantic") == "VERTEX"), None)
    if vertex is None:
        raise ValueError(f"COLLADA: <{prim.tag}> has no VERTEX input")
    offset = int(vertex.get("offset", "0"))
    blocks = [_numbers(p.text, np.int64) for p in prim.findall("p")]
    if prim.tag == "triangles":
        counts = [np.full(sum(b.size for b in blocks) // (3 * stride), 3)]
    elif prim.tag == "polylist":
        counts = [_numbers(prim.findtext("vcount"), np.int64)]
    else:  # <polygons>: one <p> per polygon
        counts = [np.array([b.size // stride]) for b in blocks]
    indices = np.concatenate(blocks) if blocks else np.zeros(0, np.int64)
    counts = np.concatenate(counts) if counts else np.zeros(0, np.int64)
    corners = indices[offset::stride][: int(counts.sum())]
    return vertex.get("source"), _fan(corners, counts)


def _fan(corners: IntArray, counts: IntArray) -> IntArray:
    """Fan-triangulate polygons given as concatenated corners and their sizes."""
    counts = counts[counts >= 3]
    if counts.size == 0:
        return np.zeros((0, 3), np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    n_tri = counts - 2
    first = np.repeat(starts, n_tri)
    k = np.arange(int(n_tri.sum())) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri)
    return np.stack([corners[first], corners[first + k + 1], corners[first + k + 2]], axis=1)


def _effect_color(effect: ET.Element | None) -> FloatArray | None:
    if effect is None:
        return None
    for shading in ("phong", "lambert", "blinn", "constant"):
        node = effect.find(f".//technique/{shading}")
        if node is None:
            continue
        color = node.findtext("diffuse/color") or node.findtext("emission/color")
        if color:
            rgba = _numbers(color)
            if rgba.size >= 3:
                return np.clip(np.append(rgba[:4], [1.0] * (4 - rgba[:4].size)), 0.0, 1.0)
    return None


def _material_color(ids: dict[str, ET.Element], material_id: str) -> FloatArray | None:
    material = ids.get(_ref(material_id))
    if material is None:
        return None
    effect = material.find("instance_effect")
    return _effect_color(ids.get(_ref(effect.get("url")))) if effect is not None else None


def _node_matrix(node: ET.Element) -> FloatArray:
    """The node's own transform (4, 4) from its transformation elements, in order."""
    pose = np.eye(4)
    for child in node:
        values = _numbers(child.text) if child.tag in _TRANSFORMS else None
        if child.tag == "matrix" and values.size == 16:
            pose = pose @ values.reshape(4, 4)
        elif child.tag == "translate" and values.size == 3:
            step = np.eye(4)
            step[:3, 3] = values
            pose = pose @ step
        elif child.tag == "scale" and values.size == 3:
            pose = pose @ np.diag(np.append(values, 1.0))
        elif child.tag == "rotate" and values.size == 4:
            pose = pose @ _axis_angle(values[:3], np.deg2rad(values[3]))
    return pose


_TRANSFORMS = ("matrix", "translate", "scale", "rotate")


def _axis_angle(axis: FloatArray, angle: float) -> FloatArray:
    axis = axis / (np.linalg.norm(axis) or 1.0)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    pose = np.eye(4)
    pose[:3, :3] = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)
    return pose


def _geometry_parts(
    geometry: ET.Element, ids: dict[str, ET.Element], bindings: dict[str, str]
) -> list[MeshPart]:
    mesh = geometry.find("mesh")
    if mesh is None:
        return []
    parts = []
    for prim in mesh:
        if prim.tag not in ("triangles", "polylist", "polygons"):
            continue
        url, faces = _primitive_triangles(prim)
        symbol = prim.get("material", "")
        rgba = _material_color(ids, bindings.get(symbol, symbol)) if symbol else None
        parts.append(MeshPart(_positions(mesh, ids, url), faces, rgba))
    return parts


def _instances(node: ET.Element, pose: FloatArray, ids: dict[str, ET.Element]):
    """Yield ``(pose, geometry element, material bindings)`` under ``node``, recursively."""
    pose = pose @ _node_matrix(node)
    for inst in node.findall("instance_geometry"):
        bindings = {
            m.get("symbol", ""): m.get("target", "")
            for m in inst.findall("bind_material/technique_common/instance_material")
        }
        geometry = ids.get(_ref(inst.get("url")))
        if geometry is not None:
            yield pose, geometry, bindings
    for inst in node.findall("instance_node"):
        target = ids.get(_ref(inst.get("url")))
        if target is not None:
            yield from _instances(target, pose, ids)
    for child in node.findall("node"):
        yield from _instances(child, pose, ids)


def read_collada(path: str | Path) -> list[MeshPart]:
    """Read the triangles of a COLLADA file, posed by its scene and scaled to metres.

    Parameters
    ----------
    path : str or pathlib.Path
        A ``.dae`` file.

    Returns
    -------
    list of MeshPart
        One part per primitive (material), vertices in metres in the file's
        root frame. Files without a visual scene give every geometry unposed.

    Raises
    ------
    ValueError
        If the file is not a COLLADA document or its primitives are malformed.
    """
    try:
        root = _strip_namespaces(ET.parse(path).getroot())
    except ET.ParseError as error:
        raise ValueError(f"{path}: expected a COLLADA (XML) file, got {error}") from error
    if root.tag != "COLLADA":
        raise ValueError(f"{path}: expected a <COLLADA> root element, got <{root.tag}>")
    ids = _by_id(root)
    unit = root.find("asset/unit")
    meter = float(unit.get("meter", "1")) if unit is not None else 1.0
    instance = root.find("scene/instance_visual_scene")
    scene = ids.get(_ref(instance.get("url"))) if instance is not None else None
    if scene is None:
        scene = root.find("library_visual_scenes/visual_scene")
    if scene is None:
        placed = [(np.eye(4), g, {}) for g in root.iter("geometry")]
    else:
        placed = [item for node in scene.findall("node")
                  for item in _instances(node, np.eye(4), ids)]
    parts = []
    for pose, geometry, bindings in placed:
        for part in _geometry_parts(geometry, ids, bindings):
            vertices = (part.vertices @ pose[:3, :3].T + pose[:3, 3]) * meter
            faces = part.faces if np.linalg.det(pose[:3, :3]) >= 0 else part.faces[:, ::-1]
            parts.append(MeshPart(vertices, faces, part.rgba))
    return parts

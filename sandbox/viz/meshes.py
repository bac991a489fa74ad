"""Mesh files as compact triangle sets for the viewer: read once, simplified, cached.

:func:`load_mesh` reads COLLADA (``.dae``), Wavefront (``.obj``) and STL files
into :class:`~sandbox.viz.collada.MeshPart` lists, drops unused vertices and,
if asked, simplifies them by *vertex clustering*: vertices are snapped to a
cubic grid of side ``resolution`` (m), each cell's vertices merge into their
mean, and triangles that collapse are removed. At 2 mm Baxter's 410k visual
triangles become about a quarter as many with no visible change at viewing
distance. Results are cached per (file, modification time, resolution), so a
second viewer in the same process reads nothing.

Numpy and the standard library only (no meshcat), so it is testable alone.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

import numpy as np

from sandbox.viz.collada import FloatArray, IntArray, MeshPart, read_collada

#: Default simplification grid (m) for viewer meshes.
DEFAULT_RESOLUTION = 0.002


def compact(part: MeshPart) -> MeshPart:
    """Drop the vertices no triangle uses and renumber the faces."""
    used, faces = np.unique(part.faces, return_inverse=True)
    return MeshPart(part.vertices[used], faces.reshape(-1, 3), part.rgba)


def cluster_vertices(part: MeshPart, resolution: float) -> MeshPart:
    """Simplify a mesh by vertex clustering on a grid of side ``resolution`` (m).

    Parameters
    ----------
    part : MeshPart
        The mesh (not modified).
    resolution : float
        Grid cell side (m), > 0.

    Returns
    -------
    MeshPart
        Merged vertices (cell means), the triangles whose three corners fell
        in different cells, each kept once; colour unchanged.
    """
    if not np.isfinite(resolution) or resolution <= 0:
        raise ValueError(f"resolution: expected a finite number > 0 (m), got {resolution!r}")
    cells = np.floor(part.vertices / resolution).astype(np.int64)
    _, cluster = np.unique(cells, axis=0, return_inverse=True)
    cluster = cluster.reshape(-1)
    n_clusters = int(cluster.max()) + 1 if cluster.size else 0
    counts = np.bincount(cluster, minlength=n_clusters)[:, None]
    merged = np.zeros((n_clusters, 3))
    np.add.at(merged, cluster, part.vertices)
    merged /= np.maximum(counts, 1)
    faces = cluster[part.faces]
    a, b, c = faces.T
    keep = (a != b) & (b != c) & (a != c)
    faces = faces[keep]
    # a triangle and its duplicates (same corners, any rotation) are kept once
    start = np.argmin(faces, axis=1)[:, None]
    rolled = np.take_along_axis(faces, (start + np.arange(3)) % 3, axis=1)
    _, first = np.unique(rolled, axis=0, return_index=True)
    return compact(MeshPart(merged, faces[np.sort(first)], part.rgba))


def _read_obj(path: Path) -> list[MeshPart]:
    vertices, faces = [], []
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        fields = line.split()
        if not fields:
            continue
        if fields[0] == "v":
            vertices.append([float(v) for v in fields[1:4]])
        elif fields[0] == "f":
            corners = [int(f.split("/")[0]) for f in fields[1:]]
            corners = [c - 1 if c > 0 else len(vertices) + c for c in corners]
            faces.extend([corners[0], corners[k], corners[k + 1]]
                         for k in range(1, len(corners) - 1))
    vertices = np.array(vertices, dtype=np.float64).reshape(-1, 3)
    return [MeshPart(vertices, np.array(faces, np.int64).reshape(-1, 3), None)]


def _read_stl(path: Path) -> list[MeshPart]:
    data = path.read_bytes()
    n = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    if n >= 0 and len(data) == 84 + 50 * n:  # binary
        records = np.frombuffer(data, dtype=np.uint8, count=50 * n, offset=84).reshape(n, 50)
        corners = records[:, 12:48].copy().view("<f4").reshape(-1, 3).astype(np.float64)
    else:  # ASCII
        words = data.decode("utf-8", errors="replace").split()
        corners = np.array(
            [words[i + 1 : i + 4] for i, w in enumerate(words) if w == "vertex"], dtype=np.float64
        ).reshape(-1, 3)
    faces = np.arange(len(corners) - len(corners) % 3, dtype=np.int64).reshape(-1, 3)
    return [weld(MeshPart(corners, faces, None))]


def weld(part: MeshPart) -> MeshPart:
    """Merge exactly coincident vertices (STL files repeat each corner per triangle)."""
    unique, inverse = np.unique(part.vertices, axis=0, return_inverse=True)
    return MeshPart(unique, inverse.reshape(-1)[part.faces], part.rgba)


_READERS = {".dae": read_collada, ".obj": _read_obj, ".stl": _read_stl}


def supported(path: str | Path) -> bool:
    """Whether :func:`load_mesh` can read this file (by extension)."""
    return Path(path).suffix.lower() in _READERS


def load_mesh(
    path: str | Path, resolution: float | None = DEFAULT_RESOLUTION
) -> tuple[MeshPart, ...]:
    """Read a mesh file into compact parts, simplified, cached per process.

    Parameters
    ----------
    path : str or pathlib.Path
        A ``.dae``, ``.obj`` or ``.stl`` file.
    resolution : float or None
        Vertex-clustering grid (m); ``None`` keeps the full mesh.

    Returns
    -------
    tuple of MeshPart
        Non-empty parts, vertices (n, 3) in metres in the file's frame. The
        arrays are read-only (shared by every caller).

    Raises
    ------
    ValueError
        Unsupported extension, or a file that cannot be parsed.
    FileNotFoundError
        If the file does not exist.
    """
    path = Path(path).resolve()
    if not supported(path):
        raise ValueError(
            f"mesh: expected a file ending in one of {sorted(_READERS)}, got {path.name!r}"
        )
    if resolution is not None and (not np.isfinite(resolution) or resolution <= 0):
        raise ValueError(f"resolution: expected None or a number > 0 (m), got {resolution!r}")
    stat = os.stat(path)
    return _load_cached(str(path), stat.st_mtime_ns, stat.st_size, resolution)


@functools.lru_cache(maxsize=256)
def _load_cached(
    path: str, mtime_ns: int, size: int, resolution: float | None
) -> tuple[MeshPart, ...]:
    parts = []
    for part in _READERS[Path(path).suffix.lower()](Path(path)):
        if part.faces.size == 0:
            continue
        part = compact(part)
        if resolution is not None:
            part = cluster_vertices(part, resolution)
        if part.faces.size:
            parts.append(_frozen(part))
    return tuple(parts)


def _frozen(part: MeshPart) -> MeshPart:
    arrays = [np.array(a) for a in (part.vertices, part.faces)]
    rgba = None if part.rgba is None else np.array(part.rgba)
    for array in [*arrays, rgba]:
        if array is not None:
            array.flags.writeable = False
    return MeshPart(arrays[0], arrays[1], rgba)


def n_triangles(parts: tuple[MeshPart, ...] | list[MeshPart]) -> int:
    """Total number of triangles of a mesh."""
    return int(sum(len(p.faces) for p in parts))


__all__ = [
    "DEFAULT_RESOLUTION",
    "FloatArray",
    "IntArray",
    "MeshPart",
    "cluster_vertices",
    "compact",
    "load_mesh",
    "n_triangles",
    "supported",
    "weld",
]

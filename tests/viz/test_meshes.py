"""Mesh loading: formats, vertex clustering, caching, error paths."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from sandbox.viz.collada import MeshPart
from sandbox.viz.meshes import cluster_vertices, load_mesh, n_triangles


def _sphere(n: int = 40) -> MeshPart:
    """A UV sphere of radius 0.1 m with ``n`` x ``n`` quads."""
    theta, phi = np.meshgrid(np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, n + 1))
    vertices = 0.1 * np.stack(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1
    ).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a, b = i * (n + 1) + j, i * (n + 1) + j + 1
    c, d = a + n + 1, b + n + 1
    faces = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)]).reshape(-1, 3)
    return MeshPart(vertices, faces, None)


def test_clustering_simplifies_within_the_grid():
    sphere = _sphere()
    coarse = cluster_vertices(sphere, 0.02)
    assert len(coarse.faces) < len(sphere.faces) / 3
    radii = np.linalg.norm(coarse.vertices, axis=1)
    assert np.all(np.abs(radii - 0.1) < 0.02 * np.sqrt(3))  # a cell's mean stays in the cell
    a, b, c = coarse.faces.T
    assert np.all((a != b) & (b != c) & (a != c))  # no degenerate triangle
    canonical = {tuple(np.roll(f, -int(np.argmin(f)))) for f in coarse.faces}
    assert len(canonical) == len(coarse.faces)  # no duplicate
    assert coarse.faces.max() == len(coarse.vertices) - 1  # compact


def test_a_fine_grid_keeps_the_mesh():
    n = 10
    x, y = np.meshgrid(np.arange(n + 1) / n, np.arange(n + 1) / n, indexing="ij")
    sheet = MeshPart(np.stack([x, y, 0 * x], -1).reshape(-1, 3), _sphere(n).faces, None)
    same = cluster_vertices(sheet, 1e-3)
    assert len(same.faces) == len(sheet.faces) == 2 * n * n
    assert len(same.vertices) == len(sheet.vertices)


def test_clustering_does_not_modify_its_input():
    sphere = _sphere()
    before = sphere.vertices.copy(), sphere.faces.copy()
    cluster_vertices(sphere, 0.05)
    np.testing.assert_array_equal(sphere.vertices, before[0])
    np.testing.assert_array_equal(sphere.faces, before[1])


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_bad_resolution_is_refused(bad):
    with pytest.raises(ValueError, match="resolution"):
        cluster_vertices(_sphere(4), bad)


def _write_stl_binary(path, triangles):
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + struct.pack("<I", len(triangles)))
        for tri in triangles:
            f.write(struct.pack("<3f", 0, 0, 1))
            for corner in tri:
                f.write(struct.pack("<3f", *corner))
            f.write(b"\0\0")


_TRIS = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]]], float)


def test_stl_binary_and_ascii_give_the_same_welded_mesh(tmp_path):
    binary = tmp_path / "a.stl"
    _write_stl_binary(binary, _TRIS)
    text = "solid t\n" + "".join(
        "facet normal 0 0 1\nouter loop\n"
        + "".join(f"vertex {x} {y} {z}\n" for x, y, z in tri)
        + "endloop\nendfacet\n"
        for tri in _TRIS
    ) + "endsolid t\n"
    ascii_ = tmp_path / "b.STL"
    ascii_.write_text(text)
    for path in (binary, ascii_):
        (part,) = load_mesh(path, None)
        assert len(part.vertices) == 4 and len(part.faces) == 2
        np.testing.assert_allclose(part.vertices[part.faces], _TRIS)


def test_obj_polygons_and_negative_indices(tmp_path):
    path = tmp_path / "q.obj"
    path.write_text(
        "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 -1//1\n"
    )
    (part,) = load_mesh(path, None)
    assert n_triangles([part]) == 2
    np.testing.assert_allclose(part.vertices[part.faces][1], [[0, 0, 0], [1, 1, 0], [0, 1, 0]])


def test_loads_are_cached_and_read_only():
    from sandbox.robot import mesh_dir

    path = mesh_dir() / "lower_shoulder/S1.DAE"
    first = load_mesh(path)
    assert load_mesh(str(path)) is first
    assert not first[0].vertices.flags.writeable
    with pytest.raises(ValueError):
        first[0].vertices[0, 0] = 1.0


def test_cache_notices_a_changed_file(tmp_path):
    path = tmp_path / "t.stl"
    _write_stl_binary(path, _TRIS[:1])
    assert n_triangles(load_mesh(path, None)) == 1
    _write_stl_binary(path, _TRIS)
    assert n_triangles(load_mesh(path, None)) == 2


def test_unsupported_or_missing_files(tmp_path):
    with pytest.raises(ValueError, match="expected a file ending in"):
        load_mesh(tmp_path / "mesh.ply")
    with pytest.raises(FileNotFoundError):
        load_mesh(tmp_path / "missing.stl")
    with pytest.raises(ValueError, match="resolution"):
        load_mesh(tmp_path / "missing.stl", resolution=-1.0)


def test_baxter_meshes_shrink_but_keep_their_extent():
    from sandbox.robot import mesh_dir

    path = mesh_dir() / "upper_shoulder/S0.DAE"
    full, simple = load_mesh(path, None), load_mesh(path, 0.002)
    assert n_triangles(simple) < 0.8 * n_triangles(full)
    lo = np.vstack([p.vertices for p in full]).min(0)
    hi = np.vstack([p.vertices for p in full]).max(0)
    np.testing.assert_allclose(np.vstack([p.vertices for p in simple]).min(0), lo, atol=0.002)
    np.testing.assert_allclose(np.vstack([p.vertices for p in simple]).max(0), hi, atol=0.002)
    assert [p.rgba is None for p in simple] == [p.rgba is None for p in full]

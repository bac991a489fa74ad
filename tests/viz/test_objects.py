"""meshcat objects from arrays: compact index types, colours, labels; all packable."""

from __future__ import annotations

import numpy as np
import pytest
import umsgpack
from meshcat.commands import SetObject

from sandbox.viz import objects


def _lowered(obj):
    data = SetObject(obj).lower()
    umsgpack.packb(data)  # what the scene sends must be packable
    return data["object"]


def test_small_meshes_use_16_bit_indices_and_float32_positions():
    vertices = np.random.default_rng(0).normal(size=(10, 3))
    faces = np.array([[0, 1, 2], [2, 3, 4]])
    geometry = _lowered(objects.tube_object(vertices, faces, [1, 0, 0, 1]))["geometries"][0]
    index, position = geometry["data"]["index"], geometry["data"]["attributes"]["position"]
    assert index["type"] == "Uint16Array" and index["array"].type == 0x14
    np.testing.assert_array_equal(np.frombuffer(index["array"].data, np.uint16), faces.ravel())
    assert position["type"] == "Float32Array" and position["itemSize"] == 3
    np.testing.assert_allclose(np.frombuffer(position["array"].data, np.float32).reshape(-1, 3),
                               vertices, rtol=1e-6)


def test_big_meshes_use_32_bit_indices():
    vertices = np.zeros((70000, 3))
    geometry = _lowered(objects.tube_object(vertices, [[0, 1, 69999]], [1, 1, 1, 1]))
    assert geometry["geometries"][0]["data"]["index"]["type"] == "Uint32Array"


@pytest.mark.parametrize(
    "rgba, expected",
    [([1, 0, 0, 1], 0xFF0000), ([0, 0.5, 1], 0x0080FF), ([2, -1, 0.2, 1], 0xFF0033)],
)
def test_hex_color(rgba, expected):
    assert objects.hex_color(rgba) == expected


def test_translucent_material_does_not_write_depth():
    material = _lowered(objects.box([1, 1, 1], [0, 1, 0, 0.3]))["materials"][0]
    assert material["transparent"] and material["opacity"] == pytest.approx(0.3)
    assert material["depthWrite"] is False
    opaque = _lowered(objects.sphere(0.1, [0, 1, 0, 1]))["materials"][0]
    assert not opaque["transparent"]


def test_label_is_a_text_texture_on_a_plane_facing_x():
    data = _lowered(objects.label("left 42%", height=0.03))
    (texture,) = data["textures"]
    assert texture["type"] == "_text" and texture["text"] == "left 42%"
    assert data["geometries"][0]["type"] == "PlaneGeometry"
    assert data["materials"][0]["map"] == texture["uuid"]
    # three.js reads the matrix column-major: the plane's normal (z) must end up along x
    matrix = np.reshape(data["object"]["matrix"], (4, 4)).T
    np.testing.assert_allclose(matrix[:3, :3] @ [0, 0, 1], [1, 0, 0])
    np.testing.assert_allclose(matrix[:3, :3] @ [0, 1, 0], [0, 0, 1])  # text up -> z


def test_cylinder_and_line_and_points_lower():
    assert _lowered(objects.cylinder(0.4, 0.1, [1, 1, 1, 1]))["geometries"][0]["height"] == 0.4
    assert _lowered(objects.line(np.zeros((3, 3)), [1, 1, 1, 1]))["object"]["type"] == "Line"
    assert _lowered(objects.points(np.zeros((3, 3)), [1, 0, 0, 1]))["object"]["type"] == "Points"

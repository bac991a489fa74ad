"""COLLADA reader: known answers on small documents, Baxter's files, error paths."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.viz.collada import read_collada

_DOC = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>Y_UP</up_axis></asset>
  <library_effects>
    <effect id="red-fx"><profile_COMMON><technique sid="common"><phong>
      <diffuse><color sid="diffuse">0.8 0.1 0.1 1</color></diffuse>
    </phong></technique></profile_COMMON></effect>
  </library_effects>
  <library_materials>
    <material id="red"><instance_effect url="#red-fx"/></material>
  </library_materials>
  <library_geometries>
    <geometry id="quad"><mesh>
      <source id="quad-pos"><float_array id="quad-pos-a" count="12">
        0 0 0  100 0 0  100 100 0  0 100 0</float_array>
        <technique_common><accessor source="#quad-pos-a" count="4" stride="3"/>
        </technique_common></source>
      <source id="quad-nrm"><float_array id="quad-nrm-a" count="3">0 0 1</float_array>
        <technique_common><accessor source="#quad-nrm-a" count="1" stride="3"/>
        </technique_common></source>
      <vertices id="quad-vtx"><input semantic="POSITION" source="#quad-pos"/></vertices>
      <polylist material="mat" count="1">
        <input semantic="VERTEX" source="#quad-vtx" offset="0"/>
        <input semantic="NORMAL" source="#quad-nrm" offset="1"/>
        <vcount>4</vcount>
        <p>0 0 1 0 2 0 3 0</p>
      </polylist>
      <triangles count="1">
        <input semantic="VERTEX" source="#quad-vtx" offset="0"/>
        <p>0 1 3</p>
      </triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene">
      <node id="outer"><translate>0 0 50</translate>
        <node id="inner">
          <matrix>1 0 0 10  0 1 0 0  0 0 1 0  0 0 0 1</matrix>
          <instance_geometry url="#quad"><bind_material><technique_common>
            <instance_material symbol="mat" target="#red"/>
          </technique_common></bind_material></instance_geometry>
        </node>
      </node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


@pytest.fixture
def doc(tmp_path):
    path = tmp_path / "quad.dae"
    path.write_text(_DOC)
    return path


def test_polylist_is_fan_triangulated_posed_and_scaled(doc):
    quad, tri = read_collada(doc)
    # cm -> m, then the nodes' translations (10, 0, 50) cm
    expected = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]) + [0.1, 0.0, 0.5]
    np.testing.assert_allclose(quad.vertices, expected, atol=1e-12)
    np.testing.assert_array_equal(quad.faces, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(tri.faces, [[0, 1, 3]])


def test_material_colour_through_the_binding(doc):
    quad, tri = read_collada(doc)
    np.testing.assert_allclose(quad.rgba, [0.8, 0.1, 0.1, 1.0])
    assert tri.rgba is None  # no material on that primitive


def test_up_axis_is_ignored(doc, tmp_path):
    other = tmp_path / "z.dae"
    other.write_text(_DOC.replace("Y_UP", "Z_UP"))
    np.testing.assert_array_equal(read_collada(doc)[0].vertices, read_collada(other)[0].vertices)


def test_mirroring_node_flips_the_winding(tmp_path):
    path = tmp_path / "m.dae"
    path.write_text(_DOC.replace("<translate>0 0 50</translate>", "<scale>-1 1 1</scale>"))
    quad = read_collada(path)[0]
    np.testing.assert_array_equal(quad.faces, [[2, 1, 0], [3, 2, 0]])


@pytest.mark.parametrize(
    "text, match",
    [("not xml at all <", "COLLADA"), ("<robot/>", "<COLLADA>")],
)
def test_not_collada_is_refused(tmp_path, text, match):
    path = tmp_path / "bad.dae"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        read_collada(path)


def test_primitive_without_vertex_input_is_refused(tmp_path):
    path = tmp_path / "novtx.dae"
    vertex = 'semantic="VERTEX" source="#quad-vtx" offset="0"/>\n        <p>0 1 3'
    normal = 'semantic="NORMAL" source="#quad-nrm" offset="0"/>\n        <p>0 1 3'
    assert vertex in _DOC
    path.write_text(_DOC.replace(vertex, normal))
    with pytest.raises(ValueError, match="VERTEX"):
        read_collada(path)


def test_baxter_torso_matches_its_collision_mesh():
    """Regression: base_link.DAE says Y_UP, yet its coordinates are z-up like its collision mesh."""
    from sandbox.robot import mesh_dir

    visual = np.vstack([p.vertices for p in read_collada(mesh_dir() / "torso/base_link.DAE")])
    collision = np.vstack(
        [p.vertices for p in read_collada(mesh_dir() / "torso/base_link_collision.DAE")]
    )
    np.testing.assert_allclose(visual.min(0), collision.min(0), atol=0.01)
    np.testing.assert_allclose(visual.max(0), collision.max(0), atol=0.01)


def test_every_baxter_mesh_reads_with_valid_triangles():
    from sandbox.robot import visuals

    for file in {v.filename for v in visuals() if v.kind == "mesh"}:
        parts = read_collada(file)
        assert parts, file
        for part in parts:
            assert part.faces.min() >= 0 and part.faces.max() < len(part.vertices)
            assert np.all(np.isfinite(part.vertices))
            assert np.abs(part.vertices).max() < 1.0  # metres: no link is a metre wide

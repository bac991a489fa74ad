"""Mirroring PyBullet bodies: geometry once, transforms of moved links only."""

from __future__ import annotations

import meshcat
import numpy as np
import pybullet
import pytest
import umsgpack

from sandbox.viz.mirror import BodyMirror, shape_objects
from sandbox.viz.scene import Scene


def _scene():
    scene = Scene()
    return scene, meshcat.Visualizer(window=scene)


def _drawn_links():
    from sandbox.robot import visuals

    return {v.link for v in visuals()}


@pytest.fixture(scope="module")
def mirrored(baxter):
    scene, vis = _scene()
    mirror = BodyMirror(vis["bodies"], baxter.client, baxter.body, "baxter",
                        links=_drawn_links())
    return scene, mirror


def test_every_drawn_link_gets_its_meshes_once(mirrored):
    scene, mirror = mirrored
    assert set(mirror.links) == _drawn_links()
    objects = [k for k, n in scene.nodes.items() if n.object is not None]
    assert len(objects) >= 38  # 38 URDF visuals, several of them with two or more colours
    assert all(k.startswith("/meshcat/bodies/baxter/") for k in objects)
    assert 100_000 < mirror.n_triangles < 410_000  # simplified (the full meshes: 410k)


def test_link_nodes_hold_pybullet_link_frames(mirrored, baxter):
    scene, mirror = mirrored
    mirror.update(force=True)
    poses = mirror.poses()
    for name in ("left_wrist", "torso", "pedestal"):
        data = umsgpack.unpackb(scene.nodes[f"/meshcat/bodies/baxter/{name}"].transform)
        np.testing.assert_allclose(np.reshape(data["matrix"], (4, 4)).T, poses[name], atol=1e-6)


def test_only_moved_links_are_sent(mirrored, baxter):
    from sandbox.robot import q_home
    from sandbox.robot.bullet import reset_arm

    _, mirror = mirrored
    mirror.update()
    assert mirror.update() == 0  # nothing moved
    from sandbox.robot import BaxterKinematics

    q = q_home().copy()
    q[5] += 0.2  # left_w1: moves what is below it, nothing above
    kin = BaxterKinematics()
    before, after = kin.link_poses(q_home()), kin.link_poses(q)
    below = {n for n in before if not np.allclose(before[n], after[n])}
    below |= {n for n in mirror.links if n.startswith("l_gripper_")}  # the fingers, too
    reset_arm(baxter, q)
    try:
        assert mirror.update() == len(below & set(mirror.links)) >= 8
    finally:
        reset_arm(baxter, q_home())
        mirror.update()


def test_collision_fallback_links_can_be_left_out(baxter):
    _, vis = _scene()
    everything = BodyMirror(vis, baxter.client, baxter.body, "all")
    assert "left_hand_link" in everything.links  # PyBullet's collision cylinder as a visual
    assert "left_hand_link" not in _drawn_links()


def test_colour_modes(baxter):
    scene, vis = _scene()
    BodyMirror(vis, baxter.client, baxter.body, "b", links=["left_gripper_base"]
               if "left_gripper_base" in _drawn_links() else ["left_gripper_base_link"],
               colors="bullet")
    colours = {umsgpack.unpackb(n.object)["object"]["materials"][0]["color"]
               for n in scene.nodes.values() if n.object is not None}
    assert colours == {0xFFFFFF}  # PyBullet's default white: the DAE's red/grey ignored


def test_primitives_become_meshcat_shapes():
    from sandbox.robot.bullet import connect
    from sandbox.viz.bodies import visual_shapes

    client = connect()
    try:
        cap = client.createVisualShape(pybullet.GEOM_CAPSULE, radius=0.05, length=0.2)
        sph = client.createVisualShape(pybullet.GEOM_SPHERE, radius=0.1)
        body = client.createMultiBody(0, -1, cap, linkMasses=[0], linkCollisionShapeIndices=[-1],
                                      linkVisualShapeIndices=[sph], linkPositions=[[0, 0, 1]],
                                      linkOrientations=[[0, 0, 0, 1]],
                                      linkInertialFramePositions=[[0, 0, 0]],
                                      linkInertialFrameOrientations=[[0, 0, 0, 1]],
                                      linkParentIndices=[0],
                                      linkJointTypes=[pybullet.JOINT_FIXED],
                                      linkJointAxis=[[0, 0, 1]])
        capsule, sphere = visual_shapes(client, body)
        parts = shape_objects(capsule)
        assert len(parts) == 3  # a cylinder and two end spheres
        np.testing.assert_allclose([p[1][2, 3] for p in parts[1:]], [0.1, -0.1])
        # three.js cylinders run along y: turned onto the shape's z axis
        np.testing.assert_allclose(parts[0][1][:3, :3] @ [0, 1, 0], [0, 0, 1])
        assert shape_objects(sphere)[0][0].geometry.radius == pytest.approx(0.1)
    finally:
        client.disconnect()


def test_unreadable_mesh_is_skipped_with_a_warning():
    from sandbox.viz.bodies import VisualShape

    shape = VisualShape(0, "l", "mesh", np.ones(3), "/nonexistent/x.dae", np.eye(4), np.ones(4))
    with pytest.warns(RuntimeWarning, match="cannot be drawn"):
        assert shape_objects(shape) == []


def test_bad_arguments(baxter):
    _, vis = _scene()
    with pytest.raises(ValueError, match="colors"):
        BodyMirror(vis, baxter.client, baxter.body, "x", colors="pink")
    with pytest.raises(ValueError, match="name"):
        BodyMirror(vis, baxter.client, baxter.body, "a/b")
    with pytest.raises(ValueError, match="links"):
        BodyMirror(vis, baxter.client, baxter.body, "x", links=["no_such_link"])

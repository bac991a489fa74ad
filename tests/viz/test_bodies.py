"""Reading PyBullet bodies: shape sizes, frames (base inertial offset), Baxter vs numpy FK."""

from __future__ import annotations

import numpy as np
import pybullet
import pytest

from sandbox.viz.bodies import FrameReader, link_names, pose_matrix, visual_shapes


@pytest.fixture
def client():
    from sandbox.robot.bullet import connect

    c = connect()
    yield c
    c.disconnect()


def _two_link_body(client):
    """A box base (inertial frame 1 m above its link frame) and a cylinder link."""
    box = client.createVisualShape(pybullet.GEOM_BOX, halfExtents=[0.1, 0.2, 0.3],
                                   visualFramePosition=[0.5, 0, 0], rgbaColor=[1, 0, 0, 1])
    col = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[0.1, 0.2, 0.3],
                                      collisionFramePosition=[0.5, 0, 0])
    cyl = client.createVisualShape(pybullet.GEOM_CYLINDER, radius=0.1, length=0.4)
    return client.createMultiBody(
        1.0, col, box, basePosition=[1, 2, 3], baseInertialFramePosition=[0, 0, 1],
        linkMasses=[1.0], linkCollisionShapeIndices=[-1], linkVisualShapeIndices=[cyl],
        linkPositions=[[0, 1, 0]], linkOrientations=[[0, 0, 0, 1]],
        linkInertialFramePositions=[[0, 0, 0.7]], linkInertialFrameOrientations=[[0, 0, 0, 1]],
        linkParentIndices=[0], linkJointTypes=[pybullet.JOINT_FIXED], linkJointAxis=[[0, 0, 1]])


def test_pose_matrix_matches_pybullet(client):
    rng = np.random.default_rng(0)
    q = rng.normal(size=(5, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    poses = pose_matrix(rng.normal(size=(5, 3)), q)
    for pose, quat in zip(poses, q):
        np.testing.assert_allclose(
            pose[:3, :3], np.reshape(client.getMatrixFromQuaternion(quat), (3, 3)), atol=1e-12)


def test_shapes_report_full_box_extents_and_cylinder_length_radius(client):
    body = _two_link_body(client)
    box, cyl = visual_shapes(client, body)
    assert (box.kind, box.link) == ("box", -1) and (cyl.kind, cyl.link) == ("cylinder", 0)
    np.testing.assert_allclose(box.size, [0.2, 0.4, 0.6])
    np.testing.assert_allclose(cyl.size[:2], [0.4, 0.1])
    np.testing.assert_allclose(box.origin[:3, 3], [0.5, 0, 0])
    np.testing.assert_allclose(box.rgba, [1, 0, 0, 1])


def test_base_frame_removes_the_inertial_offset(client):
    """The drawn box must sit where PyBullet's collision box (same frame offset) is."""
    body = _two_link_body(client)
    box = visual_shapes(client, body)[0]
    base = FrameReader(client, body, [-1]).read()[0]
    low, high = client.getAABB(body, -1)
    np.testing.assert_allclose((base @ box.origin)[:3, 3], (np.array(low) + high) / 2, atol=1e-6)


def test_link_frames_are_urdf_frames(client):
    body = _two_link_body(client)
    base, link = FrameReader(client, body, [-1, 0]).read()
    np.testing.assert_allclose(base[:3, 3], [1, 2, 3], atol=1e-9)
    np.testing.assert_allclose(link[:3, 3], [1, 3, 3], atol=1e-9)


def test_baxter_visuals_where_numpy_kinematics_puts_them(baxter):
    """Cross-check: PyBullet link frames x visual origins == numpy FK x URDF visual origins."""
    from sandbox.robot import BaxterKinematics, q_home, visuals

    kin = BaxterKinematics()
    q = q_home() + 0.3
    from sandbox.robot.bullet import reset_arm

    reset_arm(baxter, q)
    try:
        shapes = [s for s in visual_shapes(baxter.client, baxter.body) if s.kind == "mesh"]
        arm = [s for s in shapes if s.link_name in kin.links]
        assert len(arm) >= 10
        frames = FrameReader(baxter.client, baxter.body, [s.link for s in arm]).read()
        urdf = {(v.link, v.filename): v.origin for v in visuals()}
        fk = kin.link_poses(q, tuple(s.link_name for s in arm))
        for shape, frame in zip(arm, frames):
            expected = fk[shape.link_name] @ urdf[(shape.link_name, shape.filename)]
            np.testing.assert_allclose(frame @ shape.origin, expected, atol=1e-6)
    finally:
        reset_arm(baxter, q_home())


def test_link_names_and_bad_arguments(client):
    body = _two_link_body(client)
    names = link_names(client, body)
    assert set(names) == {-1, 0}
    with pytest.raises(ValueError, match="body"):
        visual_shapes(client, body + 7)
    with pytest.raises(ValueError, match="client"):
        visual_shapes(object(), body)
    with pytest.raises(ValueError, match="body"):
        FrameReader(client, True, [-1])

"""The minimal URDF reader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandbox.robot.assets import source_urdf_path
from sandbox.robot.urdf import chain_to, read_joints, rpy_matrix


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def test_rpy_is_fixed_axis_roll_then_pitch_then_yaw():
    r, p, y = 0.3, -1.1, 2.0
    expected = _rot(2, y) @ _rot(1, p) @ _rot(0, r)
    np.testing.assert_allclose(rpy_matrix(np.array([r, p, y])), expected, atol=1e-12)


def test_baxter_left_arm_joints_are_read():
    joints = read_joints(source_urdf_path())
    s1 = joints["left_lower_shoulder"]
    assert (s1.name, s1.type, s1.parent) == ("left_s1", "revolute", "left_upper_shoulder")
    assert (s1.lower, s1.upper) == (-2.147, 1.047)
    np.testing.assert_allclose(s1.origin[:3, 3], [0.069, 0.0, 0.27035])
    np.testing.assert_allclose(s1.axis, [0.0, 0.0, 1.0])


def test_chain_to_the_gripper_runs_from_the_root_through_the_seven_arm_joints():
    chain = chain_to(read_joints(source_urdf_path()), "left_gripper")
    assert chain[0].parent == "base" and chain[-1].child == "left_gripper"
    moving = [j.name for j in chain if j.type != "fixed"]
    assert moving == ["left_s0", "left_s1", "left_e0", "left_e1", "left_w0", "left_w1", "left_w2"]
    assert all(a.child == b.parent for a, b in zip(chain[:-1], chain[1:], strict=True))


def test_unknown_link_and_non_urdf_files_are_refused(tmp_path):
    with pytest.raises(ValueError, match="link"):
        chain_to(read_joints(source_urdf_path()), "no_such_link")
    bad = tmp_path / "x.urdf"
    bad.write_text("<notrobot/>")
    with pytest.raises(ValueError, match="<robot>"):
        read_joints(bad)
    bad.write_text("<robot")
    with pytest.raises(ValueError, match="parse error"):
        read_joints(bad)


def test_visuals_of_the_left_arm():
    from sandbox.robot import visuals

    found = {v.link: v for v in visuals()}
    wrist = found["left_wrist"]
    assert wrist.kind == "mesh" and wrist.filename.endswith("meshes/wrist/W2.DAE")
    assert Path(wrist.filename).is_file()
    np.testing.assert_allclose(wrist.size, [1.0, 1.0, 1.0])
    assert wrist.origin.shape == (4, 4)
    screen = [v for v in visuals() if v.kind == "box"]
    assert screen and all(v.size.shape == (3,) for v in screen)
    assert all(v.filename == "" for v in visuals() if v.kind != "mesh")

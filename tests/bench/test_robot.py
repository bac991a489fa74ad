"""The robot measurement script (its cheap parts; loading PyBullet is tested in test_bullet)."""

from __future__ import annotations

import numpy as np

from sandbox.bench.robot import bench_ik, front_targets, recorded_fk_offsets
from sandbox.robot import ARM_JOINTS, BaxterKinematics


def test_front_targets_are_reachable_and_in_front():
    kin = BaxterKinematics()
    targets = front_targets(kin, 50, np.random.default_rng(0), "left_gripper")
    assert targets.shape == (50, 3) and np.all(targets[:, 0] > 0.4)


def test_recorded_offsets_known_answer(tmp_path):
    kin = BaxterKinematics()
    q = np.random.default_rng(1).uniform(kin.lower, kin.upper, size=(5, 7))
    offset = np.array([0.001, -0.002, 0.0106])
    hand = kin.fk(q, link="left_hand_link") - offset
    header = ["t", *ARM_JOINTS, "baxter_left_hand_x", "baxter_left_hand_y", "baxter_left_hand_z"]
    folder = tmp_path / "task"
    folder.mkdir()
    rows = np.column_stack([np.arange(5) * 0.01, q, hand])
    lines = [",".join(header)] + [",".join(f"{v:.12f}" for v in row) for row in rows]
    (folder / "trial.csv").write_text("\n".join(lines) + "\n")
    count, diff = recorded_fk_offsets(kin, tmp_path)
    assert count == 1 and diff.shape == (5, 3)
    np.testing.assert_allclose(diff, np.broadcast_to(offset, (5, 3)), atol=1e-9)


def test_bench_ik_reports_accuracy(capsys):
    bench_ik(BaxterKinematics(), 30, "left_gripper")
    out = capsys.readouterr().out
    assert "success 1.0000" in out and "within limits True" in out
    assert "success [False, False, False]" in out

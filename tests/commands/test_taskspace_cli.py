"""A robot part in task space (issue 28 item 2), from a spec file through the commands.

The set (:mod:`tests.commands.taskspace_data`) has the receiving hand's x, y, z
(m) as robot part: ``fit`` stores that the part is in task space, ``evaluate``
(leave-one-out and ``--model``) and ``compare`` measure e_p on the predicted
positions themselves (no forward kinematics) and report e_q as not applicable
(null in JSON, "n/a" in tables); ``episodes`` replays it on every arm through
the arm's inverse kinematics (issue 23). A joint-space part that is not Baxter's
7 joints is refused by ``data summary`` and ``fit``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main
from tests.commands.taskspace_data import write_set

FAST = ["--windows", "0.5", "--ratios", "0.5", "--workers", "1", "--no-progress"]


@pytest.fixture(scope="module")
def taskspace(tmp_path_factory) -> tuple[Path, Path]:
    """(data folder, spec file) of the task-space set."""
    root = tmp_path_factory.mktemp("taskspace")
    spec = write_set(root)
    return root / "data", spec


@pytest.fixture(scope="module")
def model(taskspace, tmp_path_factory) -> Path:
    data, spec = taskspace
    out = tmp_path_factory.mktemp("model") / "m.npz"
    assert main(["fit", "--data", str(data), "--spec", str(spec), "--n-basis", "11",
                 "--out", str(out)]) == 0
    return out


def test_fit_stores_the_task_space_and_learns_the_geometry(model, taskspace, capsys):
    from sandbox.core import IProMP
    from sandbox.data.geometry import geometry_of

    loaded = IProMP.load(model)
    assert loaded.robot_space == "task" and loaded.robot_names == ("rx", "ry", "rz")
    geometry, note = geometry_of(loaded)
    assert note is None                         # the receiving hand itself is the fingertip
    for task in loaded.tasks:      # it stops 3 cm beside the hand (met a little before: 5 cm)
        assert np.linalg.norm(geometry.offset(task) - [0.0, 0.03, 0.0]) < 0.05
    data, spec = taskspace
    assert main(["fit", "--data", str(data), "--spec", str(spec), "--n-basis", "11",
                 "--out", str(model.parent / "j.npz"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["robot_space"] == "task"
    floor = summary["noise_floor"]["hand"]          # issue 28 item 4: reported by fit
    assert floor["floor_m"] == pytest.approx(0.02)      # 15 x 1 mm is below the minimum
    assert floor["source"] == "max(noise_floor 20 mm, 15 x jitter)"
    assert floor["jitter_m"] == pytest.approx(0.001, rel=0.2)    # the set's 1 mm jitter


@pytest.mark.parametrize("with_model", [False, True])
def test_evaluate_measures_e_p_on_the_positions_and_e_q_does_not_apply(
        taskspace, model, tmp_path, capsys, with_model):
    data, spec = taskspace
    out, markdown = tmp_path / "report.json", tmp_path / "report.md"
    extra = ["--model", str(model)] if with_model else ["--config", str(n_basis(tmp_path))]
    assert main(["evaluate", "--data", str(data), "--spec", str(spec), "--out", str(out),
                 "--markdown", str(markdown), "--plots", str(tmp_path / "plots"), *extra,
                 *FAST]) == 0
    assert (tmp_path / "plots" / "direct.png").exists()       # e_q's panel says n/a
    printed = capsys.readouterr().out
    assert "n/a" in printed and "q: expected joint angles" not in printed
    report = json.loads(out.read_text())
    for section in (report["dynamic"]["0.5"], report["static"]["0.5"], report["oracle"]):
        mean = section["mean"]
        assert mean["e_q"] is None and mean["e_q_ci"] == [None, None]
        assert 0.0 < mean["e_p"] < 0.05             # metres, goals 30 cm apart
    assert report["differences"]["0.5"]["0.5"]["e_q"] is None
    assert "| n/a |" in markdown.read_text()


def n_basis(folder: Path) -> Path:
    """A settings file with a small basis (quick fits)."""
    path = folder / "settings.yaml"
    path.write_text("n_basis: 11\n")
    return path


def test_e_p_is_the_distance_of_the_final_positions(taskspace, model):
    """Known answer: e_p of one trial is |predicted final position - recorded final one|."""
    from sandbox.core import IProMP
    from sandbox.data.recorded import load_trial
    from sandbox.data.spec import DataSpec
    from sandbox.eval.loocv import EvalConfig, evaluate_trial

    data, spec_file = taskspace
    spec = DataSpec.load(spec_file)
    path = sorted((data / "left").glob("*.csv"))[0]
    test = load_trial(path, spec=spec, preprocess="causal")
    fitted = IProMP.load(model)

    def no_fk(q):
        raise AssertionError("forward kinematics used on a task-space robot part")

    res = evaluate_trial(fitted, test, EvalConfig(windows=(0.5,), ratios=(0.5,)), no_fk)
    from sandbox.core import predict
    from sandbox.core.likelihood import Scorer
    from sandbox.eval.loocv import kept_observations

    t = test.times - test.times[0]
    t_obs, y_obs = kept_observations(fitted, t, test.human, 2)
    T = float(t[fitted.motion_end(t, test.robot, test.human)])
    oracle = predict(fitted, Scorer(fitted), t_obs, y_obs, task=0, duration=T)
    mean, _ = oracle.trajectory(fitted.basis, t)
    assert res["oracle"]["e_p"] == pytest.approx(np.linalg.norm(mean[-1] - test.robot[-1]))
    assert res["oracle"]["e_q"] is None and res["static"]["0.5"]["e_q"] is None


def test_compare_reports_e_q_as_not_applicable(taskspace, tmp_path, capsys):
    data, spec = taskspace
    out = tmp_path / "cmp"
    assert main(["compare", "--data", str(data), "--spec", str(spec), "--out", str(out),
                 "--methods", "dynamic,nearest", "--workers", "1", "--no-progress"]) == 0
    rows = json.loads((out / "compare.json").read_text())["rows"]
    assert rows["dynamic"]["e_q"] is None and rows["nearest"]["e_q"] is None
    assert all(0.0 < r["e_p"] < 0.05 for r in rows.values())
    assert "| n/a |" in (out / "compare.md").read_text()


@pytest.mark.parametrize("robot", ["baxter", "ur5"])
def test_episodes_follow_a_task_space_part_with_any_arm(taskspace, model, tmp_path, robot):
    """Issue 23: the plan's positions through the arm's inverse kinematics (refused before)."""
    data, spec = taskspace
    out = tmp_path / "e.json"
    assert main(["episodes", "--scenario", "recorded", "--data", str(data), "--spec", str(spec),
                 "--episodes", "2", "--policies", "dynamic,recorded_robot", "--robot", robot,
                 "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert result["dynamic"]["robot"] == robot and result["dynamic"]["reach"] == 1.0
    assert result["recorded_robot"]["summary"]["success_rate"] == 1.0
    assert all(e["outcome"] in ("handover", "missed") for e in result["dynamic"]["episodes"])
    from sandbox.commands import _model
    from sandbox.core import IProMP
    from sandbox.episodes.policy import check_joint_model

    _model.baxter(IProMP.load(model))              # accepted: no error
    check_joint_model(IProMP.load(model))


def test_a_joint_space_part_that_is_not_baxters_arm_is_refused_early(taskspace, tmp_path,
                                                                      capsys):
    data, spec = taskspace
    joint = tmp_path / "joint.yaml"
    joint.write_text(spec.read_text().replace(", space: task", ""))
    for argv in (["data", "summary", "--data", str(data), "--spec", str(joint)],
                 ["fit", "--data", str(data), "--spec", str(joint), "--out",
                  str(tmp_path / "m.npz")]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: robot: expected the 7 joint angles") and "space: task" in err
        assert not (tmp_path / "m.npz").exists()


def test_data_summary_reports_the_jitter_and_the_floor(taskspace, capsys):
    data, spec = taskspace
    assert main(["data", "summary", "--data", str(data), "--spec", str(spec), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["robot_space"] == "task"
    hand = result["noise_floor"]["hand"]
    assert hand["jitter_m"] == pytest.approx(0.001, rel=0.2) and hand["floor_m"] == 0.02
    assert main(["data", "summary", "--data", str(data), "--spec", str(spec)]) == 0
    assert ("hand noise floor 20.0 mm (max(noise_floor 20 mm, 15 x jitter)); raw jitter"
            in capsys.readouterr().out)


def test_the_mocap_layout_with_the_receiving_hand_as_a_task_space_robot(tmp_path, capsys):
    """Issue 28's target layout (mm, Z-up world frame, 120 Hz, files, labels, long windows),
    the taker's hand as the robot part: its units and frame apply to it as to the hand."""
    from sandbox.core import IProMP
    from tests.data.mocap_fixture import SPEC, write_mocap_set

    write_mocap_set(tmp_path / "set", n_per_task=3)
    joints = ("robot: [robot.left_s0, robot.left_s1, robot.left_e0, robot.left_e1,\n"
              "        robot.left_w0, robot.left_w1, robot.left_w2]")
    assert joints in SPEC
    spec = tmp_path / "task.yaml"
    spec.write_text(SPEC.replace("  robot: baxter_left_arm.csv", "  taker: taker_RHand_pose.csv")
                    .replace(joints, "robot: {columns: [taker.x, taker.y, taker.z], space: task}"))
    assert main(["fit", "--data", str(tmp_path / "set"), "--spec", str(spec), "--n-basis", "11",
                 "--out", str(tmp_path / "m.npz")]) == 0, capsys.readouterr().err
    model = IProMP.load(tmp_path / "m.npz")
    assert model.robot_space == "task"
    robot = model.task_models[0].weights.mean.reshape(6, 11)[3:]     # robot x, y, z weights
    assert np.all(np.abs(robot) < 1.5)            # metres in Baxter's base frame, not mm
    out = tmp_path / "r.json"
    assert main(["evaluate", "--data", str(tmp_path / "set"), "--spec", str(spec),
                 "--out", str(out), "--config", str(n_basis(tmp_path)), *FAST]) == 0
    report = json.loads(out.read_text())
    assert report["dynamic"]["0.5"]["mean"]["e_q"] is None
    assert 0.0 < report["dynamic"]["0.5"]["mean"]["e_p"] < 0.1

"""``--spec`` on the recorded episodes and scenarios (issue 28 item 3): trials loaded with the
spec, the environment given each replayed motion; no usable trial is one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sandbox.data.spec import DataSpec
from sandbox.episodes.replays import plan_replays
from tests.commands.taskspace_data import GOALS, trial


def write_joint_set(root: Path, n_per_task: int = 3) -> DataSpec:
    """The task-space set's hand with 7 made-up joint columns, in own column names."""
    rng = np.random.default_rng(0)
    for task in GOALS:
        (root / task).mkdir(parents=True, exist_ok=True)
        for i in range(n_per_task):
            rows = trial(task, rng)
            s = np.linspace(0.0, 1.0, rows.shape[0])[:, None]
            joints = 0.1 * np.arange(7) + s * (0.3 if task == "left" else -0.3)
            joints = joints + rng.normal(0, 0.005, joints.shape)
            np.savetxt(root / task / f"{i}.csv", np.column_stack([rows[:, :4], joints]),
                       delimiter=",", comments="", fmt="%.6f",
                       header="stamp,hx,hy,hz," + ",".join(f"j{j}" for j in range(7)))
    return DataSpec.from_dict({"time": "stamp", "robot": [f"j{j}" for j in range(7)],
                               "modalities": {"hand": {"columns": ["hx", "hy", "hz"]}}})


def test_replays_with_a_spec_give_the_environment_the_motion(tmp_path):
    from sandbox.envs.human import HumanMotion

    spec = write_joint_set(tmp_path)
    replays = plan_replays(tmp_path, 2, 0, spec=spec)
    for r in replays:
        motion = r.options["motion"]
        assert isinstance(motion, HumanMotion) and "source" not in r.options
        assert motion.task == r.demo.task and motion.measured.shape[1] == 3
        assert motion.times[0] == 0.0 and np.isfinite(motion.true).all()


def test_without_the_spec_no_usable_trial_is_one_line(tmp_path):
    write_joint_set(tmp_path)
    with pytest.raises(ValueError) as caught:
        plan_replays(tmp_path, 2, 0)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"no usable trial in data {tmp_path}: 6 skipped (missing column")


def test_a_task_space_spec_is_replayed(tmp_path):
    """Issue 23: the arms follow a task-space robot part through their IK (refused before)."""
    from tests.commands.taskspace_data import write_set

    spec = DataSpec.load(write_set(tmp_path))
    replays = plan_replays(tmp_path / "data", 2, 0, spec=spec)
    assert len(replays) == 2 and all(r.model.robot_space == "task" for r in replays)
    assert all(r.demo.robot.shape[1] == 3 for r in replays)


def test_a_scenario_with_a_recorded_human_takes_the_spec(tmp_path):
    from sandbox.episodes.scenario_files import load_scenario
    from sandbox.episodes.scenario_runner import build_model, reset_options

    write_joint_set(tmp_path / "set")
    (tmp_path / "spec.yaml").write_text(
        "time: stamp\nrobot: [j0, j1, j2, j3, j4, j5, j6]\n"
        "modalities:\n  hand: {columns: [hx, hy, hz]}\n")
    path = tmp_path / "s.yaml"
    path.write_text("human: {recorded: set, task: left, trial: 0}\n"
                    "policy: {type: dynamic, dow_t: 0.2}\n")
    with pytest.raises(ValueError, match=r"^no usable trial in human.recorded .*: 6 skipped"):
        build_model(load_scenario(path))
    scenario = load_scenario(path, spec=tmp_path / "spec.yaml")
    model = build_model(scenario)
    assert model.tasks == ("left", "right") and model.n_robot == 7
    assert reset_options(scenario, model)["motion"].task == "left"
    path.write_text("human: {waypoints: [{t: 0, position: [1, 0, 0]}, "
                    "{t: 1, position: [0.8, 0, 0]}]}\npolicy: {type: dynamic}\n")
    with pytest.raises(ValueError, match="human: expected a recorded human"):
        load_scenario(path, spec=tmp_path / "spec.yaml")

"""Spec files: built-in modalities, the user's own layout, every mistake a clear error."""

import json

import pytest

from sandbox.core.modality import Modality
from sandbox.data.spec import ARM, BUILT_IN, EMG, HAND, DataSpec, resolve


def test_built_in_modalities_are_the_recordings_columns():
    assert HAND.dims == ("human_left_hand_x", "human_left_hand_y", "human_left_hand_z")
    assert ARM.dims[:3] == ("human_left_elbow_x", "human_left_elbow_y", "human_left_elbow_z")
    assert ARM.size == 6 and EMG.size == 8 and EMG.kind == "signal"
    spec = DataSpec()
    assert spec.observe == ("hand",) and spec.time == "t" and spec.robot[0] == "left_s0"
    assert [m.name for m in spec.observed("hand,arm,emg")] == ["hand", "arm", "emg"]
    assert sum(m.size for m in spec.observed(["hand", "arm", "emg"])) == 17


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_spec_file_adds_modalities_and_columns(tmp_path, suffix):
    data = {"time": "stamp", "robot": ["j1", "j2"], "observe": ["wrist", "grip"],
            "modalities": {"wrist": {"columns": ["wx", "wy", "wz"], "kind": "position"},
                           "grip": {"columns": ["f1", "f2"], "kind": "signal", "units": "N"}}}
    path = tmp_path / f"spec{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(data))
    else:
        import yaml

        path.write_text(yaml.safe_dump(data))
    spec = DataSpec.load(path)
    assert (spec.time, spec.robot, spec.observe) == ("stamp", ("j1", "j2"), ("wrist", "grip"))
    assert spec.modalities["grip"] == Modality("grip", ("f1", "f2"), "signal", "N")
    assert set(BUILT_IN) <= set(spec.modalities)          # built-ins stay available
    assert DataSpec.from_dict(spec.to_dict()) == spec
    assert resolve(path).observe == ("wrist", "grip")


def test_column_shorthands_rename_the_hand_and_robot():
    spec = resolve(None, human_columns=["a", "b", "c"], robot_columns=["r1"])
    assert spec.modalities["hand"].dims == ("a", "b", "c") and spec.robot == ("r1",)


@pytest.mark.parametrize("text, message", [
    ("[1, 2]", "expected a mapping"),
    ("colour: red", r"unknown keys \['colour'\]"),
    ("modalities: {w: {kind: position}}", "'columns' is missing"),
    ("modalities: {w: {columns: [a], kind: force}}", "kind expected one of"),
    ("modalities: {w: {columns: [a], size: 3}}", r"unknown keys \['size'\]"),
    ("modalities: {w: {columns: a}}", "expected a list of names"),
    ("modalities: [a, b]", "expected a mapping name"),
    ("observe: [eeg]", r"expected names among .*got \['eeg'\]"),
    ("robot: left_s0", "robot: expected a list of names"),
    ("modalities: {w: {columns: [a, a]}}", "repeat"),
    (": : :", "invalid YAML at line 1"),
])
def test_bad_spec_files_name_the_file_and_the_key(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message) as info:
        DataSpec.load(path)
    assert str(path) in str(info.value)


def test_spec_errors():
    with pytest.raises(ValueError, match="existing YAML or JSON"):
        DataSpec.load("/no/such/spec.yaml")
    with pytest.raises(ValueError, match="also the time or robot"):
        DataSpec().with_columns(human=["t", "y", "z"]).observed("hand")
    with pytest.raises(ValueError, match="more than one modality"):
        DataSpec(modalities={**BUILT_IN, "twin": Modality("twin", HAND.dims)}).observed(
            "hand,twin")


# --------------------------------------------------------------- robot part (issue 28 item 2)
def test_a_robot_part_in_task_space_is_declared_and_kept(tmp_path):
    spec = DataSpec.from_dict({"robot": {"columns": ["rx", "ry", "rz"], "space": "task"}})
    assert spec.robot == ("rx", "ry", "rz") and spec.robot_space == "task"
    assert DataSpec.from_dict(spec.to_dict()) == spec          # the cache key's form
    assert DataSpec.from_dict({"robot": {"columns": ["a"]}}).robot_space == "joint"
    assert DataSpec().robot_space == "joint" and DataSpec().to_dict()["robot"][0] == "left_s0"
    path = tmp_path / "s.yaml"
    path.write_text("robot: {columns: [rx, ry, rz], space: task}\n")
    assert resolve(path, robot_columns=["a", "b", "c"]).robot_space == "task"


@pytest.mark.parametrize(("robot", "message"), [
    ({"columns": ["a"], "space": "cartesian"}, r"robot.space: expected one of \['joint', "
                                               r"'task'\], got 'cartesian'"),
    ({"columns": ["a"], "frame": "base"}, r"robot: unknown keys \['frame'\]; expected some of "
                                          r"\['columns', 'space'\]"),
    ({"space": "task"}, "robot: 'columns' is missing"),
    ({"columns": "rx", "space": "task"}, "robot: expected a list of names"),
])
def test_a_bad_robot_entry_is_one_line_naming_the_key(robot, message):
    with pytest.raises(ValueError, match=message):
        DataSpec.from_dict({"robot": robot})

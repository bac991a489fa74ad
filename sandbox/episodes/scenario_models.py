"""A scenario's model file against the scenario: what it observes, its robot, its tasks.

Read by :func:`~sandbox.episodes.scenario_files.load_scenario` (``model.file``, or
``play --model``): the file must observe the scenario's modalities, drive Baxter's 7
left-arm joints and know the tasks the human will do, as ``demo --model`` and
``evaluate --model`` require (issue 26).
"""

from __future__ import annotations

from typing import Any


def default_observe(model: dict, env_modalities: tuple[str, ...]) -> list[str]:
    """``hand``, or the modalities of the model file that the environments observe
    (``env_modalities``)."""
    if "file" not in model:
        return ["hand"]
    from sandbox.core import IProMP

    names = [n for n in IProMP.load(model["file"]).modality_names if n in env_modalities]
    return names or ["hand"]


def human_tasks(kind: str, human: dict, family: str) -> tuple[str, list[str]]:
    """Where the human's tasks come from and which they are: the synthetic human's named
    tasks (every family task if none is named), the recorded trial's; none for waypoints
    (a scripted path is no task of any model: its label is free)."""
    if kind == "waypoints":
        return "human", []
    if kind == "recorded":
        return "human.task", [human["task"]]
    named = [human[k] for k in ("task", "switch_to") if human.get(k) is not None]
    if named:
        return "human.task/switch_to", named
    from sandbox.envs.sources import family_tasks

    return f"family {family!r}", list(family_tasks(family))


def check_model_file(check: Any, file: str, observe: tuple[str, ...],
                tasks: tuple[str, list[str]]) -> None:
    """The model file observes ``observe``, drives Baxter's arm and knows the human's tasks
    (as ``demo --model`` and ``evaluate --model`` require)."""
    from sandbox.core import IProMP

    model = IProMP.load(file)
    if not set(observe) <= set(model.modality_names):
        check.fail("observe", f"modalities of the model file {file} "
                              f"{list(model.modality_names)}", list(observe))
    if model.n_robot != (3 if model.robot_space == "task" else 7):
        check.fail("model.file", "a model of Baxter's 7 left-arm joints or of a task-space "
                                 "position (3 dims, m)",
                   f"{model.n_robot} robot dims in {model.robot_space} space")
    source, wanted = tasks
    if any(t not in model.tasks for t in wanted):
        raise ValueError(f"scenario {check.path}: model.file: expected a model that knows the "
                         f"human's tasks {wanted} ({source}), got one of {list(model.tasks)} "
                         f"({file})")

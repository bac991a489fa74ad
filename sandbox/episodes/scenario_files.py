"""Scripted scenario files (JSON or YAML): who hands over what, how the human moves, which policy.

A scenario file is one mapping (YAML needs PyYAML; paths are relative to the file)::

    name: up, then right            # optional label
    family: diverging               # synthetic tasks of the env and model: diverging | objects
    seed: 0                         # reset seed (synthetic motion, tracker noise)
    object: box                     # optional: box, glasses_case, tape, measuring_tape, screwdriver
    speed: 1.0                      # human speed factor (0.25 - 4)
    time_limit: 6.0                 # episode length limit (s)
    robot: baxter                   # the arm: baxter | panda | ur5 | kinova (retargeted)
    observe: [hand]                 # modalities the policy observes: hand, arm, emg (or
                                    # "hand,arm"); the model is fitted on these (synthetic:
                                    # hand, arm; recorded: hand, arm, emg)
    human:                          # exactly one of the three forms below
      task: up                      # 1. synthetic reach of a family task (random if omitted),
      switch_to: right              #    optionally switching to another task
      switch_phase: 0.55            #    at this fraction of the motion
    # human:
    #   waypoints:                  # 2. scripted: the hand passes these points (m, Baxter's
    #     - {t: 0.0, position: [1.10, -0.12, 0.25]}   # base frame) at these times (s),
    #     - {t: 1.5, position: [0.80, 0.00, 0.25]}    # minimum-jerk in between
    #   task: scripted              #    label; tracker: {noise_m: ..., glitch_rate: ...}
    # human:
    #   recorded: ../data/birl-handover-20180329      # 3. a recorded trial replayed
    #   task: pencil_box
    #   trial: 3                    #    index among the task's trials or file name
    #   spec: layout.yaml           #    the set's spec file (play --spec), if not the built-in
    policy:
      type: dynamic                 # dynamic (dow_t) | static (ratio)
      dow_t: 0.2
      options: {blend_rate: 50}     # more predictor/policy options (optional)
    model:                          # optional
      demos: 20                     # synthetic demos per task (seed: model_seed)
      seed: 0
      options: {n_basis: 15}        # IProMP options of the model fitted here (optional)
      file: model.npz               # or a saved model (IProMP.save, python -m sandbox fit);
                                    # then observe defaults to the model's modalities; it
                                    # must know the human's tasks (named, or the family's)

With a recorded human and no model file, the model is fitted on all the
other trials of the recorded set (leave-one-out). :func:`load_scenario`
validates a file and raises ``ValueError`` naming the file, the key, what was
expected and what came; :func:`~sandbox.episodes.scenario_runner.run_scenario_file`
runs it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sandbox.episodes.scenario_models import check_model_file, default_observe, human_tasks
from sandbox.episodes.scenario_options import checked_options, keywords, policy_options
from sandbox.validation import MAPPING_SUFFIXES, read_mapping, short_text

SUFFIXES = MAPPING_SUFFIXES
FAMILIES = {"diverging": "sandbox/BaxterHandoverDiverging-v1",
            "objects": "sandbox/BaxterHandover-v1"}
TOP_KEYS = ("name", "family", "seed", "object", "speed", "time_limit", "observe", "human",
            "policy", "model", "robot")
#: Modalities the environments' observations carry.
ENV_MODALITIES = ("hand", "arm", "emg")
#: Modalities the synthetic motions and models carry (EMG is not simulated).
SYNTHETIC_MODALITIES = ("hand", "arm")
HUMAN_KEYS = {"synthetic": ("task", "switch_to", "switch_phase"),
              "waypoints": ("waypoints", "task", "tracker"),
              "recorded": ("recorded", "task", "trial", "spec")}
POLICY_KEYS = {"dynamic": ("type", "dow_t", "options"), "static": ("type", "ratio", "options")}
MODEL_KEYS = ("demos", "seed", "file", "options")
#: Folder of the example scenarios shipped with the package.
EXAMPLES = Path(__file__).resolve().parent / "scenario_examples"


@dataclass(frozen=True)
class Scenario:
    """A validated scenario file (see the module docstring for the meaning of each field)."""

    path: Path
    name: str
    family: str
    seed: int
    human_kind: str
    human: dict[str, Any]
    policy: dict[str, Any]
    model: dict[str, Any] = field(default_factory=dict)
    object: str | None = None
    speed: float = 1.0
    time_limit: float = 6.0
    observe: tuple[str, ...] = ("hand",)
    robot: str = "baxter"

    @property
    def env_id(self) -> str:
        """The Gymnasium id of the scenario's family (``FAMILIES[family]``)."""
        return FAMILIES[self.family]


class _Checker:
    """Raises ``ValueError("scenario <file>: <key>: expected ..., got ...")``."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, key: str, expected: str, got: Any) -> None:
        text = repr(got)
        text = text if len(text) <= 80 else text[:77] + "..."
        raise ValueError(f"scenario {self.path}: {key}: expected {expected}, got {text}")

    def keys(self, data: Any, key: str, allowed) -> dict:
        if not isinstance(data, Mapping):
            self.fail(key, "a mapping", data)
        unknown = sorted(str(k) for k in set(data) - set(allowed))
        if unknown:
            self.fail(key, f"keys among {list(allowed)}", unknown)
        return dict(data)

    def bounded(self, value: Any, key: str, name: str) -> Any:
        """``value`` within the range ``name`` of the one table, :data:`sandbox.limits.BOUNDS`."""
        from sandbox.limits import BOUNDS

        try:
            return BOUNDS[name].check(value, key)
        except ValueError as error:
            raise ValueError(f"scenario {self.path}: {error}") from None

    def choice(self, value: Any, key: str, choices) -> str:
        if value not in tuple(choices):
            self.fail(key, f"one of {list(choices)}", value)
        return str(value)

    def text(self, value: Any, key: str) -> str:
        if not isinstance(value, str) or not value:
            self.fail(key, "a non-empty string", value)
        return value


def resolve(path: str | Path) -> Path:
    """The scenario file ``path``, or the shipped example of that name (``intent_switch``)."""
    path = Path(path)
    if _exists(path, "is_file"):
        return path
    for suffix in ("", *SUFFIXES):
        example = EXAMPLES / f"{path.name}{suffix}"
        if _exists(example, "is_file") and not path.parent.parts:
            return example
    names = sorted(p.stem for p in EXAMPLES.glob("*") if p.suffix in SUFFIXES)
    raise ValueError(f"scenario: expected an existing .json/.yaml file or an example name "
                     f"({', '.join(names)}), got {short_text(str(path))}")



def _exists(path: Path, kind: str) -> bool:
    """``path.is_file()`` or ``path.is_dir()`` (``kind``); False for a name the system refuses
    (too long, a NUL byte...)."""
    try:
        return bool(getattr(path, kind)())
    except (OSError, ValueError):
        return False


def load_scenario(path: str | Path, *, observe: list[str] | str | None = None,
                  model: str | Path | None = None, options: Mapping | None = None,
                  model_options: Mapping | None = None, spec: str | Path | None = None,
                  robot: str | None = None) -> Scenario:
    """Read and validate a scenario file (or a shipped example by name).

    ``observe`` (e.g. ``"hand,arm"``), if given, replaces the file's ``observe:``;
    ``model`` (a saved model's path, relative to the working folder) its
    ``model.file``. ``options`` (predictor) and ``model_options`` (IProMP) fill
    in what the file's ``policy.options`` and ``model.options`` do not set
    (``play --config``). ``spec`` (a spec file, relative to the working folder) is the
    recorded human's ``human.spec`` (``play --spec``); refused for another human.
    ``robot`` (``play --robot``) replaces the file's ``robot:``.
    """
    path = resolve(path)
    check = _Checker(path)
    data = check.keys(read_mapping(path), "top level", TOP_KEYS)
    if observe is not None:
        data["observe"] = observe
    if spec is not None:
        if not isinstance(data.get("human"), Mapping) or "recorded" not in data["human"]:
            check.fail("human", "a recorded human (human.recorded) with --spec", data.get("human"))
        data["human"] = {**data["human"], "spec": str(Path(spec).resolve())}
    data = _fill_in(check, data, model, options, model_options)
    for key in ("human", "policy"):
        if key not in data:
            check.fail(key, "this key (required)", "nothing")
    family = check.choice(data.get("family", "diverging"), "family", FAMILIES)
    from sandbox.robot.arms import ARMS

    arm = check.choice(robot or data.get("robot", "baxter"), "robot", ARMS)
    obj = data.get("object")
    if obj is not None:
        import sandbox.urdf as urdf

        obj = check.choice(obj, "object", urdf.OBJECTS)
    seed = check.bounded(data.get("seed", 0), "seed", "seed")
    kind, human = _human(check, data["human"], family, path.parent, seed)
    model_spec = _model(check, data.get("model"), path.parent)
    names = _observe(check, data.get("observe", default_observe(model_spec, ENV_MODALITIES)))
    if "file" in model_spec:
        check_model_file(check, model_spec["file"], names, human_tasks(kind, human, family))
    synthetic_model = kind != "recorded" and "file" not in model_spec
    if synthetic_model and not set(names) <= set(SYNTHETIC_MODALITIES):
        check.fail("observe", f"modalities of the synthetic model {list(SYNTHETIC_MODALITIES)} "
                              "(EMG is not simulated: use a recorded human or a model file)",
                   list(names))
    return Scenario(
        path=path, name=str(data.get("name", path.stem)), family=family,
        seed=seed, human_kind=kind, human=human,
        policy=_policy(check, data["policy"]), model=model_spec,
        object=obj, speed=check.bounded(data.get("speed", 1.0), "speed", "speed"),
        time_limit=check.bounded(data.get("time_limit", 6.0), "time_limit", "time_limit"),
        observe=names, robot=arm)


def _fill_in(check: _Checker, data: dict, model, options, model_options) -> dict:
    """``data`` with the command line's model file and settings (the file's own win)."""
    for key in ("policy", "model"):
        if data.get(key) is not None and not isinstance(data[key], Mapping):
            check.fail(key, "a mapping", data[key])
    if model is not None:
        data["model"] = {**(data.get("model") or {}), "file": str(Path(model).resolve())}
    if options and isinstance(data.get("policy"), Mapping):
        own = data["policy"].get("options") or {}
        if isinstance(own, Mapping):
            data["policy"] = {**data["policy"], "options": {**options, **own}}
    if model_options:
        section = dict(data.get("model") or {})
        own = section.get("options") or {}
        if isinstance(own, Mapping):
            data["model"] = {**section, "options": {**model_options, **own}}
    return data


def _observe(check: _Checker, data: Any) -> tuple[str, ...]:
    names = [n.strip() for n in data.split(",")] if isinstance(data, str) else data
    if (not isinstance(names, list) or not names
            or not all(isinstance(n, str) and n for n in names)):
        check.fail("observe", "a list of modality names", data)
    unknown = [n for n in names if n not in ENV_MODALITIES]
    if unknown or len(set(names)) != len(names):
        check.fail("observe", f"distinct modalities the environments observe "
                              f"{list(ENV_MODALITIES)}", names)
    return tuple(names)


def _human(check: _Checker, data: Any, family: str, folder: Path,
           seed: int) -> tuple[str, dict]:
    if not isinstance(data, Mapping):
        check.fail("human", "a mapping (task..., waypoints: or recorded:)", data)
    kind = "waypoints" if "waypoints" in data else "recorded" if "recorded" in data else "synthetic"
    human = check.keys(data, f"human ({kind})", HUMAN_KEYS[kind])
    if kind == "synthetic":
        from sandbox.envs.sources import family_tasks

        tasks = family_tasks(family)
        for key in ("task", "switch_to"):
            if human.get(key) is not None:
                check.choice(human[key], f"human.{key}", tasks)
        if "switch_phase" in human:
            human["switch_phase"] = check.bounded(human["switch_phase"], "human.switch_phase",
                                                  "switch_phase")
        if human.get("switch_to") is not None and human.get("task") == human["switch_to"]:
            check.fail("human.switch_to", "a task other than human.task", human["switch_to"])
    elif kind == "waypoints":
        human["times"], human["points"] = _waypoints(check, human.pop("waypoints"))
        human["task"] = check.text(human.get("task", "scripted"), "human.task")
        human["tracker"] = _tracker(check, human.get("tracker"))
    else:
        root = folder / check.text(human["recorded"], "human.recorded")
        if not _exists(root, "is_dir"):
            check.fail("human.recorded", "the folder of a recorded set (<root>/<task>/<trial>.csv)",
                       str(human["recorded"]))
        human["recorded"] = str(root)
        trial = human.get("trial")
        if trial is not None and not isinstance(trial, (int, str)) or isinstance(trial, bool):
            check.fail("human.trial", "an index or a file name", trial)
        human.update(_pick_recorded(check, root, human.get("task"), trial, seed))
        if human.get("spec") is not None:
            human["spec"] = _spec(check, folder / check.text(human["spec"], "human.spec"))
    return kind, human


def _spec(check: _Checker, path: Path):
    """A recorded human's spec file, checked: Baxter's 7 joints, or a position (task space)."""
    from sandbox.data.spec import DataSpec

    try:
        spec = DataSpec.load(path)
        if spec.robot_space == "task" and len(spec.robot) != 3:
            raise ValueError(f"expected a task-space robot part of 3 columns (x, y, z), got "
                             f"{list(spec.robot)}")
        if spec.robot_space == "joint" and len(spec.robot) != 7:
            raise ValueError(f"expected Baxter's 7 arm joints as robot, got {list(spec.robot)}")
    except ValueError as error:
        raise ValueError(f"scenario {check.path}: human.spec: {error}") from None
    return spec


def _pick_recorded(check: _Checker, root: Path, task, trial, seed: int) -> dict:
    """The recorded trial the scenario replays: ``task``, ``trial`` (file name), ``file``."""
    import numpy as np

    from sandbox.envs.sources import pick_trial, recorded_trials

    trials = recorded_trials(root, task)
    if not trials:
        check.fail("human.task", f"a task with trials in {root}", task)
    try:
        task, file = pick_trial(trials, trial, np.random.default_rng(seed))
    except ValueError as error:
        raise ValueError(f"scenario {check.path}: human.{error}") from error
    return {"task": task, "trial": file.name, "file": str(file)}


def _waypoints(check: _Checker, data: Any) -> tuple[list[float], list[list[float]]]:
    if not isinstance(data, list) or len(data) < 2:
        check.fail("human.waypoints", "a list of at least 2 waypoints {t, position}", data)
    times: list[float] = []
    points: list[list[float]] = []
    for i, item in enumerate(data):
        key = f"human.waypoints[{i}]"
        item = check.keys(item, key, ("t", "position"))
        if "t" not in item or "position" not in item:
            check.fail(key, "both t (s) and position [x, y, z] (m)", item)
        t = check.bounded(item["t"], f"{key}.t", "waypoint_t")
        if times and t <= times[-1]:
            check.fail(f"{key}.t", f"a time after the previous waypoint's {times[-1]:g} s", t)
        p = item["position"]
        if (not isinstance(p, list) or len(p) != 3
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p)):
            check.fail(f"{key}.position", "3 numbers [x, y, z] (m)", p)
        for v, axis in zip(p, "xyz"):
            check.bounded(v, f"{key}.position.{axis}", "position")
        times.append(t)
        points.append([float(v) for v in p])
    return times, points


def _tracker(check: _Checker, data: Any):
    from dataclasses import fields

    from sandbox.data.synthetic.tracker import TrackerModel

    if data is None:
        return TrackerModel(glitch_rate=0.0)
    allowed = [f.name for f in fields(TrackerModel)]
    data = check.keys(data, "human.tracker", allowed)
    try:
        return TrackerModel(**{"glitch_rate": 0.0, **data})
    except (TypeError, ValueError) as error:
        raise ValueError(f"scenario {check.path}: human.tracker: {error}") from error


def _policy(check: _Checker, data: Any) -> dict:
    if not isinstance(data, Mapping):
        check.fail("policy", "a mapping with type: dynamic or static", data)
    kind = check.choice(data.get("type", "dynamic"), "policy.type", POLICY_KEYS)
    policy = check.keys(data, f"policy ({kind})", POLICY_KEYS[kind])
    policy["type"] = kind
    if kind == "dynamic":
        policy["dow_t"] = check.bounded(policy.get("dow_t", 0.2), "policy.dow_t", "dow_t")
    else:
        policy["ratio"] = check.bounded(policy.get("ratio", 0.3), "policy.ratio", "ratio")
    options = policy.get("options", {})
    if not isinstance(options, Mapping):
        check.fail("policy.options", "a mapping of predictor options", options)
    policy["options"] = checked_options(check, options, "policy.options", policy_options(kind))
    return policy


def _model(check: _Checker, data: Any, folder: Path) -> dict:
    model = check.keys({} if data is None else data, "model", MODEL_KEYS)
    if "file" in model:
        file = folder / check.text(model["file"], "model.file")
        if not _exists(file, "is_file"):
            check.fail("model.file", "an existing model file (.npz)", str(model["file"]))
        model["file"] = str(file)
    model["demos"] = check.bounded(model.get("demos", 20), "model.demos", "demos")
    model["seed"] = check.bounded(model.get("seed", 0), "model.seed", "seed")
    options = model.get("options", {})
    if not isinstance(options, Mapping):
        check.fail("model.options", "a mapping of IProMP options", options)
    from sandbox.core import IProMP

    model["options"] = checked_options(check, options, "model.options",
                                       sorted(keywords(IProMP.__init__)))
    try:
        IProMP(**model["options"])
    except ValueError as error:
        raise ValueError(f"scenario {check.path}: model.options: {error}") from None
    return model

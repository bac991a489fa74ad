"""Demonstrations as Minari datasets, the offline-RL format of the Farama ecosystem.

The only module that imports :mod:`minari` (an optional extra: ``pip install -e
".[minari]"``, Python >= 3.11). :func:`export_demonstrations` writes
:class:`~sandbox.data.demonstration.Demonstration` s with
``minari.create_dataset_from_buffers``; :func:`load_demonstrations` reads them
back exactly (``fit --data minari:ID`` fits the same model as the source).

One demonstration of T samples is one episode of T - 1 steps:

* ``observations`` (T rows, a ``Dict`` with the environment's key names): one
  entry per observed modality (``hand`` (3,) m, ``arm`` (6,) m, ``emg`` (8,)
  raw, ...) with its ``<name>_valid`` flag (int8 (1,); the values are 0 where
  the sample is missing, as in the environment), ``q`` (Q,) the robot's
  recorded joints (rad) and ``time`` (1,) s since the demonstration started;
* ``actions`` (T - 1 rows): the robot's recorded joints at the next sample
  (its joint targets, rad) and a gripper command, -1 (open: the recordings
  have no gripper);
* ``rewards`` 0 (a demonstration has no reward), ``terminations`` true at the
  last step (the handover), ``truncations`` false;
* ``infos`` (T rows): ``task`` (the task name), ``time`` ((T, 1), the recorded
  sample times, s) and ``source`` (the trial file or generator).

The dataset's metadata holds under ``"sandbox"`` the modalities, the robot's
joint names and the preprocessing the demonstrations had. Its environment spec
is a registered id of :mod:`sandbox.envs`, so
``minari.load_dataset(id).recover_environment()`` makes a working environment.
Datasets are written under Minari's datasets folder (``MINARI_DATASETS_PATH``,
default ``~/.minari/datasets``).

Played episodes (``play --record-minari ID``) are recorded as they are by a
``minari.DataCollector`` (:func:`collect`, :func:`save_collected`): the
environment's whole observation, the policy's actions, rewards and ends.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from gymnasium import spaces

from sandbox.core.modality import Modality
from sandbox.data.demonstration import Demonstration

#: ``data`` prefix naming a Minari dataset (``fit --data minari:ID``).
MINARI_PREFIX = "minari:"
#: What to install where Minari is missing.
INSTALL_HINT = 'pip install -e ".[minari]"'
#: Version of the layout above (stored in the metadata).
LAYOUT_VERSION = 1
#: Minari storage backend (the ``arrow`` extra).
DATA_FORMAT = "arrow"
#: Gripper command of every exported action (open).
GRIPPER_OPEN = -1.0


def require_minari():
    """The :mod:`minari` module; an ``ImportError`` saying what to install if it is missing."""
    try:
        import minari
    except ImportError as error:
        raise ImportError(f"Minari datasets need the optional extra: {INSTALL_HINT} "
                          f"(Minari 0.5, Python >= 3.11); {error}") from None
    return minari


def default_env_id(data: str) -> str:
    """The environment a dataset points at: the diverging one for ``synthetic:diverging``,
    the object handover for anything else (the recorded set hands over objects)."""
    import sandbox.envs

    return sandbox.envs.ENV_IDS[1 if str(data) == "synthetic:diverging" else 0]


# ------------------------------------------------------------------ spaces
def observation_space(modalities: Sequence[Modality], n_robot: int, env_space: spaces.Dict
                      ) -> spaces.Dict:
    """The episodes' observation space: the environment's entry where a key has the
    same shape there (``hand``, ``arm``, ``emg``, ``q``, ``time``), unbounded otherwise."""
    entries: dict[str, spaces.Space] = {}
    for m in modalities:
        entries[m.name] = _entry(env_space, m.name, (m.size,))
        entries[f"{m.name}_valid"] = spaces.MultiBinary(1)
    entries["q"] = _entry(env_space, "q", (n_robot,))
    entries["time"] = _entry(env_space, "time", (1,))
    return spaces.Dict(entries)


def action_space(n_robot: int, env_space: spaces.Box) -> spaces.Box:
    """Joint targets and a gripper command: the environment's if it has Q + 1 dims."""
    if env_space.shape == (n_robot + 1,):
        return env_space
    return spaces.Box(-np.inf, np.inf, (n_robot + 1,), np.float64)


def _entry(env_space: spaces.Dict, key: str, shape: tuple[int, ...]) -> spaces.Space:
    if key in env_space.spaces and env_space[key].shape == shape:
        return env_space[key]
    return spaces.Box(-np.inf, np.inf, shape, np.float64)


# ------------------------------------------------------------------ episodes
def episode_buffer(demo: Demonstration, episode_id: int):
    """One demonstration as a ``minari.data_collector.EpisodeBuffer`` (see the module docstring)."""
    require_minari()
    from minari.data_collector import EpisodeBuffer

    if demo.n_steps < 2:
        raise ValueError(f"demo: expected at least 2 samples to make a step, got {demo.n_steps}")
    n = demo.n_steps
    observations: dict[str, np.ndarray] = {}
    start = 0
    for m in demo.modalities:
        values = demo.human[:, start:start + m.size]
        start += m.size
        observations[m.name], observations[f"{m.name}_valid"] = _with_flags(values, m.name)
    observations["q"] = np.array(demo.robot)
    observations["time"] = (demo.times - demo.times[0])[:, None]
    gripper = np.full((n - 1, 1), GRIPPER_OPEN)
    return EpisodeBuffer(
        id=episode_id, observations=observations,
        actions=np.hstack([demo.robot[1:], gripper]),
        rewards=np.zeros(n - 1), terminations=np.r_[np.zeros(n - 2, bool), True],
        truncations=np.zeros(n - 1, bool),
        # (T, 1), not (T,): Minari 0.5's arrow storage cannot read back a 1-D info array
        infos={"task": [demo.task] * n, "time": np.array(demo.times)[:, None],
               "source": [demo.source] * n})


def _with_flags(values: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Values with 0 where missing, and the int8 (T, 1) flag of the rows that are there."""
    finite = np.isfinite(values)
    valid = finite.all(axis=1)
    partial = finite.any(axis=1) & ~valid
    if partial.any():
        row = int(np.flatnonzero(partial)[0])
        raise ValueError(f"demo: {name} has only some of its dims at row {row}; expected a "
                         f"modality measured whole or not at all")
    return np.where(finite, values, 0.0), valid[:, None].astype(np.int8)


def demonstration_from_episode(episode, layout: dict[str, Any], dataset_id: str
                               ) -> Demonstration:
    """The :class:`Demonstration` an episode holds (exactly as it was exported)."""
    modalities = tuple(Modality.from_dict(m) for m in layout["modalities"])
    obs = episode.observations
    human = np.hstack([np.where(obs[f"{m.name}_valid"].astype(bool), obs[m.name], np.nan)
                       for m in modalities])
    infos = episode.infos
    return Demonstration(
        times=np.asarray(infos["time"], dtype=np.float64)[:, 0], human=human,
        robot=np.asarray(obs["q"], dtype=np.float64), task=str(infos["task"][0]),
        modalities=modalities, robot_names=tuple(layout["robot_names"]),
        source=str(infos["source"][0]),
        meta={"minari": {"dataset_id": dataset_id, "episode_id": int(episode.id)},
              "preprocess": layout["preprocess"]})


# ------------------------------------------------------------------ datasets
def export_demonstrations(demos: Sequence[Demonstration], dataset_id: str, *,
                          env_id: str, preprocess: str, data: str = "",
                          force: bool = False, description: str | None = None):
    """Write ``demos`` as the Minari dataset ``dataset_id`` (e.g. ``"sandbox/objects-v0"``).

    Parameters
    ----------
    demos : sequence of Demonstration
        At least one; all with the same modalities and robot dims.
    dataset_id : str
        Minari id, ``namespace/name-vN``.
    env_id : str
        Registered environment id the dataset's spec points at.
    preprocess : str
        What preprocessing the demos had (stored; ``fit`` checks it).
    data : str
        Where they came from (stored in the metadata).
    force : bool
        Replace an existing dataset of that id (otherwise a ``ValueError``).
    description : str, optional
        Dataset description (default: one naming ``data``).

    Returns
    -------
    minari.MinariDataset
    """
    import gymnasium as gym

    import sandbox
    import sandbox.envs  # noqa: F401  (registers the ids)

    minari = require_minari()
    demos = _check_demos(demos)
    if dataset_id in minari.list_local_datasets():
        if not force:
            raise ValueError(f"--minari-id: a dataset {dataset_id!r} exists already; pass "
                             "--force to replace it")
        minari.delete_dataset(dataset_id)
    first = demos[0]
    env = gym.make(env_id)
    try:
        obs_space = observation_space(first.modalities, first.robot.shape[1],
                                      env.observation_space)
        act_space = action_space(first.robot.shape[1], env.action_space)
        with warnings.catch_warnings():  # author, e-mail, permalink, eval env "set to None"
            warnings.filterwarnings("ignore", message=".*is set to None", category=UserWarning)
            dataset = minari.create_dataset_from_buffers(
                dataset_id, [episode_buffer(d, i) for i, d in enumerate(demos)], env=env,
                observation_space=obs_space, action_space=act_space,
                algorithm_name="demonstrations", data_format=DATA_FORMAT,
                description=description or f"handover demonstrations from {data or 'memory'}",
                requirements=[f"handover-sandbox>={sandbox.__version__}"])
    finally:
        env.close()
    layout = {"layout_version": LAYOUT_VERSION, "data": str(data), "preprocess": preprocess,
              "modalities": [m.to_dict() for m in first.modalities],
              "robot_names": list(first.robot_names)}
    dataset.storage.update_metadata({"sandbox": layout})
    return dataset


def _check_demos(demos: Sequence[Demonstration]) -> list[Demonstration]:
    demos = list(demos)
    if not demos or not all(isinstance(d, Demonstration) for d in demos):
        raise ValueError("demos: expected a non-empty list of Demonstration")
    first = demos[0]
    for d in demos[1:]:
        if d.modalities != first.modalities or d.robot_names != first.robot_names:
            raise ValueError(f"demos: expected the same modalities and robot dims in all, got "
                             f"{d!r} beside {first!r}")
    return demos


def load_demonstrations(dataset_id: str) -> tuple[list[Demonstration], dict[str, Any]]:
    """The demonstrations of a dataset written by :func:`export_demonstrations`, and its
    ``"sandbox"`` metadata (modalities, robot names, preprocessing, origin)."""
    minari = require_minari()
    if dataset_id not in minari.list_local_datasets():
        raise ValueError(f"data: expected a local Minari dataset id (minari:ID), got "
                         f"{dataset_id!r}; local ones: {sorted(minari.list_local_datasets())}")
    dataset = minari.load_dataset(dataset_id)
    layout = dataset.storage.metadata.get("sandbox")
    if not isinstance(layout, dict) or layout.get("layout_version") != LAYOUT_VERSION:
        raise ValueError(f"data: the Minari dataset {dataset_id!r} was not written by "
                         "`python -m sandbox data export` (no 'sandbox' metadata of layout "
                         f"version {LAYOUT_VERSION})")
    demos = [demonstration_from_episode(e, layout, dataset_id)
             for e in dataset.iterate_episodes()]
    return demos, layout


def load_for_fit(dataset_id: str, observe: Sequence[str], *, tasks: Sequence[str] | None,
                 n_per_task: int | None, preprocess: str) -> list[Demonstration]:
    """The ``minari:ID`` branch of :func:`sandbox.data.datasets.load_dataset`.

    ``observe``: the modalities to keep; ``tasks``: a subset (an unknown one is
    a ``ValueError`` listing those there are); ``n_per_task``: the first N of
    each task; ``preprocess`` must be the one the dataset was exported with
    (its demonstrations are stored preprocessed).
    """
    from sandbox.data.demonstration import stack_tasks

    demos, layout = load_demonstrations(dataset_id)
    if preprocess != layout["preprocess"]:
        raise ValueError(f"preprocess: the dataset minari:{dataset_id} holds demonstrations "
                         f"preprocessed {layout['preprocess']!r} at export, got {preprocess!r}; "
                         f"pass --preprocess {layout['preprocess']} or export it again")
    groups = stack_tasks(demos)
    if tasks is not None:
        unknown = [t for t in tasks if t not in groups]
        if unknown:
            raise ValueError(f"tasks: expected some of {list(groups)}, got unknown {unknown}")
        groups = {t: g for t, g in groups.items() if t in set(tasks)}
    n = None if n_per_task is None else int(n_per_task)
    return [d.select(list(observe)) for group in groups.values() for d in group[:n]]


# ------------------------------------------------------------------ played episodes
def check_new_dataset_id(dataset_id: str) -> str:
    """``dataset_id`` if no local dataset has it (checked before a session is played)."""
    minari = require_minari()
    if not isinstance(dataset_id, str) or dataset_id.count("/") > 2 or not dataset_id.strip():
        raise ValueError(f"--record-minari: expected a Minari id like sandbox/played-v0, "
                         f"got {dataset_id!r}")
    if dataset_id in minari.list_local_datasets():
        raise ValueError(f"--record-minari: a dataset {dataset_id!r} exists already; choose "
                         f"another id or delete it (minari delete {dataset_id})")
    return dataset_id


def collect(env):
    """``env`` wrapped in a ``minari.DataCollector`` recording every step (arrow storage).

    Reset options that are not JSON (a scripted ``motion``) are stored as their
    type, task and source, e.g. ``"HumanMotion(task='scripted', source='waypoints[3]')"``.
    """
    require_minari()
    from minari import DataCollector

    class _Collector(DataCollector):
        steps_recorded = 0

        def step(self, action):
            self.steps_recorded += 1
            return super().step(action)

        def reset(self, *, seed=None, options=None):
            out = super().reset(seed=seed, options=options)
            if options:
                self._buffer = replace(self._buffer, options=_json_options(options))
            return out

    return _Collector(env, data_format=DATA_FORMAT)


def _json_options(options) -> dict[str, Any]:
    import json

    out = {}
    for key, value in dict(options).items():
        try:
            json.dumps(value)
            out[key] = value
        except TypeError:
            named = [f"{k}={getattr(value, k)!r}" for k in ("task", "source") if hasattr(value, k)]
            out[key] = f"{type(value).__name__}({', '.join(named)})"
    return out


def save_collected(collector, dataset_id: str, *, algorithm_name: str, description: str):
    """Write what ``collector`` (:func:`collect`) recorded as the dataset ``dataset_id``.

    An episode still running is stored truncated. Returns the
    ``minari.MinariDataset``, or None if no step was played.
    """
    if collector.steps_recorded == 0:
        return None
    import sandbox

    with warnings.catch_warnings():  # author, e-mail, permalink "set to None"
        warnings.filterwarnings("ignore", message=".*is set to None", category=UserWarning)
        return collector.create_dataset(
            dataset_id, algorithm_name=algorithm_name, description=description,
            requirements=[f"handover-sandbox>={sandbox.__version__}"])

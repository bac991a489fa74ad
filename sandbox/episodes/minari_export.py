"""Writing Minari datasets: demonstrations exported, played episodes collected.

The writing half of the Minari layout of :mod:`sandbox.data.minari_io` (see
it for the layout; it reads the datasets back): a dataset's environment spec
is a registered id of :mod:`sandbox.envs`, so writing one belongs to the
episodes layer. :func:`export_demonstrations` writes
:class:`~sandbox.data.demonstration.Demonstration` s with
``minari.create_dataset_from_buffers`` (``python -m sandbox data export``);
:func:`collect` and :func:`save_collected` record played episodes
(``play --record-minari ID``) with a ``minari.DataCollector``.
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
from sandbox.data.minari_io import DATA_FORMAT, LAYOUT_VERSION, require_minari

#: Gripper command of every exported action (open).
GRIPPER_OPEN = -1.0


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
               "source": [demo.source] * n, **_jitter_infos(demo, n)})


def _jitter_infos(demo: Demonstration, n: int) -> dict[str, np.ndarray]:
    """``jitter_<name>`` (n, 1) m: each position modality's raw jitter the loader measured
    (``demo.jitter``), which sets its noise floor and no preprocessed sample keeps."""
    return {f"jitter_{name}": np.full((n, 1), value) for name, value in demo.jitter.items()}


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
    env: Any = gym.make(env_id)
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
        _buffer: Any

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

"""Demonstrations as Minari datasets, the offline-RL format of the Farama ecosystem.

The reading half: :func:`load_demonstrations` reads the
:class:`~sandbox.data.demonstration.Demonstration` s a dataset holds back
exactly (``fit --data minari:ID`` fits the same model as the source). The
writing half, which names a registered environment, is in the episodes layer:
:mod:`sandbox.episodes.minari_export` (``export_demonstrations``, and the
played episodes of ``play --record-minari``). The two are the only modules
that import :mod:`minari` (an optional extra: ``pip install -e ".[minari]"``,
Python >= 3.11).

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
  sample times, s), ``source`` (the trial file or generator) and, for each position
  modality whose raw tracker jitter was measured, ``jitter_<name>`` ((T, 1), m; it
  sets the modality's noise floor, :mod:`sandbox.data.noisefloor`).

The dataset's metadata holds under ``"sandbox"`` the modalities, the robot's
joint names and the preprocessing the demonstrations had. Its environment spec
is a registered id of :mod:`sandbox.envs`, so
``minari.load_dataset(id).recover_environment()`` makes a working environment.
Datasets are written under Minari's datasets folder (``MINARI_DATASETS_PATH``,
default ``~/.minari/datasets``).

Played episodes (``play --record-minari ID``) are recorded as they are by a
``minari.DataCollector`` (:func:`sandbox.episodes.minari_export.collect`): the
environment's whole observation, the policy's actions, rewards and ends.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

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


def require_minari():
    """The :mod:`minari` module; an ``ImportError`` saying what to install if it is missing."""
    try:
        import minari
    except ImportError as error:
        raise ImportError(f"Minari datasets need the optional extra: {INSTALL_HINT} "
                          f"(Minari 0.5, Python >= 3.11); {error}") from None
    return minari


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
              "preprocess": layout["preprocess"], **_jitter_report(infos, modalities)})


def _jitter_report(infos, modalities) -> dict[str, Any]:
    """The raw jitter an episode's infos keep (``jitter_<name>``), as a loader's report."""
    found = {m.name: {"jitter_m": float(np.asarray(infos[f"jitter_{m.name}"])[0, 0])}
             for m in modalities if f"jitter_{m.name}" in infos}
    return {"report": {"modalities": found}} if found else {}


def load_demonstrations(dataset_id: str) -> tuple[list[Demonstration], dict[str, Any]]:
    """The demonstrations of a dataset written by
    :func:`~sandbox.episodes.minari_export.export_demonstrations`, and its ``"sandbox"``
    metadata (modalities, robot names, preprocessing, origin)."""
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

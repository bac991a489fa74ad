"""Where an episode's hand motion comes from: the synthetic generator or a recorded trial.

* :func:`synthetic_motion`: one seeded reach of a task of a synthetic family
  (``"objects"``: box, glasses case, tape; ``"diverging"``: left, right, up,
  down, straight), optionally with an intent switch to another task. The body
  follows the clean reach, the robot observes it through the tracker model.
* :func:`recorded_motion`: replay of a trial ``<root>/<task>/<trial>.csv`` in
  the recorded layout. The robot observes the causally filtered track
  (:func:`sandbox.data.load_trial` with ``preprocess="causal"``: only accepted
  tracker frames, NaN elsewhere); the body follows the smoothed track
  (``"smooth"``), its gaps interpolated.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from sandbox.data.synthetic.families import DIVERGING_VARIABILITY, OBJECTS, diverging_specs
from sandbox.data.synthetic.generator import generate
from sandbox.data.synthetic.intent import intent_switch_demo
from sandbox.data.synthetic.tasks import TaskSpec, Variability
from sandbox.envs.human import HumanMotion

#: Synthetic families and their tasks.
FAMILIES = ("objects", "diverging")


def family_specs(family: str) -> tuple[tuple[TaskSpec, ...], Variability]:
    """Task specs and variability of a synthetic ``family`` (one of :data:`FAMILIES`)."""
    if family == "objects":
        return OBJECTS, Variability()
    if family == "diverging":
        return diverging_specs(), DIVERGING_VARIABILITY
    raise ValueError(f"family: expected one of {list(FAMILIES)}, got {family!r}")


def family_tasks(family: str) -> tuple[str, ...]:
    """Task names of a synthetic ``family``."""
    return tuple(spec.name for spec in family_specs(family)[0])


def synthetic_motion(family: str, task: str, rng: np.random.Generator, *,
                     switch_to: str | None = None, switch_phase: float = 0.5) -> HumanMotion:
    """One synthetic hand motion of ``task``.

    Parameters
    ----------
    family : str
        One of :data:`FAMILIES`.
    task : str
        One of the family's tasks (:func:`family_tasks`).
    rng : numpy.random.Generator
        Source of randomness (the environment's ``np_random``).
    switch_to : str, optional
        Another task of the family the human switches to at ``switch_phase``
        of the motion (an intent switch); the episode's task is then this one.
    switch_phase : float
        Fraction of the motion's duration at which the intent switches.

    Returns
    -------
    HumanMotion
        ``meta["handover_target"]`` is where the demonstrated gripper met the hand.
    """
    specs, variability = family_specs(family)
    by_name = {spec.name: spec for spec in specs}
    for name in (task, switch_to) if switch_to is not None else (task,):
        if name not in by_name:
            raise ValueError(f"task: expected one of {list(by_name)} ({family}), got {name!r}")
    if switch_to is None:
        (demo,) = generate([by_name[task]], 1, rng, family=family, variability=variability)
        meta = {}
    else:
        demo, truth = intent_switch_demo(task, switch_to, switch_phase, rng, family=family)
        meta = {"intent": truth}
    return HumanMotion(
        times=demo.times - demo.times[0], true=demo.meta["clean_human"], measured=demo.human,
        task=demo.task, source=demo.source,
        meta={**meta, "handover_target": np.array(demo.meta["handover_target"])},
    )


def recorded_trials(root: str | Path, task: str | None = None) -> list[tuple[str, Path]]:
    """``(task, file)`` of every trial under ``root`` (of ``task`` only if given)."""
    from sandbox.data.recorded import find_trials

    return find_trials(root, None if task is None else [task])


def pick_trial(trials: list[tuple[str, Path]], trial: int | str | None,
               rng: np.random.Generator) -> tuple[str, Path]:
    """Choose one of ``trials``: by index, by file name (with or without ``.csv``), or at random."""
    if trial is None:
        return trials[int(rng.integers(len(trials)))]
    if isinstance(trial, (int, np.integer)) and not isinstance(trial, bool):
        if not 0 <= int(trial) < len(trials):
            raise ValueError(f"trial: expected an index in [0, {len(trials) - 1}], got {trial}")
        return trials[int(trial)]
    if isinstance(trial, str):
        for task, path in trials:
            if trial in (path.name, path.stem):
                return task, path
        names = ", ".join(p.stem for _, p in trials[:5])
        raise ValueError(f"trial: expected a file name among the trials ({names}, ...), "
                         f"got {trial!r}")
    raise ValueError(f"trial: expected an index, a file name or None, got {trial!r}")


def recorded_motion(root: str | Path, task: str | None, trial: int | str | None,
                    rng: np.random.Generator) -> HumanMotion:
    """Replay of one recorded trial (random task and trial where not given)."""
    trials = recorded_trials(root, task)
    return _load_motion(*map(str, pick_trial(trials, trial, rng)))


@functools.lru_cache(maxsize=64)
def _load_motion(task: str, path: str) -> HumanMotion:
    from sandbox.data.recorded import load_trial

    causal = load_trial(path, task=task, preprocess="causal")
    smooth = load_trial(path, task=task, preprocess="smooth")
    times = causal.times - causal.times[0]
    true = np.column_stack([_fill(times, smooth.human[:, j]) for j in range(3)])
    return HumanMotion(times=times, true=true, measured=causal.human, task=task, source=path,
                       meta={"report": causal.meta["report"]})


def _fill(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    ok = np.isfinite(y)
    if not ok.any():
        raise ValueError("recorded trial: the smoothed hand track has no valid sample")
    return np.interp(t, t[ok], y[ok])

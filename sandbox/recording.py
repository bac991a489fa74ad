"""One environment episode with a predictor policy, recorded: beliefs, updates, outcome, replay.

:func:`record_episode` runs an episode of a handover environment with an
:class:`~sandbox.policies.IProMPPolicy` (or :class:`~sandbox.policies.StaticPolicy`),
optionally drawing it in a :class:`sandbox.viz.Viewer` (bodies and prediction
overlays), and returns an :class:`EpisodeRecord`: what the robot believed after
each update, the outcome, and a JSON-ready :meth:`EpisodeRecord.summary`. The
``demo`` and ``play --scenario`` commands are built on it.

This module imports neither meshcat nor PyBullet: the viewer and the
environment are passed in.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Belief:
    """What the predictor believed at one time.

    Attributes
    ----------
    time : float
        Episode time (s).
    task : str
        Most probable task.
    posterior : dict of str to float
        p(task | observations so far).
    duration : float
        Estimated duration of the human motion (s), ``nan`` before the first update.
    jump : float
        Change of the robot command (rad) the update caused (0 for a non-update).
    """

    time: float
    task: str
    posterior: dict[str, float]
    duration: float
    jump: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (``nan`` becomes ``None``)."""
        return {"time": round(self.time, 4), "task": self.task,
                "posterior": {k: round(float(v), 4) for k, v in self.posterior.items()},
                "duration": _finite(self.duration), "jump": _finite(self.jump)}


@dataclass
class EpisodeRecord:
    """An episode's outcome and the predictor's beliefs over time.

    Attributes
    ----------
    task, object, source : str
        The human's task (for an intent switch: the one switched to), object, motion source.
    success : bool
        Whether the handover happened.
    handover_time : float or None
        When (s).
    final_distance : float
        Gripper fingertip to the object's grasp point in the human hand (m) at the end.
    min_distance : float
        Smallest such distance (m).
    end_time : float
        Episode time (s) at the end.
    steps : int
    recognised : list of (float, str)
        The recognised task after each step: (time s, task).
    updates : list of Belief
        One per predictor update.
    truth : list of (float, str)
        The task the human pursued at each step (intent switch); empty when not known.
    policy : str
        Name of the policy.
    """

    task: str
    object: str
    source: str
    success: bool = False
    handover_time: float | None = None
    final_distance: float = float("nan")
    min_distance: float = float("nan")
    end_time: float = 0.0
    steps: int = 0
    recognised: list[tuple[float, str]] = field(default_factory=list)
    updates: list[Belief] = field(default_factory=list)
    truth: list[tuple[float, str]] = field(default_factory=list)
    policy: str = ""

    def recognised_at(self, t: float) -> str:
        """The task recognised at time ``t`` (s): the last one at or before it ('' before)."""
        out = ""
        for time, task in self.recognised:
            if time > t + 1e-9:
                break
            out = task
        return out

    def summary(self) -> dict[str, Any]:
        """JSON-ready outcome: success, handover time, final distance, beliefs, updates."""
        changes = [(t, k) for i, (t, k) in enumerate(self.recognised)
                   if i == 0 or k != self.recognised[i - 1][1]]
        return {
            "policy": self.policy,
            "task": self.task,
            "object": self.object,
            "source": self.source,
            "success": bool(self.success),
            "handover_time_s": self.handover_time,
            "final_distance_m": _finite(self.final_distance),
            "min_distance_m": _finite(self.min_distance),
            "end_time_s": round(self.end_time, 4),
            "steps": self.steps,
            "final_task": self.recognised[-1][1] if self.recognised else "",
            "recognised": [{"time": round(t, 4), "task": k} for t, k in changes],
            "updates": [b.as_dict() for b in self.updates],
            "n_updates": len(self.updates),
        }


def _finite(value: float | None) -> float | None:
    if value is None or not math.isfinite(float(value)):
        return None
    return round(float(value), 6)


def _truth(motion) -> Any:
    """The motion's intent-switch ground truth, if any (``task_at(t)``)."""
    meta = getattr(motion, "meta", {}) or {}
    return meta.get("intent")


def record_episode(env, policy, *, seed: int | None = None,
                   options: Mapping[str, Any] | None = None, viewer=None,
                   overlay=None, policy_name: str = "", max_steps: int | None = None,
                   on_update=None) -> EpisodeRecord:
    """Run one episode of ``policy`` in ``env`` and record it.

    Parameters
    ----------
    env : gymnasium.Env
        A handover environment (``sandbox/...``), reset here.
    policy : IProMPPolicy or StaticPolicy
        Has ``predictor`` (its ``updates`` are read), ``task`` and ``reset()``.
    seed : int, optional
        ``reset`` seed.
    options : mapping, optional
        ``reset`` options.
    viewer : sandbox.viz.Viewer, optional
        Records the bodies (it must mirror ``env.unwrapped.sim``) at its frame rate.
    overlay : PredictionOverlay, optional
        Draws the predictor's state with the viewer's frames.
    policy_name : str
        Stored in the record.
    max_steps : int, optional
        Stop after this many steps (default: until the episode ends).
    on_update : callable, optional
        Called with each new :class:`Belief` as it happens (e.g. to print it).

    Returns
    -------
    EpisodeRecord
    """
    obs, info = env.reset(seed=seed, options=dict(options or {}))
    policy.reset()
    truth = _truth(env.unwrapped.motion)
    intent = getattr(env.unwrapped, "human_intent", lambda t: None)  # for the viewer's panel
    record = EpisodeRecord(task=info["task"], object=info["object"], source=info["source"],
                           policy=policy_name)
    if viewer is not None:
        viewer.restart_recording()
        viewer.update(0.0, force=True)
    distances, done = [], False
    while not done and (max_steps is None or record.steps < max_steps):
        obs, _, terminated, truncated, step = env.step(policy(obs))
        done, record.steps = terminated or truncated, record.steps + 1
        t = float(obs["time"][0])
        record.recognised.append((t, policy.task))
        if truth is not None:
            record.truth.append((t, str(truth.task_at(t))))
        distances.append(step["distance"])
        for update in policy.predictor.updates[len(record.updates):]:
            belief = _belief(update, policy.predictor.model.tasks)
            record.updates.append(belief)
            if on_update is not None:
                on_update(belief)
        if viewer is not None and viewer.begin(t):
            for body in viewer.bodies.values():
                body.update()
            if overlay is not None:
                overlay.show(policy.predictor, t, executed_q=obs["q"], truth=intent(t))
        record.success, record.handover_time = bool(step["is_success"]), step["handover_time"]
        record.final_distance, record.end_time = float(step["distance"]), t
    record.min_distance = float(np.min(distances)) if distances else float("nan")
    return record


def _belief(update, tasks) -> Belief:
    posterior = {task: float(p) for task, p in zip(tasks, update.task_posterior)}
    return Belief(time=float(update.time), task=update.task, posterior=posterior,
                  duration=float(update.duration), jump=float(update.jump))

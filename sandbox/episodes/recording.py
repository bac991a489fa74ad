"""One environment episode with a predictor policy, recorded: beliefs, updates, outcome, replay.

:func:`record_episode` runs an episode (:func:`~sandbox.episodes.rollout.rollout`)
of a handover environment with an :class:`~sandbox.episodes.policies.IProMPPolicy`
(or :class:`~sandbox.episodes.policies.StaticPolicy`),
optionally drawing it in a :class:`sandbox.viz.Viewer` (bodies and prediction
overlays), and returns an :class:`EpisodeRecord`: what the robot believed after
each update, the outcome, and a JSON-ready :meth:`EpisodeRecord.summary`. The
``demo`` and ``play --scenario`` commands are built on it.

This module imports neither meshcat nor PyBullet: the viewer and the
environment are passed in.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.episodes.policy import Policy, beliefs_of, recognitions
from sandbox.episodes.rollout import Step, rollout


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
    familiarity : float or None
        How familiar the motion was (:attr:`sandbox.core.Update.familiarity`);
        None without a calibrated model.
    moving : float
        Probability that the hand had started moving
        (:attr:`sandbox.core.Update.motion_probability`).
    familiar : bool or None
        False when ``familiarity`` is below the model's calibrated threshold:
        the viewer's "unsure / unknown motion" warning was on; None without a
        calibration.
    """

    time: float
    task: str
    posterior: dict[str, float]
    duration: float
    jump: float = 0.0
    familiarity: float | None = None
    moving: float = 1.0
    familiar: bool | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready form (``nan`` becomes ``None``)."""
        return {"time": round(self.time, 4), "task": self.task,
                "posterior": {k: round(float(v), 4) for k, v in self.posterior.items()},
                "duration": _finite(self.duration), "jump": _finite(self.jump),
                "familiarity": _finite(self.familiarity), "moving": round(self.moving, 4),
                "familiar": self.familiar}


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
        (time s, task): a predictor's task after each of its updates, at the
        update's time; nothing before its first update
        (:func:`~sandbox.episodes.policy.recognitions`). A policy without a
        predictor: its task after each step.
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
            **warnings(self.updates),
        }


def warnings(updates: list[Belief]) -> dict[str, Any]:
    """The familiarity warning over an episode: ``unfamiliar_updates`` (count) and
    ``first_warning_s`` (time of the first unfamiliar update, None if none); both None
    when no update had a calibrated familiarity."""
    judged = [b for b in updates if b.familiar is not None]
    if not judged:
        return {"unfamiliar_updates": None, "first_warning_s": None}
    low = [b.time for b in judged if not b.familiar]
    return {"unfamiliar_updates": len(low), "first_warning_s": round(low[0], 4) if low else None}


def _finite(value: float | None) -> float | None:
    if value is None or not math.isfinite(float(value)):
        return None
    return round(float(value), 6)


def _truth(motion) -> Any:
    """The motion's intent-switch ground truth, if any (``task_at(t)``)."""
    meta = getattr(motion, "meta", {}) or {}
    return meta.get("intent")


def record_episode(env: Any, policy: Policy, *, seed: int | None = None,
                   options: Mapping[str, Any] | None = None, viewer: Any = None,
                   overlay: Any = None, policy_name: str = "", max_steps: int | None = None,
                   on_update: Callable[[Belief], None] | None = None) -> EpisodeRecord:
    """Run one episode of ``policy`` in ``env`` and record it.

    Parameters
    ----------
    env : gymnasium.Env
        A handover environment (``sandbox/...``), reset here.
    policy : Policy
        E.g. an :class:`~sandbox.episodes.policies.IProMPPolicy`; its ``beliefs``
        (task, updates) are read after every step.
    seed : int, optional
        ``reset`` seed.
    options : mapping, optional
        ``reset`` options.
    viewer : sandbox.viz.Viewer, optional
        Records the bodies (it must mirror ``env.unwrapped.sim``) at its frame rate.
    overlay : PredictionOverlay, optional
        Draws the policy's beliefs with the viewer's frames.
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
    recorder = _Recorder(env, policy, viewer, overlay, policy_name, on_update)
    rollout(env, policy, seed=seed, options=options, on_reset=recorder.start,
            on_step=recorder.step, max_steps=max_steps)
    return recorder.finish()


class _Recorder:
    """What :func:`record_episode` does at the reset and after each step."""

    def __init__(self, env, policy, viewer, overlay, policy_name: str, on_update) -> None:
        self.env, self.policy, self.viewer, self.overlay = env, policy, viewer, overlay
        self.policy_name, self.on_update = policy_name, on_update
        self.distances: list[float] = []

    def start(self, step: Step) -> None:
        info = step.reset_info
        self.truth = _truth(self.env.unwrapped.motion)
        self.intent = getattr(self.env.unwrapped, "human_intent", lambda t: None)  # the panel
        self.record = EpisodeRecord(task=info["task"], object=info["object"],
                                    source=info["source"], policy=self.policy_name)
        if self.viewer is not None:
            self.viewer.restart_recording()
            self.viewer.update(0.0, force=True)
        arm = getattr(getattr(self.env.unwrapped, "robot", None), "name", "baxter")
        if self.overlay is not None and arm != "baxter":   # its fingertip, not Baxter's FK
            from sandbox.robot.retarget import Retargeter

            self.overlay.executed_tip = Retargeter(arm).tip

    def step(self, step: Step) -> None:
        record, beliefs, t = self.record, beliefs_of(self.policy), step.time
        record.steps = step.n
        seen = float(step.previous["time"][0]) if step.previous is not None else t
        record.recognised += recognitions(beliefs, len(record.updates), seen)
        if self.truth is not None:
            record.truth.append((t, str(self.truth.task_at(t))))
        self.distances.append(step.info["distance"])
        for update in beliefs.updates[len(record.updates):]:
            belief = _belief(update, beliefs.tasks, beliefs.familiarity_threshold)
            record.updates.append(belief)
            if self.on_update is not None:
                self.on_update(belief)
        if self.viewer is not None and self.viewer.begin(t):
            for body in self.viewer.bodies.values():
                body.update()
            if self.overlay is not None:
                self.overlay.show(beliefs, t, executed_q=step.obs["q"], truth=self.intent(t),
                                  truth_since=getattr(self.truth, "switch_time", None))
        record.success = bool(step.info["is_success"])
        record.handover_time = step.info["handover_time"]
        record.final_distance, record.end_time = float(step.info["distance"]), t

    def finish(self) -> EpisodeRecord:
        distances = self.distances
        self.record.min_distance = float(np.min(distances)) if distances else float("nan")
        return self.record


def _belief(update, tasks, threshold: float | None = None) -> Belief:
    posterior = {task: float(p) for task, p in zip(tasks, update.task_posterior)}
    familiarity = getattr(update, "familiarity", None)
    familiar = (None if familiarity is None or threshold is None
                or not math.isfinite(float(familiarity)) else bool(familiarity >= threshold))
    return Belief(time=float(update.time), task=update.task, posterior=posterior,
                  duration=float(update.duration), jump=float(update.jump),
                  familiarity=familiarity, familiar=familiar,
                  moving=float(getattr(update, "motion_probability", 1.0)))

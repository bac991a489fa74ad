"""The one episode loop: reset, then observe -> act -> step until the episode ends.

Every runner of the episodes layer is built on :func:`rollout`: the scripted
scenarios (:func:`sandbox.episodes.scenarios.run_episode`), the recorded
episodes of ``demo`` and ``play --scenario``
(:func:`sandbox.episodes.recording.record_episode`) and the keyboard teleop
(:func:`sandbox.episodes.keyboard.run_teleop`, which also records
demonstrations). What each one does with a step is its ``on_step``; when it
stops early is its ``until`` or ``max_steps``.

Examples
--------
>>> import gymnasium as gym, sandbox.envs
>>> from sandbox.episodes.policies import IProMPPolicy, fit_family_model
>>> env = gym.make("sandbox/BaxterHandoverDiverging-v1")
>>> policy = IProMPPolicy(fit_family_model("diverging"))
>>> last = rollout(env, policy, seed=3, max_steps=10)
>>> last.n, last.done, round(float(last.obs["time"][0]), 2)
(10, False, 0.2)
>>> env.close()
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sandbox.episodes.policy import Policy


@dataclass(frozen=True)
class Step:
    """The state of an episode after a step (or after the reset, ``n == 0``).

    Attributes
    ----------
    n : int
        Steps taken so far in this episode.
    obs : dict
        The latest observation (after the step; the reset's for ``n == 0``).
    info : dict
        The step's ``info`` (the reset's for ``n == 0``).
    previous : dict or None
        The observation the policy acted on in this step (None for ``n == 0``).
    action : ndarray, shape (8,), or None
        The action taken (None for ``n == 0``).
    reward : float
    terminated, truncated : bool
    reset_info : dict
        The ``info`` of the episode's reset.
    """

    n: int
    obs: dict
    info: dict
    previous: dict | None = None
    action: np.ndarray | None = None
    reward: float = 0.0
    terminated: bool = False
    truncated: bool = False
    reset_info: dict = field(default_factory=dict)

    @property
    def done(self) -> bool:
        """Whether the environment ended the episode (terminated or truncated)."""
        return bool(self.terminated or self.truncated)

    @property
    def time(self) -> float:
        """Episode time of :attr:`obs` (s)."""
        return float(self.obs["time"][0])


def rollout(env: Any, policy: Policy, *, seed: int | None = None,
            options: Mapping[str, Any] | None = None,
            on_reset: Callable[[Step], None] | None = None,
            on_step: Callable[[Step], None] | None = None,
            until: Callable[[Step], bool] | None = None,
            max_steps: int | None = None) -> Step:
    """Run one episode of ``policy`` in ``env``; return its last :class:`Step`.

    Parameters
    ----------
    env : gymnasium.Env
        A handover environment; reset here with ``seed`` and ``options``.
    policy : Policy
        Reset after the environment; called with each observation.
    seed : int, optional
        ``reset`` seed.
    options : mapping, optional
        ``reset`` options (copied).
    on_reset : callable, optional
        Called with the reset's step (``n == 0``) before the first step.
    on_step : callable, optional
        Called with every :class:`Step` after it is taken.
    until : callable, optional
        Called with the latest step before each next one; True ends the
        episode there (e.g. the keyboard's quit or new-episode key).
    max_steps : int, optional
        Steps at most (default: until the environment ends the episode).

    Returns
    -------
    Step
        The last one (the reset's if no step was taken).
    """
    obs, info = env.reset(seed=seed, options=dict(options or {}))
    policy.reset()
    step = Step(n=0, obs=obs, info=info, reset_info=info)
    if on_reset is not None:
        on_reset(step)
    while not step.done and (max_steps is None or step.n < max_steps):
        if until is not None and until(step):
            break
        action = policy(step.obs)
        obs, reward, terminated, truncated, info = env.step(action)
        step = Step(n=step.n + 1, obs=obs, info=info, previous=step.obs, action=action,
                    reward=float(reward), terminated=bool(terminated),
                    truncated=bool(truncated), reset_info=step.reset_info)
        if on_step is not None:
            on_step(step)
    return step

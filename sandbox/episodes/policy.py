"""What a policy is to the episode runners: :class:`Policy`, and what it believes, :class:`Beliefs`.

A policy maps each observation of :mod:`sandbox.envs` to an action (8,),
forgets its episode on :meth:`Policy.reset` and shows what it believes through
the read-only :attr:`Policy.beliefs`. The runners of :mod:`sandbox.episodes`
(:func:`~sandbox.episodes.rollout.rollout` and its callers), the viewer's
overlays and panel and the teleop status line read :class:`Beliefs`, never the
policy's predictor.

A :class:`Beliefs` is a snapshot taken when ``policy.beliefs`` is read: its
fields do not change afterwards. Its :meth:`~Beliefs.plan`,
:meth:`~Beliefs.command` and :meth:`~Beliefs.observations` ask the policy's
predictor now (read-only), so read them before the next step. It has the
attributes and queries the viewer's :meth:`~sandbox.viz.overlays.PredictionOverlay.show`
reads (``task``, ``task_posterior``, ``alpha``, ``familiar``, ``updates``,
``plan()``, ``command(t)``, ``observations()``), so it is drawn as it is.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def _no_predictor(*args: Any) -> Any:
    raise RuntimeError("beliefs: this policy has no predictor (no plan, command or "
                       "observations to show)")


@dataclass(frozen=True)
class Beliefs:
    """What a policy believes after its latest observation.

    Attributes
    ----------
    task : str
        The task recognised now (``""`` if the policy recognises none, e.g. a
        predictor before its first update: the prior's favourite is no recognition).
    tasks : tuple of str
        Every task the policy knows, in the model's order.
    task_posterior : mapping of str to float
        p(task | observations so far), over :attr:`tasks`.
    duration : float
        Predicted duration of the human motion (s); before the first update the
        prior mean (``nan`` for a policy without a predictor).
    alpha : float
        Speed factor of the recognised task (its prior mean before the first
        update; 1 for a policy without a predictor).
    familiar : bool or None
        False when the motion is unlike the training demonstrations; None when
        the policy cannot tell.
    familiarity_threshold : float or None
        The model's calibrated threshold: an update whose
        :attr:`~sandbox.core.Update.familiarity` is below it is unfamiliar (None
        without a calibration).
    updates : tuple of Update
        The predictor's updates so far (:class:`sandbox.core.predictor.Update`,
        frozen), oldest first; empty for a policy without a predictor.
    """

    task: str
    tasks: tuple[str, ...] = ()
    task_posterior: Mapping[str, float] = field(default_factory=dict)
    duration: float = math.nan
    alpha: float = 1.0
    familiar: bool | None = None
    familiarity_threshold: float | None = None
    updates: tuple[Any, ...] = ()
    _plan: Callable[[], tuple[FloatArray, FloatArray, FloatArray]] = field(
        default=_no_predictor, repr=False, compare=False)
    _command: Callable[[float], tuple[FloatArray, FloatArray]] = field(
        default=_no_predictor, repr=False, compare=False)
    _observations: Callable[[], tuple[FloatArray, FloatArray]] = field(
        default=_no_predictor, repr=False, compare=False)

    @property
    def n_updates(self) -> int:
        """Number of predictor updates so far."""
        return len(self.updates)

    def plan(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The current plan: knot times (n,) s, joint means (n, Q) rad, covariances (n, Q, Q)."""
        return self._plan()

    def command(self, t: float) -> tuple[FloatArray, FloatArray]:
        """The planned command at time ``t`` (s): mean (Q,) rad and covariance (Q, Q)."""
        return self._command(t)

    def observations(self) -> tuple[FloatArray, FloatArray]:
        """Observations kept so far: times (s,) s and values (s, P) (the model's layout)."""
        return self._observations()

    @classmethod
    def of_predictor(cls, predictor: Any) -> Beliefs:
        """The beliefs of a :class:`~sandbox.core.DynamicPredictor` or
        :class:`~sandbox.core.StaticPredictor` now."""
        return cls(task=predictor.task if predictor.updates else "",
                   tasks=tuple(predictor.model.tasks),
                   task_posterior=dict(predictor.task_posterior),
                   duration=float(predictor.duration), alpha=float(predictor.alpha),
                   familiar=predictor.familiar, updates=tuple(predictor.updates),
                   familiarity_threshold=_threshold(predictor.model),
                   _plan=predictor.plan, _command=predictor.command,
                   _observations=predictor.observations)


def _threshold(model: Any) -> float | None:
    """The familiarity threshold of ``model``'s calibration (None without one)."""
    calibration = getattr(model, "calibration", None)
    return None if calibration is None else float(calibration.threshold)


def recognitions(beliefs: Beliefs, n_known: int, time: float) -> list[tuple[float, str]]:
    """The (time s, task) recognitions a step adds, on the updates' clock.

    A predictor's: one per update after the first ``n_known``, stamped with the
    update's own time (the observation it was made at); nothing before its
    first update. A policy without a predictor: its task at ``time`` (the
    observation the policy acted on).
    """
    if beliefs.updates:
        return [(float(u.time), str(u.task)) for u in beliefs.updates[n_known:]]
    return [(float(time), beliefs.task)] if beliefs.task else []


@runtime_checkable
class Policy(Protocol):
    """A controller of the handover environments.

    ``policy(obs)`` returns the action (8,) for an observation: seven joint
    targets (rad) and a gripper command (> 0 closes); ``policy.reset()`` forgets
    the episode; ``policy.beliefs`` is what it believes now (read-only).
    """

    def reset(self) -> None:
        """Forget the episode."""

    def __call__(self, obs: Mapping[str, FloatArray]) -> FloatArray:
        """The action (8,) for observation ``obs``."""

    @property
    def beliefs(self) -> Beliefs:
        """What the policy believes after its latest observation."""


def beliefs_of(policy: Any) -> Beliefs:
    """``policy.beliefs``; for a policy without them, a :class:`Beliefs` of its ``task``
    attribute (``""`` if it has none), so a bare callable with ``reset()`` still runs."""
    beliefs = getattr(policy, "beliefs", None)
    if isinstance(beliefs, Beliefs):
        return beliefs
    return Beliefs(task=str(getattr(policy, "task", "")))


def check_joint_model(model) -> None:
    """Refuse (``ValueError``, one line) a model whose robot part no arm can follow: the
    policies drive an arm from Baxter's 7 joints (retargeted to other arms) or from a
    task-space position (3 dims, m), through the arm's inverse kinematics."""
    if getattr(model, "robot_space", "joint") == "task":
        if getattr(model, "n_robot", 3) != 3:
            raise ValueError(f"the model's robot part is in task space with {model.n_robot} "
                             f"dims; a policy follows a position x, y, z (3 dims, m)")
        return
    if getattr(model, "n_robot", 7) != 7:          # an unfitted model: its own error later
        raise ValueError(f"the model drives {model.n_robot} robot dims, the environments' "
                         f"Baxter arm has 7 joints")

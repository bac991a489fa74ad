"""The robot's plan: a piecewise-linear command over time, blended at every update.

A predictor (:mod:`sandbox.core.predictor`) executes a :class:`Plan`: knot times
(s), the mean joint targets (rad) and their covariance at each knot, linearly
interpolated between knots and held beyond the first and last knot. Before
the first update the plan is the moment-matched mixture of the task priors
(:meth:`Plan.prior`, each task at its mean duration, weighted by p(k)). An
update blends a new robot distribution in from its time on (:meth:`Plan.blended`,
eq. 16-18): the current plan with a falling sigmoid, the new one with a rising
sigmoid centred ``delay`` after the update. The plan before an update's time is
never rewritten, so what was executed stays executed; the change of the command
at the first knot after the update is the update's *jump*.

Sizes are bounded: a plan holds at most :data:`~sandbox.core.limits.MAX_PLAN_STEPS`
knots (:func:`check_steps`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.blending import blend_pair, sigmoid_activations
from sandbox.core.limits import MAX_PLAN_STEPS
from sandbox.core.promp import trajectory_distribution
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

#: A robot distribution over time: ``times`` (T,) in s -> means (T, Q), covariances (T, Q, Q).
Trajectory = Callable[[FloatArray], tuple[FloatArray, FloatArray]]


def check_steps(steps: float, what: str, dt: float) -> None:
    """Refuse a span that would take more than MAX_PLAN_STEPS knots of ``dt`` s (``ValueError``)."""
    if not steps <= MAX_PLAN_STEPS:
        raise ValueError(f"plan: {what} would take {steps:.3g} knots of dt={dt:g} s, "
                         f"more than limits.MAX_PLAN_STEPS={MAX_PLAN_STEPS}; raise dt or "
                         f"shorten that span")


@dataclass(frozen=True)
class Blending:
    """How an update enters the plan (validated by the predictor).

    Attributes
    ----------
    dt : float
        Knot spacing (s).
    rate : float
        Gradient l of the activation sigmoids (1/s, eq. 18).
    delay : float
        Delay (s) from an update to the centre of its sigmoids.
    blend : bool
        Blend the new distribution in (False: replace the plan from the update on).
    horizon : float
        The plan reaches at least this far (s) past each update.
    """

    dt: float
    rate: float
    delay: float
    blend: bool = True
    horizon: float = 0.0


@dataclass(frozen=True, eq=False)
class Plan:
    """Knot times (n,) in s, means (n, Q) in rad and covariances (n, Q, Q); never mutated.

    Internal: built by :meth:`prior` and :meth:`blended`, unchecked.
    """

    times: FloatArray
    mean: FloatArray
    cov: FloatArray

    @classmethod
    def prior(cls, model: IProMP, dt: float) -> Plan:
        """Moment-matched mixture of the task priors, each at its mean duration, on knots of ``dt``.

        Parameters
        ----------
        model : IProMP
            A fitted model (its robot dims, basis, task priors p(k)).
        dt : float
            Knot spacing (s); the plan runs to the longest mean duration.
        """
        tasks, P, p = model.task_models, model.n_human, model.priors
        end = max(t.mean_duration for t in tasks)
        check_steps(end / dt + 1, f"the prior plan to {end:g} s", dt)
        knots = np.arange(0.0, end + dt, dt)
        parts = []
        for task in tasks:
            robot = task.weights.dims(slice(P, None))
            z = np.clip(knots / task.mean_duration, 0.0, 1.0)
            parts.append(trajectory_distribution(robot, model.basis, z))      # eq. 4
        means = np.array([m for m, _ in parts])
        covs = np.array([c for _, c in parts])
        mean = np.tensordot(p, means, axes=1)
        dev = means - mean
        cov = np.tensordot(p, covs + dev[..., :, None] * dev[..., None, :], axes=1)
        return cls(knots, mean, cov)

    def interpolate(self, times: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Means (T, Q) and covariances (T, Q, Q) at ``times`` (T,) in s; held beyond the ends."""
        pt = self.times
        i = np.clip(np.searchsorted(pt, times, side="right"), 1, pt.size - 1)
        span = pt[i] - pt[i - 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(span > 0, np.clip((times - pt[i - 1]) / span, 0.0, 1.0), 1.0)
        mean = (1 - w)[:, None] * self.mean[i - 1] + w[:, None] * self.mean[i]
        cov = ((1 - w)[:, None, None] * self.cov[i - 1]
               + w[:, None, None] * self.cov[i])
        return mean, cov

    def at(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Mean (Q,) and covariance (Q, Q) at one time ``t`` (s): :meth:`interpolate`."""
        mean, cov = self.interpolate(np.array([float(t)]))
        return mean[0], cov[0]

    def blended(self, t: float, new: Trajectory, duration: float,
                how: Blending) -> tuple[Plan, float]:
        """The plan with a new robot distribution blended in from ``t`` (s) on (eq. 16-18).

        Parameters
        ----------
        t : float
            Update time (s); knots before it are kept as they are.
        new : callable
            The new distribution at given times (e.g. :meth:`Prediction.trajectory
            <sandbox.core.inference.Prediction.trajectory>` with the model's basis).
        duration : float
            Its predicted end (s): the plan reaches at least this far.
        how : Blending

        Returns
        -------
        plan : Plan
        jump : float
            Euclidean change (rad) of the command at the first knot after ``t``.
        """
        keep = self.times < t                          # knot t is added below: no duplicate
        # At least until the blend has completed (the rising sigmoid within e^-10 of 1):
        # an update after the predicted end must still take over the plan.
        settled = t + how.delay + 10.0 / how.rate
        end = max(duration, self.times[-1], t + how.horizon, settled)
        first = (np.floor(t / how.dt + 1e-9) + 1.0) * how.dt
        check_steps(np.count_nonzero(keep) + (end - first) / how.dt + 2,
                    f"an update at {t:g} s, planning to {end:g} s,", how.dt)
        new_t = np.arange(first, end + how.dt, how.dt)
        new_t = new_t[new_t > t + 1e-9]
        fall, rise, n = _activations(new_t, t + how.delay, how.rate)
        # the old plan matters only where it is blended (the jump reads its first knot)
        n_old = n if how.blend else 0
        old_mean, old_cov = self.interpolate(np.concatenate([[t], new_t[:max(n_old, 1)]]))
        mean, cov = new(new_t)
        if how.blend:
            mean, cov = _blend((old_mean[1:], old_cov[1:]), (mean, cov), fall, rise, n)
        jump = float(np.linalg.norm(mean[0] - old_mean[1])) if new_t.size else 0.0
        plan = Plan(np.concatenate([self.times[keep], [t], new_t]),
                    np.concatenate([self.mean[keep], old_mean[:1], mean]),
                    np.concatenate([self.cov[keep], old_cov[:1], cov]))
        return plan, jump


def _activations(times: FloatArray, center: float, rate: float):
    """Falling and rising sigmoids at ``times`` (eq. 18) and the number of leading knots
    blended: past the falling sigmoid's numerically irrelevant tail (< 1e-12; it only
    falls) the product is the new distribution."""
    fall, rise = sigmoid_activations(times, center, rate)                  # eq. 18
    n = int(np.searchsorted(-fall, -1e-12))
    rise[rise < 1e-12] = 0.0
    return fall, rise, n


def _blend(old: tuple[FloatArray, FloatArray], new: tuple[FloatArray, FloatArray],
           fall: FloatArray, rise: FloatArray, n: int) -> tuple[FloatArray, FloatArray]:
    """Product of the old (falling) and new (rising) distributions at the knots (eq. 16-18);
    ``old`` is needed at the first ``n`` knots only (:func:`_activations`)."""
    mean, cov = new
    head = blend_pair(old[0][:n], old[1][:n], fall[:n], mean[:n], cov[:n], rise[:n])  # eq. 16-17
    return (np.concatenate([head[0], mean[n:]]),
            np.concatenate([head[1], cov[n:] / rise[n:, None, None]]))

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

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.blending import blend_pair_into, sigmoid_activations
from sandbox.core.blendkernel import blend_knots, knots_kernel
from sandbox.core.limits import MAX_PLAN_STEPS
from sandbox.core.promp import WeightDistribution, held_trajectory, trajectory_distribution
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
class Held:
    """A robot weight distribution played over ``duration`` s and held after its end: what
    an update blends into the plan (:meth:`Plan.blended` computes it knot by knot in one
    compiled call when numba is installed, :mod:`sandbox.core.blendkernel`).

    Attributes
    ----------
    robot : WeightDistribution
        Over the Q robot dims.
    duration : float
        Its duration (s).
    basis : GaussianBasis
    """

    robot: WeightDistribution
    duration: float
    basis: GaussianBasis

    def __call__(self, times: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Means (T, Q) and covariances (T, Q, Q) at ``times`` (s): :func:`held_trajectory`."""
        return held_trajectory(self.robot, self.duration, self.basis, times)


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
        knots_kernel()          # loaded (or compiled) now, with numba, not in an update
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
        i = int(np.searchsorted(self.times, t))   # knots before t are kept; t is added
        new_t = _new_knots(t, max(duration, float(self.times[-1])), i, how)
        kernel = knots_kernel() if isinstance(new, Held) else None
        if kernel is not None:                   # one compiled call (blendkernel)
            times = np.concatenate((self.times[:i], [t], new_t))
            out_mean = np.empty((times.size,) + self.mean.shape[1:])
            out_cov = np.empty((times.size,) + self.cov.shape[1:])
            out_mean[:i], out_cov[:i] = self.mean[:i], self.cov[:i]
            jump = blend_knots(kernel, (self.times, self.mean, self.cov), t, new_t, new, how,
                               (out_mean[i:], out_cov[i:]))
            return Plan(times, out_mean, out_cov), jump
        fall, rise, n = _activations(new_t, t + how.delay, how.rate)
        # the old plan matters only where it is blended (the jump reads its first knot)
        old_mean, old_cov = self.interpolate(np.concatenate(
            ([t], new_t[:max(n if how.blend else 0, 1)])))
        mean, cov = new(new_t)
        times = np.concatenate((self.times[:i], [t], new_t))
        out_mean = np.empty((times.size,) + self.mean.shape[1:])
        out_cov = np.empty((times.size,) + self.cov.shape[1:])
        out_mean[:i], out_cov[:i] = self.mean[:i], self.cov[:i]
        out_mean[i], out_cov[i] = old_mean[0], old_cov[0]
        if how.blend:
            _blend((old_mean[1:], old_cov[1:]), (mean, cov), fall, rise, n,
                        (out_mean[i + 1:], out_cov[i + 1:]))
        else:
            out_mean[i + 1:], out_cov[i + 1:] = mean, cov
        d = out_mean[i + 1] - old_mean[1] if new_t.size else None
        jump = math.sqrt(d.dot(d)) if d is not None else 0.0        # its Euclidean norm
        return Plan(times, out_mean, out_cov), jump


def _new_knots(t: float, end: float, kept: int, how: Blending) -> FloatArray:
    """The knots of ``dt`` after ``t`` (s) an update at ``t`` plans, to ``end`` (s) at least,
    its horizon and the blend's completion (the rising sigmoid within e^-10 of 1: an update
    after the predicted end must still take over the plan); ``kept`` knots come before."""
    end = max(end, t + how.horizon, t + how.delay + 10.0 / how.rate)
    first = (math.floor(t / how.dt + 1e-9) + 1.0) * how.dt
    check_steps(kept + (end - first) / how.dt + 2,
                f"an update at {t:g} s, planning to {end:g} s,", how.dt)
    new_t = np.arange(first, end + how.dt, how.dt)
    if new_t.size and new_t[0] <= t + 1e-9:       # (increasing) no knot within 1e-9 of t
        new_t = new_t[int(np.searchsorted(new_t, t + 1e-9, side="right")):]
    return new_t


def _activations(times: FloatArray, center: float, rate: float):
    """Falling and rising sigmoids at ``times`` (increasing; eq. 18) and the number of
    leading knots blended: past the falling sigmoid's numerically irrelevant tail (< 1e-12;
    it only falls) the product is the new distribution."""
    fall, rise = sigmoid_activations(times, center, rate)                  # eq. 18
    n = int(np.count_nonzero(fall > 1e-12))        # fall only falls: its leading knots
    if rise.size and rise[0] < 1e-12:              # (rises: only leading knots can be)
        rise[rise < 1e-12] = 0.0
    return fall, rise, n


def _blend(old: tuple[FloatArray, FloatArray], new: tuple[FloatArray, FloatArray],
                fall: FloatArray, rise: FloatArray, n: int,
                out: tuple[FloatArray, FloatArray]) -> None:
    """Product of the old (falling) and new (rising) distributions at the knots (eq. 16-18)
    into ``out`` (means (T, Q), covariances (T, Q, Q)); ``old`` is needed at the first ``n``
    knots only (:func:`_activations`), after which the new one is divided by its activation."""
    mean, cov = new
    blend_pair_into(old[0][:n], old[1][:n], fall[:n], mean[:n], cov[:n], rise[:n],
                    out[0][:n], out[1][:n])                                 # eq. 16-17
    out[0][n:] = mean[n:]
    np.divide(cov[n:], rise[n:, None, None], out=out[1][n:])

"""One prediction from observations: speed, task and the conditioned robot motion.

:func:`predict` is one update of the method (paper sec. 2): the MAP speed of
every task (:mod:`sandbox.core.phase`), the task posterior
(:mod:`sandbox.core.recognition`), and the robot weights of the most probable
task conditioned on the observations (eq. 8, :func:`~sandbox.core.factor.condition_robot`).
The online predictors (:mod:`sandbox.core.predictor`) call it at every window;
the evaluation calls it for static predictions and the oracle.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.factor import condition_robot
from sandbox.core.likelihood import Scorer
from sandbox.core.phase import ended_probability, estimate_phase
from sandbox.core.promp import WeightDistribution, held_trajectory
from sandbox.core.recognition import posterior_unchecked
from sandbox.core.rest import chosen_task, motion_probability, rest_log_likelihood, with_rest
from sandbox.core.statistics import StreamStatistics
from sandbox.validation import FloatArray

__all__ = ["Prediction", "conditioned_robot", "held_trajectory", "predict"]

if TYPE_CHECKING:
    from sandbox.core.model import IProMP


@dataclass(frozen=True, eq=False)
class Prediction:
    """One prediction from observations: speeds, task posterior and the robot's distribution.

    Attributes
    ----------
    task_index : int
        The chosen (most probable, or given) task.
    task_posterior, alphas, durations, log_likelihood : ndarray, shape (K,)
    robot : WeightDistribution
        Conditioned robot weights of the chosen task (eq. 8).
    duration : float
        Its duration :math:`T^*` (s).
    factors : ndarray or None, shape (K, R+1, R+1)
        Every task's augmented Cholesky factor at its MAP duration (joint
        likelihood only): what :meth:`for_task` conditions another task with.
    grid : list or None
        Each task's posterior over its grid of durations
        (:attr:`~sandbox.core.phase.PhaseEstimate.grid`).
    n_values : int or None
        Observed values (finite entries of the observations) it was made from
        (what :func:`~sandbox.core.familiarity.statistic` divides by).
    motion_probability : float
        Probability that the hand had started moving, against the rest
        hypothesis (:mod:`sandbox.core.rest`); 1 when it was not weighed.
    observations : tuple of ndarray or None
        The observations ``(times, values)`` it was made from when the robot is
        conditioned by a scorer of its own (``shrinkage="robot"``'s weights or a
        ``condition_floor``'s noise, :mod:`sandbox.core.condfloor`): what
        :meth:`for_task` conditions another task's robot with; None otherwise.
    """

    task_index: int
    task_posterior: FloatArray
    alphas: FloatArray
    durations: FloatArray
    log_likelihood: FloatArray
    robot: WeightDistribution
    duration: float
    factors: FloatArray | None = None
    grid: list | None = None
    n_values: int | None = None
    motion_probability: float = 1.0
    observations: tuple[FloatArray, FloatArray] | None = None

    def trajectory(self, basis, times) -> tuple[FloatArray, FloatArray]:
        """Robot mean (T, Q) and covariance (T, Q, Q) at ``times`` (s); holds after the end."""
        return held_trajectory(self.robot, self.duration, basis, times)

    def for_task(self, model: IProMP, k: int, posterior: FloatArray | None = None, *,
                 scorer: Scorer | None = None) -> Prediction:
        """The same estimate with task ``k`` chosen: its robot at its MAP duration.

        ``posterior`` replaces the task posterior (e.g. one held since the motion
        ended). Needs :attr:`factors` (joint likelihood) and the ``Scorer(model)`` that
        made them (built if not given).
        """
        if self.factors is None:
            raise ValueError("for_task: this prediction kept no factors (marginal likelihood)")
        scorer = Scorer(model) if scorer is None else scorer
        factor = self.factors[k]
        if self.observations is not None:          # the robot's own scorer (conditioner)
            scorer = scorer.conditioner
            factor = scorer.joint_pairs(*self.observations, self.durations[k:k + 1],
                                        np.array([k]))[1][0]
        robot = condition_robot(scorer.weights[k], factor, model.n_human, scorer.rank[k])
        return replace(self, task_index=int(k), robot=robot, duration=float(self.durations[k]),
                       task_posterior=self.task_posterior if posterior is None else posterior)

    def ended_probability(self, t: float, task: int | None = None) -> float:
        """Probability that a task's motion (default the chosen one's) had ended by ``t`` (s)."""
        k = self.task_index if task is None else int(task)
        if self.grid is None:
            return float(self.durations[k] <= t)
        return float(ended_probability(self.grid[k:k + 1], t)[0])


def predict(model: IProMP, scorer: Scorer, times: FloatArray, values: FloatArray, *,
            likelihood: str = "joint", n_candidates: int = 50, width: float = 3.0,
            refine_steps: int = 1, stats: StreamStatistics | None = None,
            task: int | None = None, duration: float | None = None,
            rest: bool = True) -> Prediction:
    """Estimate speeds and task from observations and condition the robot (one update).

    Parameters
    ----------
    model : IProMP
    scorer : Scorer
        ``Scorer(model)``.
    times : ndarray, shape (s,)
        Observation times since the motion started (s), s >= 1.
    values : ndarray, shape (s, P)
        Observed human dims (normalised units), NaN where a modality is not observed.
    likelihood, n_candidates, width, refine_steps
        As for :class:`DynamicPredictor`.
    stats : StreamStatistics, optional
        Statistics of exactly these observations (faster).
    task, duration : optional
        Condition this task at this duration instead of the estimated ones (an
        oracle); the posterior and speed estimates are still reported.
    rest : bool
        Weigh the hypothesis that the hand has not started (:mod:`sandbox.core.rest`)
        into the task posterior. Only for observations from the start of the
        stream (a later window of a held hand is the end of a motion, not a rest).
    """
    est = estimate_phase(scorer, model.task_models, times, values, n_candidates=n_candidates,
                         width=width, refine_steps=refine_steps, mode=likelihood, stats=stats)
    post = posterior_unchecked(est.log_likelihood, model.priors)     # eq. 14-15
    p_motion = 1.0
    if rest:
        still = rest_log_likelihood(values, scorer.sigma2, scorer.start_mean, scorer.start_var,
                                    joint=likelihood == "joint")
        p_motion = motion_probability(est.log_likelihood, model.priors, still)
        post, chosen = with_rest(post, model.priors, p_motion), post
    else:
        chosen = post
    k = chosen_task(post, chosen) if task is None else int(task)
    T = float(est.durations[k]) if duration is None else float(duration)
    cond = scorer.conditioner     # shrinkage="robot" or condition_floor: another scorer
    if cond is scorer and duration is None and est.factors is not None:
        robot = condition_robot(cond.weights[k], est.factors[k], model.n_human, cond.rank[k])
    else:
        robot = conditioned_robot(model, scorer, times, values, k, T)
    observations = None if cond is scorer else (times, values)
    return Prediction(k, post, est.alphas, est.durations, est.log_likelihood, robot, T,
                      est.factors, est.grid, int(np.isfinite(values).sum()), p_motion,
                      observations)


def conditioned_robot(model: IProMP, scorer: Scorer, times: FloatArray, values: FloatArray,
                      k: int, duration: float) -> WeightDistribution:
    """The robot weights of task ``k`` at ``duration`` (s) conditioned on the observations
    (eq. 8), by the robot's own scorer when it has one (``shrinkage="robot"``,
    ``condition_floor``): :func:`predict`'s robot with ``task=k, duration=duration``,
    without its phase estimate (the evaluation's oracle)."""
    cond = scorer.conditioner
    factor = cond.joint_pairs(times, values, np.array([float(duration)]),
                              np.array([int(k)]))[1][0]
    return condition_robot(cond.weights[k], factor, model.n_human, cond.rank[k])

"""What the two predictors share: observations in, updates blended into the plan.

:class:`PredictorBase` keeps the observation stream (:mod:`sandbox.core.stream`)
and its likelihood statistics, makes an update (:func:`~sandbox.core.inference.predict`
on the kept observations, then :meth:`~PredictorBase.apply`: blend the prediction
into the plan, hold the task once the motion has ended, record an :class:`Update`),
answers for the plan (:meth:`~PredictorBase.command`) and the current beliefs
(task posterior, speed, duration, familiarity). When to update and from which
observations is the public predictors' part (:mod:`sandbox.core.predictor`, whose
docstring describes the method).
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.familiarity import chosen, statistic, statistics
from sandbox.core.inference import Prediction, predict
from sandbox.core.likelihood import Scorer
from sandbox.core.limits import MAX_CANDIDATES, MAX_LATTICE_FLOATS, MAX_TIME_S, check_time
from sandbox.core.phase import Lattice
from sandbox.core.plan import Blending, Held, Plan, check_steps
from sandbox.core.statistics import StreamStatistics
from sandbox.core.stream import ObservationStream
from sandbox.limits import BOUNDS
from sandbox.validation import (
    FloatArray,
    check_array,
    check_bool,
    check_choice,
    check_fraction,
    check_integer,
    check_number,
    check_positive,
)

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

LIKELIHOODS = ("joint", "marginal")
#: Most parabolic refinement steps of the speed.
MAX_REFINE_STEPS = int(BOUNDS["refine_steps"].high)


@dataclass(frozen=True, eq=False)
class Update:
    """What one update decided.

    Attributes
    ----------
    time : float
        When it happened (s).
    n_observations : int
        Observations it used.
    task : str
        Most probable task.
    task_posterior : ndarray, shape (K,)
    alphas, durations, log_likelihood : ndarray, shape (K,)
        MAP speed factor, duration (s) and log-likelihood of every task.
    alpha, duration : float
        Those of the chosen task.
    jump : float
        Euclidean change (rad) of the planned command at the first step after the update.
    seconds : float
        Wall time the update took.
    after_end : bool
        Made after the motion had ended (``until_end``): the task and its
        posterior are those held since the end; the speeds and the robot are new.
    familiarity : float or None
        How well the observations fit the best task, against held-out training
        motions (:mod:`sandbox.core.familiarity`), in (0, 1]; None when the
        model carries no calibration, the likelihood is marginal, or the update
        is past the motion's estimated end and the calibration is gated to it.
    motion_probability : float
        Probability that the hand had started moving, against the hypothesis
        that it rests at its start (:mod:`sandbox.core.rest`); the task
        posterior leans back to the prior by the rest.
    """

    time: float
    n_observations: int
    task: str
    task_posterior: FloatArray
    alphas: FloatArray
    durations: FloatArray
    log_likelihood: FloatArray
    alpha: float
    duration: float
    jump: float
    seconds: float
    after_end: bool = False
    familiarity: float | None = None
    motion_probability: float = 1.0


class PredictorBase:
    """What the two predictors share (module docstring); they differ in when they update
    (:meth:`_maybe_update`) and from which observations (:meth:`_window`)."""

    def __init__(self, model: IProMP, *, observe=None, subsample: int = 5,
                 likelihood: str = "joint", n_candidates: int = 50, width: float = 3.0,
                 refine_steps: int = 1,
                 dt: float = 0.01, blend_rate: float = 50.0, blend_delay: float = 0.1,
                 blend: bool = True, horizon: float = 0.0, incremental: bool = True,
                 until_end: bool = True, end_prob: float = 0.5,
                 max_time: float = MAX_TIME_S) -> None:
        if not getattr(model, "is_fitted", False):
            raise RuntimeError("the model is not fitted: fit it (or load it) before predicting")
        self.model = model
        self.n_candidates = check_integer(n_candidates, "n_candidates", 3, MAX_CANDIDATES)
        self.likelihood = check_choice(likelihood, "likelihood", LIKELIHOODS)
        self.width = check_positive(width, "width")
        self.refine_steps = check_integer(refine_steps, "refine_steps", 0, MAX_REFINE_STEPS)
        self.dt = check_positive(dt, "dt")
        self.blend_rate = float(BOUNDS["blend_rate"].check(blend_rate, "blend_rate"))
        self.blend_delay = float(BOUNDS["blend_delay"].check(blend_delay, "blend_delay"))
        self.blend = check_bool(blend, "blend")
        self.horizon = check_positive(horizon, "horizon", allow_zero=True)
        self.until_end = check_bool(until_end, "until_end")
        self.end_prob = check_fraction(end_prob, "end_prob")
        self.max_time = check_positive(max_time, "max_time")
        self._incremental = check_bool(incremental, "incremental") and self.likelihood == "joint"
        self._blending = Blending(self.dt, self.blend_rate, self.blend_delay, self.blend,
                                  self.horizon)
        self.stream = ObservationStream(model, observe, subsample)
        self.scorer = Scorer(model)
        self.subsample = self.stream.subsample
        self._lattice = Lattice.for_tasks(model.task_models, self.n_candidates, self.width)
        self._check_sizes()
        self._prior = Plan.prior(model, self.dt)        # immutable: every reset() starts from it
        self.reset()

    def _check_sizes(self) -> None:
        """The lattice's statistics and the plan's spans within :mod:`sandbox.core.limits`."""
        sc, C = self.scorer, self._lattice.durations.size
        floats = C * (sc.N**2 * len(sc.groups) + sc.K * (sc.R + 1) ** 2)
        if floats > MAX_LATTICE_FLOATS:
            raise ValueError(f"n_candidates: the speed lattice ({C} durations, N={sc.N}, "
                             f"{sc.K} tasks of rank <= {sc.R}) needs {floats:.3g} floats, more "
                             f"than limits.MAX_LATTICE_FLOATS={MAX_LATTICE_FLOATS:g}; lower "
                             f"n_candidates (now {self.n_candidates}) or width "
                             f"(now {self.width:g})")
        spans = {"the longest candidate duration": float(self._lattice.durations.max()),
                 "horizon": self.horizon, "the blend (blend_delay + 10/blend_rate)":
                 self.blend_delay + 10.0 / self.blend_rate}
        for what, span in spans.items():
            check_steps(span / self.dt, f"{what}, {span:g} s,", self.dt)

    # -------------------------------------------------------------- public
    def reset(self) -> None:
        """Forget all observations and updates; the plan is the prior mixture again."""
        self.stream.reset()
        self.ended, self._past_end, self._last_time = False, 0.0, -np.inf   # _past_end: ongoing()
        self.updates: list[Update] = []
        self._prediction: Prediction | None = None
        self._stats = StreamStatistics(self.scorer, self._lattice) if self._incremental else None
        self._plan = self._prior

    def observe(self, t: float, y) -> Update | None:
        """Receive one human observation; update if a window boundary was reached.

        Parameters
        ----------
        t : float
            Time since the motion started (s); non-decreasing across calls and
            not before the last update; ``|t| <= max_time``.
        y : array_like, shape (P_obs,), or mapping of str to array_like
            The observed modalities' dims in order (m for positions, raw units
            for signals), or a mapping from modality names to their values. A
            modality with a NaN, or outside the range the model was fitted on
            with a margin (counted in ``n_rejected``,
            :func:`~sandbox.core.stream.observation_bounds`), is masked in this
            row; a row with no valid modality is skipped (counted in ``n_skipped``).

        Returns
        -------
        Update or None
            The update this observation triggered, if any.
        """
        t = check_time(t, "t", self.max_time)
        previous = max(self._last_time, self._last_update)
        if t < previous:
            raise ValueError(f"t: expected a finite time >= the previous one "
                             f"({previous:g}), got {t!r}")
        row = self.stream.accept(t, y)
        self._last_time = t
        if row is not None and self._stats is not None:
            self._stats.add(t, row)
        return self._maybe_update(t)

    def command(self, t: float) -> tuple[FloatArray, FloatArray]:
        """Planned robot command at time ``t`` (s).

        Returns
        -------
        mean : ndarray, shape (Q,)
            Joint targets (rad).
        cov : ndarray, shape (Q, Q)
        """
        return self._plan.at(check_number(t, "t"))   # the plan holds at its ends

    def commands(self, times) -> tuple[FloatArray, FloatArray]:
        """Planned commands at many ``times`` (s): means (T, Q) and covariances (T, Q, Q)."""
        return self._plan.interpolate(check_array(times, "times", 1))

    def plan(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The whole current plan: knot times (n,), means (n, Q), covariances (n, Q, Q)."""
        plan = self._plan
        return plan.times.copy(), plan.mean.copy(), plan.cov.copy()

    def prediction(self, times) -> tuple[FloatArray, FloatArray]:
        """The latest update's robot distribution at ``times`` (unblended; holds after its end).

        Raises ``RuntimeError`` before the first update.
        """
        if self._prediction is None:
            raise RuntimeError("no update yet: observe more of the motion first")
        return self._prediction.trajectory(self.model.basis, check_array(times, "times", 1))

    @property
    def last_prediction(self) -> Prediction | None:
        """The latest update's :class:`Prediction` (None before the first update)."""
        return self._prediction

    def observations(self) -> tuple[FloatArray, FloatArray]:
        """Kept observations: times (s,), values (s, P) in the model's human layout
        (signals normalised; NaN where a modality was not kept)."""
        return self.stream.observations()

    @property
    def n_skipped(self) -> int:
        """Rows skipped because no modality was valid in them (NaN or rejected)."""
        return self.stream.n_skipped

    @property
    def n_rejected(self) -> int:
        """Rows in which a modality was outside the model's range (masked like a NaN)."""
        return self.stream.n_rejected

    @property
    def task_posterior(self) -> dict[str, float]:
        """Current p(k | observations) by task name (the priors before any update)."""
        p = self.updates[-1].task_posterior if self.updates else self.model.priors
        return {name: float(v) for name, v in zip(self.model.tasks, p)}

    @property
    def task(self) -> str:
        """Most probable task now."""
        post = self.task_posterior
        return max(post, key=lambda name: post[name])

    @property
    def alpha(self) -> float:
        """Speed factor of the chosen task (its prior mean before any update)."""
        return (self.updates[-1].alpha if self.updates else
                float(self.model.task_models[self.model.task_index(self.task)].alpha_mean))

    @property
    def duration(self) -> float:
        """Estimated duration of the motion (s); before any update, the prior mean."""
        return (self.updates[-1].duration if self.updates else
                float(np.dot(self.model.priors, [t.mean_duration for t in self.model.task_models])))

    def update(self, t: float | None = None) -> Update | None:
        """Update now (at ``t``, default: the last observation time) with the observations kept.

        Returns None if there is nothing to update from. ``t`` earlier than the
        last update is a ``ValueError``: the plan before it may have been executed.
        """
        window = self._update_window(t)
        if window is None:
            return None
        t, times, values = window
        start = _time.perf_counter()
        stats = self._stats if self._stats is not None and self._stats.count == times.size else None
        first = self.stream.first_time
        pred = predict(self.model, self.scorer, times, values, likelihood=self.likelihood,
                       n_candidates=self.n_candidates, width=self.width,
                       refine_steps=self.refine_steps, stats=stats,
                       rest=bool(times[0] <= first))   # a later window is no rest (rest.py)
        return self._apply(t, pred, int(times.size), start)

    def _update_window(self, t: float | None):
        """``(t, times, values)`` of an update at ``t`` (default: the last observation
        time), checked against the last update; None if the window holds nothing."""
        if t is None:
            if not np.isfinite(self._last_time):
                raise ValueError("update: no observation yet and no time given")
            t = self._last_time
        t = self._check_update_time(t)
        times, values = self._window(t)
        return None if times.size == 0 else (t, times, values)

    def apply(self, t: float, prediction: Prediction, *, n_observations: int = 0,
              started: float | None = None) -> Update | None:
        """Blend a prediction made elsewhere (:func:`~sandbox.core.inference.predict`) into
        the plan at time ``t``, exactly as an update does; returns the recorded update.

        Lets several predictors that differ only in how they blend share one
        estimate (e.g. windows of an evaluation fed the same observations).
        With ``until_end``, once a prediction's motion ended before ``t`` (see
        :attr:`ended`), the task is held: this and later predictions condition
        the task chosen before the end (marginal likelihood: they are dropped
        and None is returned). ``t`` earlier than the last update is a ``ValueError``.
        """
        start = _time.perf_counter() if started is None else started
        t = self._check_update_time(t)
        if not isinstance(prediction, Prediction):
            raise ValueError(f"prediction: expected a Prediction, got {type(prediction).__name__}")
        n_observations = check_integer(n_observations, "n_observations", 0)
        return self._apply(t, prediction, n_observations, start)

    def _apply(self, t: float, prediction: Prediction, n_observations: int,
               start: float) -> Update | None:
        """:meth:`apply` of checked arguments (an update's own prediction)."""
        held = self.ended
        ends = False
        familiarity = self._familiarity_of(t, prediction)
        if held:
            if prediction.factors is None:
                return None                      # marginal likelihood: the plan just holds
            last = self.updates[-1]
            prediction = prediction.for_task(self.model, self.model.task_index(last.task),
                                             last.task_posterior, scorer=self.scorer)
        elif self.until_end and prediction.ended_probability(t) >= self.end_prob:
            ends = True                          # this update decides; later ones hold it
        k = prediction.task_index
        self._plan, jump = self._plan.blended(
            t, Held(prediction.robot, prediction.duration, self.model.basis),
            prediction.duration, self._blending)
        self.ended = self.ended or ends
        self._prediction = prediction
        upd = Update(float(t), int(n_observations), self.model.tasks[k],
                     prediction.task_posterior, prediction.alphas, prediction.durations,
                     prediction.log_likelihood, float(prediction.alphas[k]),
                     prediction.duration, jump, _time.perf_counter() - start, held,
                     familiarity, prediction.motion_probability)
        self.updates.append(upd)
        self._after_update()
        return upd

    def _after_update(self) -> None:
        """Hook: what to forget after an update (nothing by default)."""

    @property
    def familiarity(self) -> float | None:
        """How well the observations fit the best task, in (0, 1] (higher: more like the
        held-out training motions; :mod:`sandbox.core.familiarity`).

        None before the first update, and when the model carries no calibration
        (``model.calibration``, made by :func:`~sandbox.core.familiarity.calibrate`;
        model files saved without one load with None), the likelihood is marginal
        or, for a calibration gated to the ongoing motion, past its estimated end.
        """
        return self.updates[-1].familiarity if self.updates else None

    @property
    def familiar(self) -> bool | None:
        """False when :attr:`familiarity` is below the calibration's threshold (an
        unknown motion); None when there is no familiarity."""
        fam, cal = self.familiarity, getattr(self.model, "calibration", None)
        return None if fam is None or cal is None else bool(fam >= cal.threshold)

    def _familiarity_of(self, t: float, prediction: Prediction) -> float | None:
        cal = getattr(self.model, "calibration", None)
        if cal is None or prediction.factors is None:
            return None
        k = chosen(prediction)                # past the estimated end (latched): not judged
        self._past_end = max(self._past_end, prediction.ended_probability(t, k))
        if cal.end_prob is not None and self._past_end >= cal.end_prob:
            return None
        value: float | FloatArray = (statistic(prediction) if len(cal.components) == 1 else
                                     statistics(self.model, prediction, t, *self._window(t),
                                                names=tuple(cal.components)))
        return cal.familiarity(t, value, k)

    @property
    def _last_update(self) -> float:
        return self.updates[-1].time if self.updates else -np.inf

    def _check_update_time(self, t) -> float:
        t = check_time(t, "t", self.max_time)
        if t < self._last_update:
            raise ValueError(f"update: expected a time >= the last update's "
                             f"({self._last_update:g} s), got {t:g} s: the plan before the last "
                             f"update may have been executed and is never rewritten")
        return t

    # ------------------------------------------------------------ internals
    def _maybe_update(self, t: float) -> Update | None:
        raise NotImplementedError

    def _window(self, t: float) -> tuple[FloatArray, FloatArray]:
        return self.stream.until(t)

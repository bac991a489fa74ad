"""Familiarity: do the observations look like the motions the model learned?

The task posterior only compares the tasks with each other: a motion unlike
any of them (a task left out of training, a hand held still) still gets a
confident "most probable" task. Familiarity asks the other question: how well
do the observations fit the *best* task, compared with how well held-out
motions of the trained tasks fit it?

The first statistic of one update (:func:`statistic`) is the squared Mahalanobis
distance of all observations so far from the best task's predictive
distribution at its MAP speed, per observed value,

.. math::  m = \\frac{1}{n} (y - \\mu_y)^T C^{-1} (y - \\mu_y), \\quad
            C = \\Psi \\Sigma_\\omega \\Psi^T + \\Sigma_y

(the quadratic term of the joint log-likelihood, eq. 12; :math:`n` observed
values). Under the model it would be about 1; the real scale is not (the noise
floor is set for recognition, not for calibration, and observations are
correlated). A slow or hesitant person is absorbed by the speed factor in
:math:`m`, so three statistics of timing join it (:mod:`sandbox.core.evidence`,
with their equations): the elapsed time against the best task's speed prior
while the motion has not ended, the observed speed against the predicted one
over the last 0.3 s, and the spread of the speed posterior; one of the
goal: how far the conditioned end of the hand's motion lies from the task's
prior ends (a hand heading elsewhere); and one of the position: the last 0.2 s of
observations, each against the task's prior predictive at its phase (a hand off the
task's tube now, which :math:`m`, averaged over all values so far, sees late);
:func:`statistics` gives all six, :math:`s = (m, s_T, s_v, s_\\phi, s_G, s_X)`.

They are *calibrated* (:func:`calibrate`): each training motion,
streamed as a predictor sees it, is scored by a model fitted without it
(leave-one-out), and the quantiles of each statistic per task and bin of
elapsed time are stored (:class:`Calibration`; a task's cell holds the updates that chose
it, or with ``cells="own"`` every update of its own motions under it:
:mod:`sandbox.core.cells`, with the derivation). Each statistic of an update
then ranks as a p-value-like :math:`p_j` in (0, 1]: the share of held-out
training updates in the cell of the task chosen at it, at about the same elapsed time, that
scored worse (:math:`s_T` and :math:`s_G`, p-value bounds by construction, rank as
:math:`e^{-s}`); the familiarity is Fisher's combination of the four,
:math:`f = P(\\chi^2_8 \\ge -2 \\sum_j \\log p_j)`, and with the goal or the position
the least of that and theirs as a p-value (Šidák; :meth:`Calibration.familiarity`).
The threshold below which :attr:`~sandbox.core.updating.PredictorBase.familiar`
is False is the split-conformal quantile of each calibration motion's *lowest*
familiarity over its updates (:func:`~sandbox.core.calibration.conformal_threshold`),
so a new motion like the training ones is called unfamiliar at some update
with probability at most ``alpha`` (and above ``alpha - 1/(n+1)``).
By default (``score="timing"``) a calibration ranks the first four; ``score="goal"``
adds :math:`s_G`, ``score="position"`` :math:`s_X`, ``score="all"`` both
(:data:`SCORE_NAMES`; what the position gains and costs: docs, Results). The goal
doubles the detection of a hand heading for an end outside every task (synthetic), but
costs elsewhere: on the synthetic sessions whose motions have a tail after the handover
(drifting back) a slowed motion was flagged in 0.03 of trials instead of 0.77, and on
the recorded set's leave-task-out (where left-out objects are handed over where the
trained ones are) detection at 5 % false alarms fell from 0.14 to 0.13; so it is asked
for, not the default (docs, Results). ``score="mahalanobis"`` calibrates :math:`m` alone
(what models before the timing evidence carry; they still load and rank that way).

The statistic grows with the white noise of the stream (1 cm of tracker noise
adds (1 cm / 2 cm floor)^2 = 0.25), so the calibration streams must be
preprocessed like the live ones (causally filtered, same rate).

Measured on the recorded handovers, hand only (``python -m sandbox.eval.ood``;
README, Results), with :math:`m` alone: the Mahalanobis term, the
log-likelihood per value and the smallest Mahalanobis term over tasks all
detected a left-out task at about their false-alarm rate (within 1 point of
each other); left-out objects are reached like the trained ones.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.calibration import CELLS, EDGES, LEVELS, Calibration, check, leave_one_out
from sandbox.core.evidence import COMPONENTS, TIMING, components
from sandbox.core.inference import Prediction, predict
from sandbox.core.likelihood import Scorer
from sandbox.core.phase import Lattice
from sandbox.core.statistics import StreamStatistics
from sandbox.core.stream import ObservationStream
from sandbox.validation import FloatArray, check_array, check_choice, check_integer

if TYPE_CHECKING:
    from sandbox.core.model import IProMP

__all__ = ["CELLS", "COMPONENTS", "EDGES", "LEVELS", "SCORES", "SCORE_NAMES", "Calibration",
           "calibrate", "check", "chosen", "leave_one_out", "loo_records", "statistic",
           "statistics", "statistics_under", "stream_record", "update_times"]

#: What a calibration ranks, by the name ``calibrate(score=...)`` takes: the four of
#: timing (default), those and the goal, those and the position, all six
#: :data:`COMPONENTS`, or the Mahalanobis term alone.
SCORE_NAMES = {"timing": TIMING, "goal": TIMING + ("goal",), "position": TIMING + ("position",),
               "all": COMPONENTS, "mahalanobis": ("mahalanobis",)}
SCORES = tuple(SCORE_NAMES)


def statistic(prediction: Prediction) -> float:
    """Squared Mahalanobis distance per observed value of the chosen task (module docstring).

    Parameters
    ----------
    prediction : Prediction
        From :func:`~sandbox.core.inference.predict` with the joint likelihood
        (it keeps every task's augmented factor and ``n_values``).

    Returns
    -------
    float
        :math:`m \\ge 0`; NaN when the prediction kept no factors (marginal likelihood).
    """
    if prediction.factors is None or not prediction.n_values:
        return float("nan")
    k = chosen(prediction)
    return float(prediction.factors[k, -1, -1] ** 2 / prediction.n_values)


def statistics(model: IProMP, prediction: Prediction, t: float, times: FloatArray,
               values: FloatArray, *, names: tuple = COMPONENTS) -> FloatArray:
    """The statistics ``names`` of an update, shape (len(names),): by default all six of
    :data:`COMPONENTS` (module docstring); a calibration's ``components`` for what it ranks.

    Parameters
    ----------
    model : IProMP
    prediction : Prediction
        As for :func:`statistic`, made from ``times`` and ``values``.
    t : float
        Update time (s) since the motion started.
    times : ndarray, shape (s,)
        Kept observation times (s).
    values : ndarray, shape (s, P)
        Kept observations (normalised units; NaN where unobserved).
    """
    m = statistic(prediction)
    if not np.isfinite(m):
        return np.full(len(names), np.nan)
    return components(model, prediction, t, times, values, chosen(prediction), m, names=names)


def chosen(prediction: Prediction) -> int:
    """The task the observations fit best: the most probable one (its own posterior,
    even when a predictor holds another task after the motion's end)."""
    return int(np.argmax(prediction.task_posterior))


# ----------------------------------------------------------------- calibrating
def update_times(times: FloatArray, kept: FloatArray, dow_t: float) -> FloatArray:
    """Row times at which a :class:`~sandbox.core.predictor.DynamicPredictor` updates.

    ``times`` (T,) are the rows' times (s), ``kept`` (s,) those of the kept
    observations (an update needs at least one).
    """
    out, boundary = [], dow_t
    for ti in times:
        if ti >= boundary - 1e-9:
            if np.searchsorted(kept, ti, side="right") > 0:
                out.append(float(ti))
            boundary = float((np.floor(ti / dow_t + 1e-9) + 1) * dow_t)
    return np.array(out)


def stream_record(model: IProMP, times, human, *, dow_t: float = 0.2, subsample: int = 2,
                  n_candidates: int = 50, width: float = 3.0, refine_steps: int = 1,
                  score: str = "timing", ended: bool = False, own: int | None = None) -> tuple:
    """Update times (u,), statistics and chosen task (u,) of a stream, as a predictor sees it.

    The statistics are :func:`statistics` (u, 6) for every score but
    ``"mahalanobis"`` (all are recorded; a calibration keeps its own),
    :func:`statistic` (u,) with ``score="mahalanobis"``. With ``own``, the same
    statistics under task ``own`` at every update follow last (u, 6) or (u,): what an
    own-task calibration files into that task's cells (:mod:`sandbox.core.cells`).

    Parameters
    ----------
    model : IProMP
        Fitted.
    times : array_like, shape (T,)
        Row times (s) since the motion started.
    human : array_like, shape (T, P)
        Raw rows (all the model's modalities; NaN where missing).
    dow_t, subsample, n_candidates, width, refine_steps
        As for :class:`~sandbox.core.predictor.DynamicPredictor` (joint likelihood,
        all observations so far).
    score : {"timing", "goal", "position", "all", "mahalanobis"}
        What to record (:data:`SCORES`).
    ended : bool
        Also return, fourth, each update's posterior probability that the chosen
        task's motion had ended (u,) (:meth:`~sandbox.core.inference.Prediction.ended_probability`),
        what :func:`~sandbox.core.conformal.ongoing` gates on.
    own : int or None
        The motion's true task (index in [0, K)): also return its statistics under it.
    """
    times = check_array(times, "times", 1)
    own = None if own is None else check_integer(own, "own", 0, len(model.task_models) - 1)
    timing = check_choice(score, "score", SCORES) != "mahalanobis"
    stream = ObservationStream(model, subsample=subsample)
    for ti, yi in zip(times, np.asarray(human, dtype=np.float64)):
        stream.accept(ti, yi)
    t_obs, y_obs = stream.observations()
    scorer = Scorer(model)
    stats = StreamStatistics(scorer, Lattice.for_tasks(model.task_models, n_candidates, width))
    at = update_times(times, t_obs, dow_t)
    out = np.empty((at.size, len(COMPONENTS)) if timing else at.size)
    under = np.empty_like(out)
    task, fed, done = np.zeros(at.size, dtype=np.int64), 0, np.zeros(at.size)
    for j, tau in enumerate(at):
        n = int(np.searchsorted(t_obs, tau, side="right"))
        for i in range(fed, n):
            stats.add(t_obs[i], y_obs[i])
        fed = n
        pred = predict(model, scorer, t_obs[:n], y_obs[:n], n_candidates=n_candidates,
                       width=width, refine_steps=refine_steps, stats=stats)
        out[j] = statistics(model, pred, tau, t_obs[:n], y_obs[:n]) if timing else statistic(pred)
        task[j] = chosen(pred)
        done[j] = min(1.0, pred.ended_probability(tau, task[j]))     # sums may round over 1
        if own is not None:
            under[j] = (out[j] if task[j] == own else
                        statistics_under(model, pred, tau, t_obs[:n], y_obs[:n], int(own),
                                         timing))
    found = (at, out, task, done) if ended else (at, out, task)
    return found if own is None else (*found, under)


def statistics_under(model: IProMP, prediction: Prediction, t: float, times: FloatArray,
                     values: FloatArray, k: int, timing: bool = True):
    """:func:`statistics` (all six; ``timing=False``: :math:`m` alone, a float) of an update
    under task ``k`` instead of the chosen one: :math:`m` from task k's factor at its MAP
    speed, the others with k's priors (:func:`~sandbox.core.evidence.components`)."""
    if prediction.factors is None or not prediction.n_values:
        return np.full(len(COMPONENTS), np.nan) if timing else float("nan")
    m = float(prediction.factors[k, -1, -1] ** 2 / prediction.n_values)
    return components(model, prediction, t, times, values, k, m) if timing else m


def loo_records(model: IProMP, demos, streams=None, *, labelled: bool = False,
                **options) -> list[tuple]:
    """:func:`stream_record` of every demo by a model fitted on all the others.

    ``model`` gives the options (its fit, if any, is not used); ``streams[i]``
    is demo i as a predictor receives it (e.g. causally filtered; default the
    demo itself, whose smoothing makes it fit better than live streams do).
    Each task needs three demos or more (two left when one is out). ``labelled``:
    each record ends with the statistics under the demo's own task (``own``).
    """
    streams = demos if streams is None else streams
    if len(streams) != len(demos):
        raise ValueError(f"streams: expected one per demo ({len(demos)}), got {len(streams)}")
    fits = [model.demo_fit(d) for d in demos]
    # the tasks in all the demos' first-seen order, whichever demo is out: a task index of
    # a record is then the full model's (interleaved demos would reorder them otherwise)
    order = {task: j for j, task in enumerate(dict.fromkeys(f.task for f in fits))}
    out = []
    for i, s in enumerate(streams):
        rest = sorted(fits[:i] + fits[i + 1:], key=lambda f: order[f.task])   # stable
        held_out = copy.copy(model).fit_demo_fits(rest, demos[0])
        t = np.asarray(s.times, dtype=np.float64)
        own = held_out.task_index(demos[i].task) if labelled else None
        out.append(stream_record(held_out, t - t[0], s.human, own=own, **options))
    return out


def calibrate(model: IProMP, demos, streams=None, *, alpha: float = 0.05, dow_t: float = 0.2,
              subsample: int = 2, score: str = "timing", refit: bool = True,
              end_prob: float | None = None, cells: str = "own", **options) -> Calibration:
    """Leave-one-out calibration of the familiarity of ``model`` (fitted on ``demos``).

    Sets ``model.calibration`` and returns it. Cost: one stream of every demo
    with an update every ``dow_t`` (seconds per demo on the recorded set).

    Parameters
    ----------
    model : IProMP
        Fitted on ``demos`` (the calibration refits without each in turn), or, with
        ``refit=False``, on other motions.
    demos, streams, **options
        As for :func:`loo_records`.
    alpha : float
        Share of held-out motions allowed to be unfamiliar at some update.
    dow_t, subsample : float, int
        The predictor's window (s) and subsampling the familiarity is calibrated for.
    score : {"timing", "goal", "position", "all", "mahalanobis"}
        The four statistics of timing with the Mahalanobis term (default), those and
        the goal, the position or both, or the Mahalanobis term alone
        (:data:`SCORE_NAMES`; module docstring).
    refit : bool
        True: ``demos`` are the training demos, each streamed by a model fitted
        without it. False: ``demos`` are motions the model was not fitted on (a fresh
        draw of a synthetic family, a held-out set), each streamed by ``model`` itself:
        no refit, the split-conformal calibration of the same statistics.
    end_prob : float or None
        Calibrate (and rank) only the updates before each motion's estimated end, where
        the probability that it had ended first reached ``end_prob``
        (:func:`~sandbox.core.conformal.ongoing`); None: every update.
    cells : {"own", "chosen"}
        File each calibration motion's updates under its own task (each demo's ``task``,
        its statistics under that task: default) or under the task chosen at each update
        (before issue 30's own-task cells); :mod:`sandbox.core.cells` for why.
    """
    labelled = check_choice(cells, "cells", CELLS) == "own"
    records = _records(model, demos, streams, refit, labelled, dow_t=dow_t, subsample=subsample,
                       score=score, ended=True, **options)
    names = SCORE_NAMES[score]
    where = [COMPONENTS.index(n) for n in names]
    pick = (lambda v: np.asarray(v)[:, where]) if score != "mahalanobis" else np.asarray
    own = ([(t, pick(u), np.full(len(t), model.task_index(d.task)), e)
            for (t, _, _, e, u), d in zip(records, demos, strict=True)] if labelled else None)
    records = [(t, pick(v), k, e) for t, v, k, e, *_ in records]
    mean = float(np.dot(model.priors, [t.mean_duration for t in model.task_models]))
    cal = Calibration.from_records(records, len(model.task_models), alpha=alpha,
                                   edges=np.array(EDGES) * mean, own=own,
                                   subsample=subsample, dow_t=dow_t, end_prob=end_prob,
                                   components=names)
    model.calibration = cal
    return cal


def _records(model: IProMP, demos, streams, refit: bool, labelled: bool, **options) -> list:
    """:func:`calibrate`'s records: :func:`loo_records` (``refit``) or each stream by
    ``model`` itself; ``labelled``: with the statistics under each demo's own task last."""
    if refit:
        return loo_records(model, demos, streams, labelled=labelled, **options)
    streams = demos if streams is None else streams
    if len(streams) != len(demos):
        raise ValueError(f"streams: expected one per demo ({len(demos)}), got {len(streams)}")
    out = []
    for d, s in zip(demos, streams, strict=True):
        t = np.asarray(s.times, dtype=np.float64)
        out.append(stream_record(model, t - t[0], s.human,
                                 own=model.task_index(d.task) if labelled else None, **options))
    return out

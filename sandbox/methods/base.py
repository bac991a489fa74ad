"""What the four methods share: the predictor interface, the plan and the observation stream.

A :class:`MethodPredictor` is a :class:`~sandbox.core.DynamicPredictor` whose
estimate is not the IProMP's: every ``dow_t`` seconds it asks its method for a
:class:`~sandbox.core.inference.Prediction` (task posterior, duration, robot
weight distribution) from the observations kept so far, and blends it into
the plan exactly as the dynamic IProMP does (eq. 16-18). The observation
stream (validation, NaN skipping, subsampling, normalisation of signals), the
update times, the blending, the end-of-motion hold and the online API
(``observe``, ``command``, ``task_posterior``...) are therefore the same for
every method: differences in a comparison are the estimators'.

A filter (BIP, eBIP) advances from a phase :math:`\\phi` at the update time
:math:`t_u` at rate :math:`\\dot\\phi`; its robot motion is the
:class:`PhasePrediction`, whose phase at time :math:`\\tau` is
:math:`\\mathrm{clip}(\\phi + \\dot\\phi(\\tau - t_u), 0, 1)` and whose duration
is :math:`t_u + (1 - \\phi)/\\dot\\phi`.

Choice where the papers are silent: the end-of-motion hold (``until_end``) of
the dynamic IProMP applies to every method (an update whose predicted
duration lies before its time ends the motion; later updates keep the plan,
as the IProMP with the marginal likelihood does).
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sandbox.core.inference import Prediction
from sandbox.core.predictor import DynamicPredictor
from sandbox.core.promp import WeightDistribution, trajectory_distribution
from sandbox.core.recognition import task_posterior
from sandbox.methods.library import DemoLibrary
from sandbox.validation import FloatArray

#: Smallest phase velocity (1/s) a filter may predict with (a motion of at most 1000 s).
MIN_RATE = 1e-3


@dataclass(frozen=True, eq=False)
class PhasePrediction(Prediction):
    """A :class:`Prediction` whose phase runs from ``phase`` at ``time`` at ``rate`` (1/s)."""

    phase: float = 0.0
    rate: float = 1.0
    time: float = 0.0

    def trajectory(self, basis, times) -> tuple[FloatArray, FloatArray]:
        """Robot mean (T, Q) and covariance (T, Q, Q) at ``times`` (s); holds after the end."""
        z = np.clip(self.phase + self.rate * (np.asarray(times, dtype=float) - self.time), 0, 1)
        return trajectory_distribution(self.robot, basis, z)


def end_time(phase: float, rate: float, t: float) -> float:
    """Duration (s) of a motion at ``phase`` at time ``t`` (s) advancing at ``rate`` (1/s)."""
    return float(t + (1.0 - phase) / max(rate, MIN_RATE))


def robot_from_cov(mean: FloatArray, cov: FloatArray, reg: FloatArray,
                   n_basis: int) -> WeightDistribution:
    """A robot :class:`WeightDistribution` from a mean (Q*N,) and a dense positive definite
    ``cov`` (Q*N, Q*N): its eigen-factor, with a regulariser of 1e-6 x the smallest of
    ``reg`` (Q,) split off the spectrum so it stays positive definite."""
    vals, vecs = np.linalg.eigh(0.5 * (cov + cov.T))
    floor = float(reg.min()) * 1e-6
    factor = vecs * np.sqrt(np.maximum(vals - floor, 0.0))
    return WeightDistribution(mean, factor, np.full(reg.size, floor), n_basis)


def robot_from_members(mean: FloatArray, members: FloatArray, reg: FloatArray,
                       n_basis: int) -> WeightDistribution:
    """A robot :class:`WeightDistribution` from a mean (Q*N,) and ensemble ``members``
    (E, Q*N): their sample covariance plus the task's robot regulariser ``reg`` (Q,), so the
    result stays positive definite with E below Q*N."""
    dev = (members - mean).T / np.sqrt(max(members.shape[0] - 1, 1))
    return WeightDistribution(mean, dev, reg, n_basis)


class MethodPredictor(DynamicPredictor):
    """A method's estimate behind the dynamic predictor's interface (module docstring).

    Subclasses implement :meth:`estimate`. Parameters are
    :class:`~sandbox.core.DynamicPredictor`'s (``dow_t``, ``observe``,
    ``subsample``, blending...), plus the training demos.

    Parameters
    ----------
    library : DemoLibrary
        The training demos and the model fitted on them.
    dow_t : float
        Seconds between updates.
    **options
        Of :class:`~sandbox.core.DynamicPredictor` (``likelihood`` and the speed
        lattice are unused).
    """

    #: The method's name in the registry (:data:`sandbox.methods.METHODS`).
    name = ""
    #: Per-task filters of a filtering method (BIP, eBIP), fed by :meth:`_feed_filters`.
    filters: list

    def __init__(self, library: DemoLibrary, dow_t: float = 0.2, **options) -> None:
        if not isinstance(library, DemoLibrary):
            raise ValueError(f"library: expected a DemoLibrary, got {type(library).__name__}")
        self.library = library
        options = {"incremental": False, "n_candidates": 3, **options}
        super().__init__(library.model, dow_t=dow_t, **options)

    def reset(self) -> None:
        super().reset()
        self._fed = 0
        self._reset_method()

    def _reset_method(self) -> None:
        """Hook: forget the method's own state."""

    def update(self, t: float | None = None):
        """Update now (at ``t``, default the last observation time); see
        :meth:`~sandbox.core.DynamicPredictor.update`."""
        window = self._update_window(t)
        if window is None:
            return None
        t, times, values = window
        start = _time.perf_counter()
        pred = self.estimate(t, times, values)
        return self.apply(t, pred, n_observations=int(times.size), started=start)

    def _feed_filters(self, t: float, times: FloatArray, values: FloatArray) -> None:
        """Run each task's filter (``self.filters``: ``predict(t)``, ``correct(y)``) over the
        observations not fed yet, then predict all of them to ``t`` (s)."""
        for ti, yi in zip(times[self._fed:], values[self._fed:]):
            for f in self.filters:
                f.predict(ti)
                f.correct(yi)
        self._fed = times.size
        for f in self.filters:
            f.predict(t)

    def estimate(self, t: float, times: FloatArray, values: FloatArray) -> Prediction:
        """The method's prediction at ``t`` (s) from the observations up to it.

        Parameters
        ----------
        t : float
        times : ndarray, shape (s,)
            Kept observation times (s).
        values : ndarray, shape (s, P)
            Their values in the model's human layout (normalised), NaN where not kept.
        """
        raise NotImplementedError

    def _make_prediction(self, log_likelihood: FloatArray, durations, robot: Callable,
                    phases=None, rates=None, t: float = 0.0) -> Prediction:
        """Recognition (eq. 14-15 on the method's per-task log-likelihoods) and the
        chosen task's prediction; ``robot(k)`` is task k's robot WeightDistribution."""
        model = self.model
        post = task_posterior(log_likelihood, model.priors)
        k = int(np.argmax(post))
        nominal = np.array([tm.nominal_duration for tm in model.task_models])
        durations = np.asarray(durations, dtype=float)
        common = (k, post, durations / nominal, durations, np.asarray(log_likelihood, float),
                  robot(k), float(durations[k]))
        if phases is None:
            return Prediction(*common)
        return PhasePrediction(*common, phase=float(phases[k]), rate=float(rates[k]), time=t)

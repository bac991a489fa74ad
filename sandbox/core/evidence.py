"""Evidence about timing that a streaming predictor has and a static pose check lacks.

The familiarity (:mod:`sandbox.core.familiarity`) ranks, per update, a vector of
:data:`COMPONENTS` statistics, each larger for a less usual motion. The first is
the Mahalanobis term of the best task at its MAP speed (what it always was); a
slow or hesitant person is absorbed by the speed factor there, so three more
read the timing, all for the chosen task :math:`k` at the update time :math:`t`
(s), from what the update already computed:

* **not arrived** (elapsed time against the speed prior). With
  :math:`\\alpha \\sim \\mathcal{N}(\\mu_\\alpha, \\sigma_\\alpha^2)` and
  :math:`T = \\alpha T_{nom}` (eq. 10), the prior probability that a motion is
  still going at :math:`t` is :math:`S(t) = 1 - \\Phi((t/T_{nom} - \\mu_\\alpha)/\\sigma_\\alpha)`.
  Weighted by the posterior probability that it has not ended,
  :math:`1 - e(t)` with :math:`e(t) = \\sum_{T_j \\le t} w_j` the duration
  posterior's mass up to :math:`t` (:func:`~sandbox.core.phase.ended_probability`),

  .. math::  s_T = (1 - e(t)) \\, (-\\log S(t)).

  For a motion of the prior that ends at :math:`T`, :math:`S(T)` is uniform,
  so the lowest :math:`e^{-s_T}` over its updates is a valid online p-value of
  its duration ("already 4.5 s and no handover yet").
* **speed change** (hesitation, stopping, rushing): over the last
  :data:`SPEED_WINDOW` seconds of kept observations (rows :math:`a, b`), the
  observed displacement against the one the task's mean predicts at the MAP
  duration :math:`T^*`, both in units of the observation noise
  :math:`\\sigma_p` per observed dim,

  .. math::  d_{obs} = (y_b - y_a) / \\sigma, \\quad
             d_{pred} = \\mu(t_b / T^*) - \\mu(t_a / T^*)\\ (\\text{over } \\sigma), \\quad
             s_v = \\left| \\log \\frac{\\lVert d_{pred} \\rVert + c}{\\lVert d_{obs} \\rVert + c}
             \\right|,

  :math:`c = \\sqrt{2 n}` the noise of a difference of two rows of
  :math:`n` observed dims (so noise alone moves :math:`s_v` little). A hand
  that stops mid-reach has :math:`d_{obs} \\approx 0` where :math:`d_{pred}`
  is large; past the predicted end the mean holds, and a hand still moving
  there has the reverse.
* **phase spread**: the duration posterior over the grid (weights
  :math:`w_j` on :math:`\\alpha_j = T_j / T_{nom}`), its expected squared
  standardised speed

  .. math::  s_\\phi = \\sum_j w_j
             \\left(\\frac{\\alpha_j - \\mu_\\alpha}{\\sigma_\\alpha}\\right)^2
             = \\mathrm{Var}[z] + \\mathrm{E}[z]^2,

  large when the speed is uncertain late in a motion (no candidate explains
  the observations better than another) or piled at an extreme of the prior.

None of them is used as a p-value directly: each is ranked against held-out
training updates of the same task and time bin (:mod:`sandbox.core.calibration`),
and the ranks are combined there. All are causal (the update's observations
and estimate) and cost a few microseconds beside the update.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.special import log_ndtr

from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.inference import Prediction
    from sandbox.core.model import IProMP

#: Names of the familiarity's statistics, in the order of :func:`components`.
COMPONENTS = ("mahalanobis", "not_arrived", "speed_change", "phase_spread")
#: Span (s) of observations the speed change compares.
SPEED_WINDOW = 0.3


def not_arrived(model: IProMP, prediction: Prediction, t: float, k: int) -> float:
    """:math:`s_T = (1 - e(t))(-\\log S(t)) \\ge 0` of task ``k`` at ``t`` (s), module docstring."""
    task = model.task_models[k]
    u = (t / task.nominal_duration - task.alpha_mean) / task.alpha_std
    log_survival = float(log_ndtr(-u))                 # log(1 - Phi(u)), exact in the tail
    ended = prediction.ended_probability(t, k) if prediction.grid is not None else 0.0
    return max(0.0, (1.0 - ended) * -log_survival)


def speed_change(model: IProMP, prediction: Prediction, k: int, times: FloatArray,
                 values: FloatArray, window: float = SPEED_WINDOW) -> float:
    """:math:`s_v \\ge 0` of task ``k`` from kept ``times`` (s,) and ``values`` (s, P) (normalised
    units, NaN where unobserved); 0 with fewer than two rows or no dim seen in both."""
    if times.size < 2:
        return 0.0
    b = times.size - 1
    a = max(int(np.searchsorted(times, times[b] - window, side="right")) - 1, 0)
    seen = np.isfinite(values[a]) & np.isfinite(values[b])
    if a == b or not seen.any():
        return 0.0
    sd = np.sqrt(model.noise[seen])
    observed = (values[b, seen] - values[a, seen]) / sd
    P, N = model.n_human, model.basis.n_basis
    mean = model.task_models[k].weights.mean[:P * N].reshape(P, N)[seen]
    z = np.clip(np.array([times[a], times[b]]) / prediction.durations[k], 0.0, 1.0)
    psi = model.basis.evaluate(z)                      # (2, N), eq. 3
    predicted = (mean @ (psi[1] - psi[0])) / sd
    c = np.sqrt(2.0 * seen.sum())
    return float(abs(np.log((np.linalg.norm(predicted) + c) / (np.linalg.norm(observed) + c))))


def phase_spread(model: IProMP, prediction: Prediction, k: int) -> float:
    """:math:`s_\\phi \\ge 0` of task ``k``: expected squared standard speed (0 without grid)."""
    if prediction.grid is None:
        return 0.0
    durations, weights = prediction.grid[k]
    task = model.task_models[k]
    z = (durations / task.nominal_duration - task.alpha_mean) / task.alpha_std
    return float(np.dot(weights, z * z))


def components(model: IProMP, prediction: Prediction, t: float, times: FloatArray,
               values: FloatArray, k: int, mahalanobis: float) -> FloatArray:
    """The :data:`COMPONENTS` of one update, shape (4,): ``mahalanobis`` (given), then
    :func:`not_arrived`, :func:`speed_change`, :func:`phase_spread` of task ``k``."""
    return np.array([mahalanobis, not_arrived(model, prediction, t, k),
                     speed_change(model, prediction, k, times, values),
                     phase_spread(model, prediction, k)])

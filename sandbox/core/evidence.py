"""Evidence about timing and goal that a streaming predictor has and a static pose check lacks.

The familiarity (:mod:`sandbox.core.familiarity`) ranks, per update, a vector of
:data:`COMPONENTS` statistics, each larger for a less usual motion. The first is
the Mahalanobis term of the best task at its MAP speed (what it always was); a
slow or hesitant person is absorbed by the speed factor there, so three more
read the timing and one the goal, all for the chosen task :math:`k` at the
update time :math:`t` (s), from what the update already computed:

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

* **goal** (where the hand is heading). The weights are
  :math:`w = \\mu + U x + \\epsilon`, :math:`x \\sim \\mathcal{N}(0, I_r)` the demos'
  modes of variation, :math:`\\epsilon \\sim \\mathcal{N}(0, \\Lambda)`. The human's end
  (phase 1) over the :math:`d` observed dims is :math:`g = G w`,
  :math:`G = I_d \\otimes \\psi(1)^T`, with the prior
  :math:`\\mathcal{N}(G\\mu, \\Sigma_g)`, :math:`\\Sigma_g = G (UU^T + \\Lambda) G^T`. The
  update's factor (:mod:`sandbox.core.likelihood`, step 3) already holds the
  posterior of :math:`x` given the observations, :math:`\\mathcal{N}(K^{-1} e, K^{-1})`
  (eq. 8 on the latent), so the conditioned end moves by
  :math:`\\delta = G U K^{-1} e` and

  .. math::  D = \\delta^T \\Sigma_g^{-1} \\delta, \\qquad
             s_G = -\\log P(\\chi^2_d \\ge D).

  Under the model :math:`e` has covariance :math:`(K - I) K`, so :math:`\\delta` is
  Gaussian with covariance :math:`G U (I - K^{-1}) U^T G^T \\preceq \\Sigma_g`: :math:`D`
  is stochastically below :math:`\\chi^2_d` and :math:`e^{-s_G}` is a valid
  (conservative) p-value, like :math:`e^{-s_T}` (at the MAP speed and task, as all
  the statistics). A hand
  heading for an end outside the task moves :math:`\\delta` before the residual of
  each observation is large, and :math:`D` tests that one direction (:math:`d`
  degrees of freedom) where the Mahalanobis term averages over all :math:`n`
  values. It sees an end only along the demos' modes of variation
  (:math:`GU`): an end off in a direction no demo varied in moves
  :math:`\\delta` little, and is left to the Mahalanobis term.

* **position** (where the hand is, against where the task has it at this phase).
  Every statistic above reads the observations through the fit at the MAP speed, and
  the Mahalanobis term :math:`m` averages over all :math:`n` values so far: an end off
  every task shows in the last few tenths of a second before the handover (the
  diverging tasks branch late), where it adds a few units to :math:`m n` and so a few
  hundredths to :math:`m`. The prior predictive of one observation of task :math:`k`
  at phase :math:`z` is (eq. 12 for one row)

  .. math::  y \\sim \\mathcal{N}(\\mu(z), C(z)), \\quad
             \\mu(z) = \\Psi(z)\\mu_h, \\quad
             C(z) = \\Psi(z)(U_hU_h^T + \\Lambda_h)\\Psi(z)^T + \\Sigma_y,

  :math:`\\Psi(z) = I_P \\otimes \\psi(z)^T`. Each kept observation :math:`y_i` of the
  last :data:`POSITION_WINDOW` seconds, at its phase :math:`z_i = \\min(t_i / T^*, 1)`
  under the MAP duration, gives
  :math:`D_i = (y_i - \\mu(z_i))^T C(z_i)^{-1} (y_i - \\mu(z_i))` over its :math:`d_i`
  observed dims, :math:`\\chi^2_{d_i}` under the model, and

  .. math::  s_X = \\mathrm{median}_i \\left(-\\log P(\\chi^2_{d_i} \\ge D_i)\\right).

  One observation is the whole test (nothing is averaged away), the median over the
  window makes an isolated tracker jump (a single row off by centimetres, which the
  recordings and the synthetic tracker have) count for nothing, while a hand that keeps
  off the task's tube counts from half a window on. Its null distribution is not
  :math:`\\chi^2` (the MAP speed is fitted to these observations, the rows are
  correlated), so it is ranked against held-out updates like :math:`m`.

``not_arrived`` and ``goal`` are p-value bounds by construction and rank as
:math:`e^{-s}`; the others are ranked against held-out training updates of the
same task and time bin (:mod:`sandbox.core.calibration`), and the ranks are
combined there. All are causal (the update's observations and estimate) and
cost a few microseconds beside the update (one :math:`r \\times r` triangular
solve and a :math:`d \\times d` Cholesky for the goal, a batch of :math:`P \\times P`
solves over the window's rows for the position; ``bench``'s ``familiarity_ms`` and
``position_ms``).
"""

from __future__ import annotations

import weakref
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import lapack
from scipy.special import chdtrc, gammaln, log_ndtr

from sandbox.core.likelihood import compress_human
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.inference import Prediction
    from sandbox.core.model import IProMP

#: Names of the familiarity's statistics, in the order of :func:`components`.
COMPONENTS = ("mahalanobis", "not_arrived", "speed_change", "phase_spread", "goal",
              "position")
#: The statistics of calibrations made before the goal (model files still rank them).
TIMING = COMPONENTS[:4]
#: Statistics that are p-value bounds by construction, ranked as :math:`e^{-s}`.
ANALYTIC = ("not_arrived", "goal")
#: Statistics that ask a question of their own (where the hand heads, where it is): a
#: calibration combines each apart from the Fisher combination of the others
#: (:mod:`sandbox.core.calibration`).
SEPARATE = ("goal", "position")
#: Span (s) of observations the speed change compares.
SPEED_WINDOW = 0.3
#: Span (s) of the last observations whose median the position statistic takes.
POSITION_WINDOW = 0.2


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


#: Per task's weights: the end's latent loadings and prior covariance (:func:`goal_frame`).
_GOAL_FRAMES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def goal_frame(model: IProMP, k: int) -> tuple[FloatArray, FloatArray]:
    """Task ``k``'s human end: :math:`G U` (P, r) in the likelihood's frame and
    :math:`\\Sigma_g` (P, P).

    The loadings are those of :func:`~sandbox.core.likelihood.compress_human`'s
    turned factor (the frame of the update's factor; its first r columns); the
    covariance is frame-free. Cached per weights object (a refit makes new ones).
    """
    weights = model.task_models[k].weights
    cached = _GOAL_FRAMES.get(weights)
    if cached is not None:
        return cached
    P, N = model.n_human, model.basis.n_basis
    psi1 = model.basis.evaluate(np.ones(1))[0]                        # (N,), eq. 3 at z = 1
    turned, rank = compress_human(weights, P)
    loads = np.einsum("pnr,n->pr", turned.factor[:P * N].reshape(P, N, -1), psi1)
    cov = loads @ loads.T + np.diag(weights.reg[:P] * float(psi1 @ psi1))
    frame = (np.ascontiguousarray(loads[:, :rank]), cov)
    _GOAL_FRAMES[weights] = frame
    return frame


def goal(model: IProMP, prediction: Prediction, k: int, values: FloatArray) -> float:
    """:math:`s_G = -\\log P(\\chi^2_d \\ge D) \\ge 0` of task ``k`` (module docstring).

    ``values`` (s, P) are the update's observations (NaN where unobserved): the
    :math:`d` dims observed in some row are tested. 0 without factors (marginal
    likelihood) or observed dims.
    """
    seen = np.isfinite(values).any(axis=0) if values.size else np.zeros(model.n_human, bool)
    if prediction.factors is None or not seen.any():
        return 0.0
    loads, cov = goal_frame(model, k)
    r, R = loads.shape[1], prediction.factors.shape[1] - 1
    factor = prediction.factors[k]
    x = lapack.dtrtrs(factor[:r, :r], factor[R, :r], lower=1, trans=1)[0] if r else np.zeros(0)
    delta = loads[seen] @ x                                            # posterior end shift
    w = lapack.dtrtrs(np.linalg.cholesky(cov[np.ix_(seen, seen)]), delta, lower=1)[0]
    return chi2_log_survival(float(w @ w), int(seen.sum()))


#: Per task's weights: the human block's mean, factor and diagonal (:func:`position_frame`).
_POSITION_FRAMES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def position_frame(model: IProMP, k: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Task ``k``'s human block: mean :math:`\\mu_h` (P, N), factor :math:`U_h` (P, N, r)
    and diagonal :math:`\\lambda` (P,) (normalised units); cached per weights object."""
    weights = model.task_models[k].weights
    cached = _POSITION_FRAMES.get(weights)
    if cached is not None:
        return cached
    P, N = model.n_human, model.basis.n_basis
    frame = (weights.mean[:P * N].reshape(P, N),
             np.ascontiguousarray(weights.factor[:P * N].reshape(P, N, -1)),
             np.asarray(weights.reg[:P], dtype=np.float64))
    _POSITION_FRAMES[weights] = frame
    return frame


def position(model: IProMP, prediction: Prediction, k: int, times: FloatArray,
             values: FloatArray, window: float = POSITION_WINDOW) -> float:
    """:math:`s_X \\ge 0` of task ``k`` (module docstring) from kept ``times`` (s,) in s and
    ``values`` (s, P) (normalised units, NaN where unobserved): the median over the rows of
    the last ``window`` seconds; 0 without an observed value there."""
    if times.size == 0:
        return 0.0
    rows = times >= times[-1] - window - 1e-9
    mean, factor, reg = position_frame(model, k)
    psi = model.basis.evaluate(np.clip(times[rows] / prediction.durations[k], 0.0, 1.0))
    loads = np.einsum("wn,pnr->wpr", psi, factor)                     # (w, P, r)
    diag = reg[None] * np.einsum("wn,wn->w", psi, psi)[:, None] + model.noise[None]
    residual = values[rows] - psi @ mean.T                             # (w, P)
    seen = np.isfinite(residual)
    both = seen[:, :, None] & seen[:, None, :]
    eye = np.eye(model.n_human)
    cov = np.where(both, loads @ loads.transpose(0, 2, 1) + diag[:, :, None] * eye, eye)
    residual = np.where(seen, residual, 0.0)
    quad = np.einsum("wp,wp->w", residual, np.linalg.solve(cov, residual[:, :, None])[..., 0])
    dims = seen.sum(axis=1)
    scores = [chi2_log_survival(float(q), int(d)) for q, d in zip(quad, dims) if d]
    return float(np.median(scores)) if scores else 0.0


def chi2_log_survival(x: float, d: int) -> float:
    """:math:`-\\log P(\\chi^2_d \\ge x) \\ge 0`; past the doubles' range, the leading
    term of the upper incomplete gamma function,
    :math:`x/2 - (d/2 - 1)\\log(x/2) + \\log\\Gamma(d/2)`."""
    p = float(chdtrc(d, x))
    if p > 1e-300:
        return float(max(0.0, -np.log(p)))
    a, h = 0.5 * d, 0.5 * x
    return float(h - (a - 1.0) * np.log(h) + gammaln(a))


def components(model: IProMP, prediction: Prediction, t: float, times: FloatArray,
               values: FloatArray, k: int, mahalanobis: float, *,
               names: tuple = COMPONENTS) -> FloatArray:
    """The statistics ``names`` (default all :data:`COMPONENTS`) of one update of task ``k``,
    shape (len(names),): ``mahalanobis`` (given), :func:`not_arrived`, :func:`speed_change`,
    :func:`phase_spread`, :func:`goal`, :func:`position`; only those asked for are computed."""
    make = {"mahalanobis": lambda: mahalanobis,
            "not_arrived": lambda: not_arrived(model, prediction, t, k),
            "speed_change": lambda: speed_change(model, prediction, k, times, values),
            "phase_spread": lambda: phase_spread(model, prediction, k),
            "goal": lambda: goal(model, prediction, k, values),
            "position": lambda: position(model, prediction, k, times, values)}
    return np.array([make[name]() for name in names], dtype=np.float64)

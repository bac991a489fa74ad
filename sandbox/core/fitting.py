"""The parts of an :class:`~sandbox.core.model.IProMP` fit, step by step.

What one demonstration gives (:class:`DemoFit`: its weights, residuals and
moments up to :func:`motion_end`), and how the parts of many are pooled: the
scale of signal modalities (:func:`signal_scale`), the task models with their
regulariser and speed prior (:func:`task_models`) and the task priors
(:func:`task_priors`). The choices these steps implement are stated in
:mod:`sandbox.core.model`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.limits import MAX_ALPHA_STD
from sandbox.core.modality import Modality
from sandbox.core.promp import WeightDistribution, check_human_conditioning, fit_weights
from sandbox.core.shrinkage import shrunk
from sandbox.validation import FloatArray


class DemonstrationLike(Protocol):
    """What :meth:`IProMP.fit` needs of a demonstration (see ``sandbox.data.Demonstration``).

    ``modalities`` (a sequence of :class:`~sandbox.core.modality.Modality`) and
    ``human_names`` are optional: without them the human dims are one position
    modality ``"hand"``.
    """

    times: Any
    human: Any
    robot: Any
    task: str


@dataclass(frozen=True, eq=False)
class TaskModel:
    """One task's interaction primitive.

    Attributes
    ----------
    name : str
    weights : WeightDistribution
        Over the P human dims (normalised units) followed by the Q robot dims.
    nominal_duration : float
        :math:`T_{nom}` (s).
    alpha_mean, alpha_std : float
        Prior of the speed factor :math:`\\alpha = T/T_{nom}`.
    n_demos : int
    robot : WeightDistribution or None
        The same weights with the shrunk covariance that conditions the robot
        (``shrinkage="robot"``, :mod:`sandbox.core.shrinkage`); None: ``weights`` do.
    """

    name: str
    weights: WeightDistribution
    nominal_duration: float
    alpha_mean: float
    alpha_std: float
    n_demos: int
    robot: WeightDistribution | None = None

    @property
    def mean_duration(self) -> float:
        """Prior mean duration :math:`\\mu_\\alpha T_{nom}` (s)."""
        return self.alpha_mean * self.nominal_duration


@dataclass(frozen=True, eq=False)
class DemoFit:
    """What :meth:`IProMP.demo_fit` keeps of one demonstration (raw units).

    Attributes
    ----------
    task : str
    weights : ndarray, shape ((P+Q)*N,)
        Of the motion (up to its end, see :func:`motion_end`).
    residual : ndarray, shape (P,)
        Sum of squared residuals of the human dims' basis fit.
    dof : ndarray, shape (P,)
        Their degrees of freedom (valid samples - N).
    duration : float
        Of the motion (s).
    moments : ndarray, shape (3, P)
        Count, sum and sum of squares of each human dim's valid samples (for
        the scale of signal modalities).
    jitter : ndarray, shape (P,), optional
        Jitter (m) of each position dim's raw samples, NaN where unknown
        (:func:`sandbox.core.jitter.demo_jitter`).
    """

    task: str
    weights: FloatArray
    residual: FloatArray
    dof: FloatArray
    duration: float
    moments: FloatArray
    jitter: FloatArray | None = None


def motion_end(times, robot, settle_tol: float | None, human=None,
               arrive_tol: float | None = None) -> int:
    """Index of the last sample of a demonstration's motion.

    The motion is over once both partners have arrived:

    * the robot, at the first sample after which it stays within ``settle_tol``
      (rad, Euclidean norm over joints) of its final configuration;
    * the human (if ``human`` and ``arrive_tol`` are given), at the first sample
      where the hand (the first three human dims) comes within ``arrive_tol`` (m)
      of its farthest distance from where it started.

    ``None`` for a tolerance skips that partner; with neither, the last sample.
    At least the first two samples are kept.

    Parameters
    ----------
    times : ndarray, shape (T,)
    robot : ndarray, shape (T, Q)
    settle_tol : float or None
    human : ndarray, shape (T, P), optional
        NaN where missing.
    arrive_tol : float or None
    """
    last = len(times) - 1
    ends = []
    if settle_tol is not None:
        robot = np.asarray(robot, dtype=np.float64)
        away = np.flatnonzero(np.linalg.norm(robot - robot[-1], axis=1) > settle_tol)
        ends.append(away[-1] + 1 if away.size else last)
    if arrive_tol is not None and human is not None and np.shape(human)[1] >= 3:
        hand = np.asarray(human, dtype=np.float64)[:, :3]
        ok = np.isfinite(hand).all(axis=1)
        if ok.any():
            reach = np.where(ok, np.linalg.norm(hand - hand[np.argmax(ok)], axis=1), -np.inf)
            ends.append(int(np.argmax(reach >= reach.max() - arrive_tol)))
    if not ends:
        return last
    return int(min(max(max(ends), 1), last))


def settle_index(robot, tol: float | None, start: int = 0) -> int:
    """First sample at or after ``start`` from which the robot stays within ``tol`` (rad,
    Euclidean norm over joints) of its final configuration; ``start`` for ``None``.

    Parameters
    ----------
    robot : ndarray, shape (T, Q)
    tol : float or None
    start : int
    """
    if tol is None:
        return int(start)
    robot = np.asarray(robot, dtype=np.float64)
    away = np.flatnonzero(np.linalg.norm(robot - robot[-1], axis=1) > tol)
    return int(max(away[-1] + 1 if away.size else 0, start))


def fit_one(task: str, times: FloatArray, human: FloatArray, robot: FloatArray,
            basis: GaussianBasis, ridge: float, robot_end: int | None = None,
            jitter: FloatArray | None = None) -> DemoFit:
    """:class:`DemoFit` of one demonstration's motion (cut at :func:`motion_end`).

    Parameters
    ----------
    task : str
    times : ndarray, shape (T,)
        Seconds, increasing; the motion is ``times[:T]`` with ``T = len(human)``.
    human : ndarray, shape (T, P)
        Raw units, NaN where missing.
    robot : ndarray, shape (T_r, Q)
        Joint angles (rad), ``T_r >= T`` samples from the start.
    basis : GaussianBasis
    ridge : float
        Relative ridge of the weight fit (eq. 2).
    robot_end : int, optional
        Last robot sample of the robot's part (default ``T - 1``, the motion's
        end): the robot's samples up to it are time-normalised over the phase
        [0, 1] on their own (:class:`~sandbox.core.model.IProMP`, ``robot_tol``),
        so its end state is where it settled. The motion ends once the robot is
        within ``settle_tol`` (0.05 rad) of its final pose; on the recorded
        handovers that pose is 9 mm (mean) from where it settles, and the
        robot settles to 0.01 rad 12 % of the motion's duration later (median):
        predicted in a slightly shorter time, the settled pose costs e_q 0.001
        rad and takes 1 mm off e_p (leave-one-out, hand, dow_t 0.2 s).
    jitter : ndarray, shape (P,), optional
        Kept as :attr:`DemoFit.jitter`.
    """
    T = len(human)
    n = basis.n_basis
    end_r = T - 1 if robot_end is None else int(robot_end)
    z = (times[:T] - times[0]) / (times[T - 1] - times[0])
    z_r = (times[:end_r + 1] - times[0]) / (times[end_r] - times[0])
    wh = fit_weights(z, human, basis, ridge)                       # eq. 2, 5
    wr = fit_weights(z_r, robot[:end_r + 1], basis, ridge)
    err = human - basis.evaluate(z) @ wh.T
    ok = np.isfinite(err)
    clean = np.where(np.isfinite(human), human, 0.0)
    moments = np.stack([np.isfinite(human).sum(axis=0), clean.sum(axis=0),
                        (clean**2).sum(axis=0)]).astype(float)
    return DemoFit(str(task), np.vstack([wh, wr]).ravel(),   # eq. 6: concatenated dim after dim
                   (np.where(ok, err, 0.0) ** 2).sum(axis=0),
                   np.maximum(ok.sum(axis=0) - n, 1).astype(float),
                   float(times[T - 1] - times[0]), moments, jitter)


def by_task(fits: Sequence[DemoFit]) -> tuple[dict[str, list], dict[str, FloatArray]]:
    """Each task's demo weights (a list of arrays) and motion durations (s), in first-seen order.

    Raises
    ------
    ValueError
        For a task with fewer than two demonstrations.
    """
    weights: dict[str, list] = {}
    durations: dict[str, list] = {}
    for f in fits:
        weights.setdefault(f.task, []).append(f.weights)
        durations.setdefault(f.task, []).append(f.duration)
    small = [k for k, v in weights.items() if len(v) < 2]
    if small:
        raise ValueError(f"demos: expected at least two demonstrations per task, "
                         f"got one for {small}")
    return weights, {k: np.array(v) for k, v in durations.items()}


def observation_noise(fits: Sequence[DemoFit], scale: FloatArray, floors: FloatArray,
                      noise_scale: float) -> FloatArray:
    """Diagonal of :math:`\\Sigma_y`, shape (P,): pooled residual variance, scaled and floored.

    Parameters
    ----------
    fits : sequence of DemoFit
    scale : ndarray, shape (P,)
        Scale of the human dims (:func:`signal_scale`; 1 for positions).
    floors : ndarray, shape (P,)
        Lower bound of each standard deviation (normalised units).
    noise_scale : float
        Multiplies the pooled variance.
    """
    residual = np.sum([f.residual for f in fits], axis=0) / scale**2
    dof = np.sum([f.dof for f in fits], axis=0)
    return np.maximum(noise_scale * residual / dof, floors**2)


def task_models(weights: Mapping[str, FloatArray], durations: Mapping[str, FloatArray],
                sigma2: FloatArray, modalities: Sequence[Modality], regularizer: float,
                n_basis: int, min_alpha_std: float, shrinkage: str = "none",
                reg_floor: FloatArray | None = None,
                ) -> tuple[tuple[TaskModel, ...], dict[str, float]]:
    """One :class:`TaskModel` per task, in the order of ``weights``, and their shrinkage.

    Parameters
    ----------
    weights : mapping of str to ndarray, shape (n_demos, (P+Q)*N)
        Each task's demo weights (human dims normalised).
    durations : mapping of str to ndarray, shape (n_demos,)
        Motion durations (s).
    sigma2 : ndarray, shape (P,)
        Observation noise variances of the human dims (normalised units).
    modalities : sequence of Modality
        Their sizes sum to P.
    regularizer : float
        Relative size of the regulariser (:mod:`sandbox.core.model`).
    n_basis : int
    min_alpha_std : float
        Lower bound of the speed prior's standard deviation.
    shrinkage : {"auto", "none", "robot"}
        Covariance shrinkage toward the pooled one (:mod:`sandbox.core.shrinkage`);
        ``"robot"``: in :attr:`TaskModel.robot` only.
    reg_floor : ndarray, shape (P,), optional
        Lower bound of each modality's mean human regulariser (normalised units;
        :mod:`sandbox.core.spanreg`), equal over a modality's dims.

    Returns
    -------
    tasks : tuple of TaskModel
    intensities : dict of str to float
        Each task's shrinkage intensity (0 with ``"none"``).
    """
    P = sigma2.size
    dists = {k: WeightDistribution.from_weights(w, regularizer, n_basis)
             for k, w in weights.items()}
    shrunk_dists, intensities = shrunk(weights, dists, shrinkage)
    if shrinkage != "robot":
        dists = shrunk_dists
    human_reg = _human_reg(dists, sigma2, modalities, regularizer, reg_floor)
    tasks = []
    for k, dist in dists.items():
        reg = dist.reg.copy()
        reg[:P] = human_reg
        dist = WeightDistribution(dist.mean, dist.factor, reg, n_basis)
        robot = (WeightDistribution(dist.mean, shrunk_dists[k].factor, reg, n_basis)
                 if shrinkage == "robot" else None)
        T = durations[k]
        t_nom = float(T.mean())
        a_std = float(np.std(T / t_nom, ddof=1)) if T.size > 1 else 0.0   # eq. 10
        check_speed_spread(k, a_std, T)
        check_human_conditioning(dist, sigma2, k)
        tasks.append(TaskModel(k, dist, t_nom, 1.0, max(a_std, min_alpha_std), int(T.size),
                               robot))
    return tuple(tasks), intensities


def _human_reg(dists: Mapping, sigma2: FloatArray, modalities: Sequence[Modality],
               regularizer: float, reg_floor: FloatArray | None) -> FloatArray:
    """The human dims' regulariser (P,): :math:`\\kappa_m \\sigma_p^2`, one
    :math:`\\kappa_m` per modality from its own dims only, at least ``reg_floor``'s mean."""
    kappa = np.empty(sigma2.size)
    start = 0
    for m in modalities:
        dims = slice(start, start + m.size)
        var = np.mean([d.reg[dims] / regularizer for d in dists.values()])
        low = 0.0 if reg_floor is None else float(np.mean(reg_floor[dims]))
        kappa[dims] = max(regularizer * var, low) / sigma2[dims].mean()
        start += m.size
    return kappa * sigma2


def check_speed_spread(task: str, alpha_std: float, durations: FloatArray) -> None:
    """Refuse demos whose durations spread more than :data:`~sandbox.core.limits.MAX_ALPHA_STD`."""
    if alpha_std > MAX_ALPHA_STD:
        raise ValueError(f"task {task!r}: its demos' durations spread {alpha_std:.3g} times "
                         f"their mean (limits.MAX_ALPHA_STD {MAX_ALPHA_STD:g}): expected "
                         f"motions of one kind, got durations from {durations.min():g} s to "
                         f"{durations.max():g} s; check their time stamps and labels")


def signal_scale(modalities: Sequence[Modality], moments: FloatArray) -> FloatArray:
    """Standard deviation of each signal dim over the pooled samples; 1 for positions."""
    count, total, squares = moments
    scale = np.ones(count.size)
    start = 0
    for m in modalities:
        dims = np.arange(start, start + m.size)
        start += m.size
        if m.kind != "signal":
            continue
        n = np.maximum(count[dims], 1.0)
        var = squares[dims] / n - (total[dims] / n) ** 2
        std = np.sqrt(np.maximum(var, 0.0))
        bad = (count[dims] < 2) | ~(std > 1e-12 * np.maximum(np.abs(total[dims] / n), 1.0))
        if bad.any():
            names = [m.dims[i] for i in np.flatnonzero(bad)]
            raise ValueError(f"modality {m.name!r}: signal dims {names} are constant or missing "
                             f"in every training demonstration; nothing to normalise by")
        scale[dims] = std
    return scale


def task_priors(tasks: Sequence[str], spec: Mapping[str, float] | None) -> FloatArray:
    """Normalised task priors p(k), shape (K,); uniform without ``spec``."""
    if spec is None:
        return np.full(len(tasks), 1.0 / len(tasks))
    unknown = set(spec) - set(tasks)
    if unknown:
        raise ValueError(f"priors: unknown tasks {sorted(unknown)}; tasks are {list(tasks)}")
    p = np.array([spec.get(t, 0.0) for t in tasks], dtype=np.float64)
    if not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
        raise ValueError(f"priors: expected non-negative numbers with a positive sum, got {spec}")
    if not np.isfinite(p.sum()):
        p = p / p.max()      # huge priors: scale first, or the sum overflows
    return p / p.sum()

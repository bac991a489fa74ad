"""Error measures of DESIGN.md section 5 (paper sec. 3.1) and a few beyond the paper.

For a test trial with true robot joints q(t) (T x Q) at times t, true duration T:

* :func:`joint_rms` (e_q): RMS over time steps and joints of q_hat(t) - q(t) (rad);
* :func:`goal_error` (e_p): distance (m) between forward kinematics of q_hat(T) and q(T);
  for a robot part in task space (a position, m) the distance between the predicted and
  the true final positions themselves (:func:`goal_map`), and e_q does not apply (None);
* e_phi: ``|T_hat - T|`` (s);
* :func:`time_to_correct`: earliest fraction of the motion after which the
  predicted goal stays within ``tol`` of the true goal;
* :func:`gaussian_nll` and :func:`coverage`: calibration of the predicted
  per-step distribution of the robot joints;
* :func:`window_metric` (eq. 20): :math:`m(dow) = \\sum_i \\gamma_i e_i(dow) / \\max_{dow} e_i`;
* :func:`bootstrap_ci`: percentile confidence interval of a mean.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.special import gammaincinv

from sandbox.validation import FloatArray


def joint_rms(q_hat: FloatArray, q: FloatArray) -> float:
    """e_q: RMS over time steps and joints (rad). Shapes (T, Q)."""
    return float(np.sqrt(np.mean((np.asarray(q_hat) - np.asarray(q)) ** 2)))


def goal_error(q_hat_end: FloatArray, q_end: FloatArray, fk: Callable) -> float:
    """e_p: distance (m) between ``fk(q_hat_end)`` and ``fk(q_end)``."""
    return float(np.linalg.norm(fk(q_hat_end) - fk(q_end)))


def task_goal(x: FloatArray) -> FloatArray:
    """The goal of a task-space robot part: the position itself (m), shape as given."""
    return np.asarray(x, dtype=np.float64)


def goal_map(model, fk: Callable) -> Callable:
    """What e_p measures the distance between: ``fk`` (joints -> gripper position, m) for a
    joint-space model, :func:`task_goal` for one whose robot part is in task space."""
    return task_goal if getattr(model, "robot_space", "joint") == "task" else fk


def time_to_correct(fractions: FloatArray, goal_errors: FloatArray, tol: float = 0.05) -> float:
    """Earliest fraction after which every later predicted goal is within ``tol`` (m).

    Parameters
    ----------
    fractions : ndarray, shape (U,)
        Fraction of the motion at each update, increasing.
    goal_errors : ndarray, shape (U,)
        Distance of that update's predicted goal from the true goal (m).

    Returns
    -------
    float
        The fraction, or 1.0 if the last prediction is not within ``tol`` (never
        correct before the end).
    """
    ok = np.asarray(goal_errors) <= tol
    if ok.size == 0 or not ok[-1]:
        return 1.0
    bad = np.flatnonzero(~ok)
    first = 0 if bad.size == 0 else bad[-1] + 1
    return float(np.asarray(fractions)[first])


def gaussian_nll(q: FloatArray, mean: FloatArray, cov: FloatArray) -> float:
    """Mean over steps of :math:`-\\log\\mathcal{N}(q_t; \\mu_t, \\Sigma_t)` (nats per step)."""
    return calibration(q, mean, cov)[0]


def coverage(q: FloatArray, mean: FloatArray, cov: FloatArray) -> float:
    """Fraction of steps whose true q lies in the 95 % ellipsoid of N(mean_t, cov_t)."""
    return calibration(q, mean, cov)[1]


def calibration(q: FloatArray, mean: FloatArray, cov: FloatArray) -> tuple[float, float]:
    """:func:`gaussian_nll` and :func:`coverage` of one predicted distribution, from one
    Cholesky factorisation of its covariances.

    Parameters
    ----------
    q : ndarray, shape (T, Q)
        True robot joints (rad).
    mean : ndarray, shape (T, Q)
    cov : ndarray, shape (T, Q, Q)
        Predicted per-step distribution.

    Returns
    -------
    nll : float
        Mean over steps of :math:`-\\log\\mathcal{N}(q_t; \\mu_t, \\Sigma_t)` (nats per step).
    coverage : float
        Fraction of steps whose q lies in the 95 % ellipsoid.
    """
    d = (np.asarray(q) - mean)[..., None]
    L = np.linalg.cholesky(cov)
    m2 = (np.linalg.solve(L, d)[..., 0] ** 2).sum(axis=-1)      # squared Mahalanobis (T,)
    logdet = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(axis=-1)
    Q = mean.shape[-1]
    nll = float(np.mean(0.5 * (Q * np.log(2 * np.pi) + logdet + m2)))
    # the chi-square 95 % quantile, as scipy.stats.chi2.ppf computes it (equal to the bit)
    return nll, float(np.mean(m2 <= 2.0 * gammaincinv(Q / 2.0, 0.95)))


def window_metric(errors: dict[str, Sequence[float]], gamma: Sequence[float]) -> list[float]:
    """Window-selection metric m (eq. 20) for each window.

    Parameters
    ----------
    errors : dict
        ``{"e_p": [...], "e_q": [...], "e_phi": [...]}``, one entry per window.
    gamma : (3,) weights of e_p, e_q, e_phi.
    """
    out = np.zeros(len(errors["e_p"]))
    for g, key in zip(gamma, ("e_p", "e_q", "e_phi")):
        e = np.asarray(errors[key], dtype=float)
        top = e.max()
        out += g * (e / top if top > 0 else np.zeros_like(e))      # eq. 20
    return out.tolist()


def bootstrap_ci(values: FloatArray, groups: FloatArray | None = None, *, n_boot: int = 1000,
                 level: float = 0.95, rng: np.random.Generator | None = None,
                 statistic: Callable | str | None = None,
                 draws: list[np.ndarray] | None = None) -> tuple[float, float]:
    """Percentile bootstrap confidence interval of a mean (or ``statistic``).

    Resamples trials with replacement within each group (task), so a
    macro-average over tasks keeps its task weights.

    Parameters
    ----------
    values : array_like, shape (n,)
    groups : array_like, shape (n,), optional
        Group (task) of each value; one group if omitted.
    n_boot : int
        Resamples.
    level : float
        Coverage of the interval.
    rng : numpy.random.Generator, optional
        Source of the resamples (default: seeded with 0).
    statistic : callable or "pooled", optional
        ``statistic(values, groups) -> float`` of a resample; default the macro
        mean (mean over groups of the group means), computed for all resamples at once.
        ``"pooled"``: the mean over all resampled values (e.g. a share of trials),
        computed for all resamples at once, equal to ``lambda v, g: v.mean()``.
    draws : list of ndarray, optional
        The resamples, as returned by :func:`within_group_draws` for these
        ``groups``; pass them to reuse one set of resamples over many measures
        (``rng`` and ``n_boot`` are then unused).
    """
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return (float("nan"), float("nan"))
    groups = np.zeros(values.size, dtype=int) if groups is None else np.asarray(groups)
    if draws is None:
        rng = np.random.default_rng(0) if rng is None else rng
        draws = within_group_draws(groups, n_boot, rng)
    if statistic is None:
        samples = macro_mean_samples(values, draws)
    elif statistic == "pooled":
        samples = values[np.concatenate(draws, axis=1)].mean(axis=1)
    elif isinstance(statistic, str):
        raise ValueError(f"statistic: expected a callable or 'pooled', got {statistic!r}")
    else:
        picks = np.concatenate(draws, axis=1)
        samples = np.array([statistic(values[p], groups[p]) for p in picks])
    lo, hi = np.quantile(samples, [(1 - level) / 2, (1 + level) / 2])
    return float(lo), float(hi)


def within_group_draws(groups: Sequence, n_boot: int,
                       rng: np.random.Generator) -> list[np.ndarray]:
    """Bootstrap resamples within each group, one index matrix per group.

    Parameters
    ----------
    groups : sequence, shape (n,)
        Group (task) of each trial.
    n_boot : int
        Resamples.
    rng : numpy.random.Generator

    Returns
    -------
    list of ndarray, each shape (n_boot, n_g)
        For each group in sorted order, the indices (into ``groups``) drawn with
        replacement among that group's members. The draws are made resample by
        resample and group by group, so the same ``rng`` state always gives the
        same resamples whatever the values later measured on them.
    """
    groups = np.asarray(groups)
    members = [np.flatnonzero(groups == g) for g in np.unique(groups)]
    sizes = np.array([m.size for m in members], dtype=np.int64)
    # one call, in the order of resample by resample and group by group: each position
    # draws below its group's size, the same numbers as rng.choice(m, size=m.size) per
    # group and resample (Generator.integers with an array bound)
    picks = rng.integers(0, np.tile(np.repeat(sizes, sizes), n_boot))
    picks = picks.reshape(n_boot, int(sizes.sum()))
    ends = np.cumsum(sizes)
    return [m[picks[:, end - m.size:end]] for m, end in zip(members, ends)]


def macro_mean_samples(values: FloatArray, draws: list[np.ndarray]) -> FloatArray:
    """Macro mean (mean over groups of each group's mean) of every resample, shape (n_boot,)."""
    values = np.asarray(values, dtype=float)
    return np.stack([values[d].mean(axis=1) for d in draws], axis=1).mean(axis=1)


def resample_within(groups: Sequence, n_boot: int, rng: np.random.Generator) -> np.ndarray:
    """Bootstrap index matrix, shape (n_boot, n): trials drawn with replacement within
    each group (task), so every resample keeps the task sizes."""
    groups = np.asarray(groups)
    out = np.empty((n_boot, groups.size), dtype=int)
    for g in np.unique(groups):
        idx = np.flatnonzero(groups == g)
        out[:, idx] = idx[rng.integers(0, idx.size, size=(n_boot, idx.size))]
    return out


def curve_bootstrap(curves: FloatArray, groups: Sequence, *, n_boot: int = 1000,
                    level: float = 0.95, rng: np.random.Generator | None = None) -> dict:
    """Percentile intervals of a mean curve over trials and of its late decay.

    Parameters
    ----------
    curves : ndarray, shape (n_trials, C)
        Per trial, e.g. 1 where the task was recognised at each fraction of the motion.
    groups : sequence, shape (n_trials,)
        Task of each trial (resampled within).

    Returns
    -------
    dict
        ``mean`` (C,), ``lo``/``hi`` (C,) of the mean curve; ``decay`` (peak minus
        end of the mean curve) and ``decay_ci`` [lo, hi].
    """
    curves = np.asarray(curves, dtype=float)
    rng = np.random.default_rng(0) if rng is None else rng
    means = curves[resample_within(groups, n_boot, rng)].mean(axis=1)     # (n_boot, C)
    q = [(1 - level) / 2, (1 + level) / 2]
    lo, hi = np.quantile(means, q, axis=0)
    decay = means.max(axis=1) - means[:, -1]
    mean = curves.mean(axis=0)
    return {"mean": mean.tolist(), "lo": lo.tolist(), "hi": hi.tolist(),
            "decay": float(mean.max() - mean[-1]),
            "decay_ci": np.quantile(decay, q).tolist()}


"""Phase (speed) estimation from partial observations (paper eq. 10-13).

For task k the speed factor is :math:`\\alpha = T / T_{nom,k}` with prior
:math:`\\mathcal{N}(\\mu_\\alpha, \\sigma_\\alpha^2)`. Given observations up to
:math:`t_{last}`, the MAP estimate (eq. 13)

.. math::  \\alpha^* = \\arg\\max_\\alpha \\; \\log p(y | \\alpha, \\theta_k) + \\log p(\\alpha)

is found on a grid of at least ``n_candidates`` values over
:math:`\\mu_\\alpha \\pm w\\sigma_\\alpha` per task, refined by safeguarded
parabolic steps inside the bracket around the best grid point (a bounded 1-D
search). Candidates share one duration lattice across tasks, so each
candidate's factorisation serves all tasks (:mod:`sandbox.core.likelihood`).

A candidate shorter than the observations so far is not impossible: past its
end a motion holds its final state (:meth:`~sandbox.core.likelihood.Scorer.phases`),
so observations after T are scored against the motion's end. Earlier versions
excluded such candidates and, when no candidate was long enough, declared
the motion "ending now" at the last observation; on the recorded handovers,
whose recordings run on after the handover, that stretched every estimate
over the idle tail, misaligned the approach (where the tasks differ) and made
recognition fall in the last third of the motion (README, "late motion").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sandbox.core.interaction import LOG_2PI
from sandbox.core.likelihood import Scorer
from sandbox.core.limits import MAX_LATTICE_FLOATS
from sandbox.validation import FloatArray


@dataclass(frozen=True, eq=False)
class PhaseEstimate:
    """MAP speed of every task.

    Attributes
    ----------
    durations : ndarray, shape (K,)
        :math:`T^*_k = \\alpha^*_k T_{nom,k}` (s).
    alphas : ndarray, shape (K,)
    log_likelihood : ndarray, shape (K,)
        :math:`\\log p(y | \\alpha^*_k, \\theta_k)`.
    log_prior : ndarray, shape (K,)
        :math:`\\log p(\\alpha^*_k)`.
    factors : ndarray or None, shape (K, R+1, R+1)
        Augmented Cholesky factors at the MAP (joint mode), for conditioning.
    n_candidates : ndarray of int, shape (K,)
        Grid candidates each task evaluated (before refinement).
    grid : list of (ndarray, ndarray), optional
        Per task, its grid durations (s) and their posterior probabilities
        (normalised over the grid, prior included): what
        :func:`ended_probability` reads.
    """

    durations: FloatArray
    alphas: FloatArray
    log_likelihood: FloatArray
    log_prior: FloatArray
    factors: FloatArray | None
    n_candidates: np.ndarray
    grid: list | None = None


@dataclass(frozen=True)
class Lattice:
    """The duration lattice shared by all tasks: candidates are ``step * j`` (s).

    Task k's interval :math:`T_{nom,k}(\\mu_\\alpha \\pm w\\sigma_\\alpha)` holds the
    integers ``j_lo[k] .. j_hi[k]``; the step is the narrowest interval divided by
    ``n_candidates``, so every task gets at least ``n_candidates`` of them.
    """

    step: float
    j_lo: np.ndarray
    j_hi: np.ndarray

    @classmethod
    def for_tasks(cls, tasks, n_candidates: int = 50, width: float = 3.0) -> Lattice:
        """Lattice for a sequence of :class:`~sandbox.core.model.TaskModel`."""
        nominal = np.array([t.nominal_duration for t in tasks])
        mean = np.array([t.alpha_mean for t in tasks])
        std = np.array([t.alpha_std for t in tasks])
        lo = nominal * np.maximum(mean - width * std, 0.05)
        hi = nominal * (mean + width * std)
        if not np.all(hi > lo):
            raise ValueError(f"tasks: expected speed priors reaching above alpha=0.05, got "
                             f"means {mean.tolist()} and stds {std.tolist()} (width {width:g})")
        step = float(np.min(hi - lo) / n_candidates)
        if not (hi.max() - lo.min()) / step <= MAX_LATTICE_FLOATS:
            raise ValueError(f"tasks: their speed priors span {lo.min():g}-{hi.max():g} s in steps "
                             f"of {step:g} s: more candidates than limits.MAX_LATTICE_FLOATS; "
                             f"lower n_candidates or width")
        j_lo = np.ceil(lo / step - 1e-9).astype(np.int64)
        j_hi = np.floor(hi / step + 1e-9).astype(np.int64)
        return cls(step, j_lo, j_hi)

    @property
    def durations(self) -> FloatArray:
        """Every lattice duration any task uses, shape (C,)."""
        return np.arange(self.j_lo.min(), self.j_hi.max() + 1) * self.step

    def spans(self) -> np.ndarray:
        """Each task's candidates in :attr:`durations`, shape (K, 2): ``[start, stop)``."""
        base = self.j_lo.min()
        return np.stack([self.j_lo - base, self.j_hi - base + 1], axis=1)


def log_alpha_prior(alpha: FloatArray, mean: float | FloatArray,
                    std: float | FloatArray) -> FloatArray:
    """:math:`\\log\\mathcal{N}(\\alpha; \\mu_\\alpha, \\sigma_\\alpha^2)`."""
    u = (alpha - mean) / std
    return -0.5 * (u * u + LOG_2PI) - np.log(std)


def estimate_phase(scorer: Scorer, tasks, times: FloatArray, values: FloatArray, *,
                   n_candidates: int = 50, width: float = 3.0, refine_steps: int = 1,
                   mode: str = "joint", stats=None) -> PhaseEstimate:
    """MAP speed factor of every task given observations (eq. 11-13).

    Parameters
    ----------
    scorer : Scorer
    tasks : sequence of TaskModel
    times : ndarray, shape (s,)
        Observation times since the motion started (s), s >= 1.
    values : ndarray, shape (s, P)
        Observations (normalised units); NaN where a modality is not observed.
    n_candidates, width : see :func:`Lattice`.
    refine_steps : int
        Parabolic refinement steps after the grid (0: grid only).
    mode : {"joint", "marginal"}
        Joint likelihood of all observations, or product of per-step marginals.
    stats : StreamStatistics, optional
        Sufficient statistics of exactly these observations on the lattice
        (:mod:`sandbox.core.statistics`); used for the grid when given (joint mode).
    """
    if stats is not None and mode == "joint" and getattr(scorer, "post_var", None) is None:
        loglik, factors_of = stats.grid()                 # every task's pairs, one batch
        layout = stats.layout(tasks)
    else:
        lattice = Lattice.for_tasks(tasks, n_candidates, width)
        durations, spans = lattice.durations, lattice.spans()
        scores = (scorer.joint if mode == "joint" else scorer.marginal)(times, values,
                                                                         durations, spans)
        loglik = np.concatenate(scores.loglik)
        factors_of = _picker(None if scores.factors is None else np.concatenate(scores.factors))
        layout = GridLayout.of(tasks, durations, spans)
    nominal, a_mean, a_std = layout.nominal, layout.alpha_mean, layout.alpha_std
    lengths, starts, T, lp = layout.lengths, layout.starts, layout.T, layout.log_prior
    f = loglik + lp                               # eq. 11: log posterior (eq. 12 + prior)
    best = _argmax_per_task(f, starts, lengths)   # eq. 13
    w = np.exp(f - np.repeat(f[best], lengths))
    w /= np.repeat(np.add.reduceat(w, starts), lengths)
    grid = [(T[a:b], w[a:b]) for a, b in layout.cuts]
    best_T, best_ll, best_lp = T[best], loglik[best], lp[best]
    refined: dict = {}            # task -> the refinement's factor at its new best
    brackets = [None if i in (a, a + n - 1) else
                (T[i - 1], T[i], T[i + 1], f[i - 1], f[i], f[i + 1])
                for i, a, n in zip(best.tolist(), starts.tolist(), lengths.tolist())]
    pairs = scorer.joint_pairs if mode == "joint" else _marginal_pairs(scorer)
    for _ in range(refine_steps):
        brackets = _refine(pairs, times, values, tasks, brackets, nominal, a_mean, a_std,
                           best_T, best_ll, best_lp, refined)
    factors = _best_factors(factors_of, best, refined)
    return PhaseEstimate(best_T, best_T / nominal, best_ll, best_lp, factors, lengths, grid)


@dataclass(frozen=True, eq=False)
class GridLayout:
    """What the phase grid of :func:`estimate_phase` needs besides the likelihoods: it
    depends only on the tasks and the lattice, so a stream's statistics keep it
    (:meth:`~sandbox.core.statistics.StreamStatistics.layout`).

    Attributes
    ----------
    nominal, alpha_mean, alpha_std : ndarray, shape (K,)
        Each task's :math:`T_{nom}` (s) and speed prior.
    lengths, starts : ndarray of int, shape (K,)
        Each task's candidates and where they start in the packed grid.
    T : ndarray, shape (M,)
        The duration (s) of every packed (candidate, task) pair.
    log_prior : ndarray, shape (M,)
        :math:`\\log p(\\alpha)` of every pair (eq. 10).
    cuts : list of (int, int)
        Each task's ``[start, stop)`` in the packed grid.
    """

    nominal: FloatArray
    alpha_mean: FloatArray
    alpha_std: FloatArray
    lengths: np.ndarray
    starts: np.ndarray
    T: FloatArray
    log_prior: FloatArray
    cuts: list

    @classmethod
    def of(cls, tasks, durations: FloatArray, spans: np.ndarray) -> GridLayout:
        """The layout of ``tasks`` on the lattice ``durations`` (C,) with ``spans`` (K, 2)."""
        nominal = np.array([t.nominal_duration for t in tasks])
        a_mean = np.array([t.alpha_mean for t in tasks])
        a_std = np.array([t.alpha_std for t in tasks])
        lengths = spans[:, 1] - spans[:, 0]
        starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
        task_of = np.repeat(np.arange(len(tasks)), lengths)
        T = durations[np.arange(int(lengths.sum())) - np.repeat(starts - spans[:, 0], lengths)]
        lp = log_alpha_prior(T / nominal[task_of], a_mean[task_of], a_std[task_of])  # eq. 10
        cuts = list(zip(starts.tolist(), (starts + lengths).tolist()))
        for a in (nominal, a_mean, a_std, lengths, starts, T, lp):
            a.setflags(write=False)
        return cls(nominal, a_mean, a_std, lengths, starts, T, lp, cuts)


def _best_factors(factors_of, best: np.ndarray, refined: dict) -> FloatArray | None:
    """Each task's augmented factor (K, R+1, R+1) at its best duration: the refinement's
    where it moved the best (``refined``, task -> factor), else the grid's pair ``best[k]``
    from ``factors_of``, taken for those tasks only (with the kept factors each is a copy,
    and a refined task's would be thrown away: 160 demos per task, all four). None
    without factors (marginal likelihood)."""
    keep = np.array([k for k in range(best.size) if k not in refined], dtype=np.int64)
    grid = factors_of(best[keep])
    if grid is None or not refined:
        return grid
    some = next(iter(refined.values()))
    out = np.empty((best.size,) + some.shape, dtype=some.dtype)
    out[keep] = grid
    for k, factor in refined.items():
        out[k] = factor
    return out


def _picker(factors: FloatArray | None):
    """``index -> factors[index]`` (None without factors)."""
    return lambda index: None if factors is None else factors[index]


def _argmax_per_task(f: FloatArray, starts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Index in ``f`` of each segment's first maximum (as ``np.argmax`` of each segment)."""
    top = np.maximum.reduceat(f, starts)
    if not np.all(np.isfinite(top)):              # NaN or -inf scores: one segment at a time
        return np.array([a + int(np.argmax(f[a:a + n])) for a, n in zip(starts, lengths)])
    hits = np.flatnonzero(f == np.repeat(top, lengths))
    return hits[np.searchsorted(hits, starts)]


def ended_probability(grid, t: float) -> FloatArray:
    """Each task's posterior probability that its motion had ended by ``t`` (s), shape (K,).

    ``grid`` is :attr:`PhaseEstimate.grid` (the mass of the candidate durations <= t).
    """
    return np.array([w[T <= t].sum() for T, w in grid])


def _vertex(br) -> float | None:
    """Vertex of the parabola through a bracket, if it is a maximum inside it."""
    x0, x1, x2, f0, f1, f2 = br
    num = (x1 - x0) ** 2 * (f1 - f2) - (x1 - x2) ** 2 * (f1 - f0)
    den = (x1 - x0) * (f1 - f2) - (x1 - x2) * (f1 - f0)
    if den == 0 or not math.isfinite(num / den):
        return None
    x = x1 - 0.5 * num / den
    return float(x) if x0 < x < x2 and x != x1 else None


def _refine(score_pairs, times, values, tasks, brackets, nominal, a_mean, a_std,
            best_T, best_ll, best_lp, refined):
    trial = [(k, _vertex(br)) for k, br in enumerate(brackets) if br is not None]
    trial = [(k, x) for k, x in trial if x is not None]
    if not trial:
        return [None] * len(brackets)
    ks = np.array([k for k, _ in trial])
    xs = np.array([x for _, x in trial])
    lls, facs = score_pairs(times, values, xs, ks)
    lps = log_alpha_prior(xs / nominal[ks], a_mean[ks], a_std[ks])
    new: list[tuple | None] = [None] * len(brackets)
    for j, (k, x) in enumerate(trial):
        ll, lp = float(lls[j]), float(lps[j])
        x0, x1, x2, f0, f1, f2 = brackets[k]
        if ll + lp > f1:
            best_T[k], best_ll[k], best_lp[k] = x, ll, lp
            if facs is not None:
                refined[k] = facs[j]
            new[k] = (x0, x, x1, f0, ll + lp, f1) if x < x1 else (x1, x, x2, f1, ll + lp, f2)
        else:
            new[k] = (x, x1, x2, ll + lp, f1, f2) if x < x1 else (x0, x1, x, f0, f1, ll + lp)
    return new


def _marginal_pairs(scorer: Scorer):
    """Per-step-marginal scores of (duration, task) pairs, in the shape of ``joint_pairs``."""
    def score(times, values, durations, tasks):
        out = []
        for x, k in zip(durations, tasks):
            spans = np.zeros((scorer.K, 2), dtype=int)
            spans[k] = (0, 1)
            out.append(scorer.marginal(times, values, np.array([x]), spans).loglik[k][0])
        return np.array(out), None
    return score

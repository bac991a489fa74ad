"""The observation noise floor of each position modality, learned from the training demos.

``IProMP(noise_floor="auto")`` chooses the floor :math:`\\sigma_{min}` of every
position modality from a grid (:data:`GRID_M`, 2 mm to 40 mm; candidates below
the modality's measured jitter, :mod:`sandbox.core.jitter`, are raised to it) by
a held-out score computed from the training demos alone, inside the fit.

Why a held-out score. The floor stands for what a *new* demonstration departs
from the model by: its observed hand is not in the span of the few training
demos' weight covariance (:math:`UU^T + \\Lambda`, rank n - 1 plus a
regulariser), and trusting observations more than that departure warrants
pulls the posterior to a wrong robot goal and sharpens the task posterior
toward a wrong task. The demos' own basis-fit residuals (pooled in
:math:`\\Sigma_y`) cannot show it; leaving a demonstration out can.

The score. For every demonstration i of a task with at least three, its task's
weight distribution is refitted without it (the other tasks keep theirs), and
its human weights are observed at phases :math:`z = \\rho\\, j / (M - 1)`,
:math:`j = 0 \\ldots M-1`, for the prefix ratios :data:`RATIOS`, M being the
demo's valid samples within the prefix (so the balance between prior and data
is that of its own sampling rate). The score of a floor is the held-out log
predictive probability of the demo's task and robot goal given the prefix,

.. math::

    \\sum_i \\sum_\\rho \\log p(k_i \\mid y_{i,\\rho}) +
    \\log \\mathcal{N}(g_i \\mid \\mu_{g \\mid y}, \\Sigma_{g \\mid y}),

where :math:`p(k \\mid y) \\propto p(k)\\, \\mathcal{N}(y \\mid H\\mu_k, H\\Sigma_k H^T +
\\Sigma_y)` (eq. 12's marginal with the true phase), :math:`g_i` the robot's
final state (phase 1) and :math:`\\mu_{g|y}, \\Sigma_{g|y}` its Gaussian
conditional (eq. 7-9) under the demo's task. It is a proper score of both what
the predictors report: the task (recognition) and the goal (e_p). The demo's own
basis-fit residual (variance :math:`r_p` per dim, the part of a raw track the
weights drop) enters as its expectation, :math:`-\\tfrac12 \\mathrm{tr}(C^{-1}R)`
per task. Modalities are searched one after the other, each with the others
at their constant floors. Cost: at most :data:`MAX_HELD_OUT` demos per task are
held out, and each (demo, ratio, task) costs one eigendecomposition of a P N
square matrix (:mod:`sandbox.core.floorscore`), whatever M; a fit takes about 4
(174 demos) to 8 (30 demos) times as long as with a constant floor.

The true phase is used (no speed search). Measured on five sets (the recorded
handovers, the mocap fixture, three synthetic sessions; docs, "Bring your own
recordings"), the score rises with the floor through the grid's top on every one
(to 113-160 mm on a grid extended to 160 mm), and so does the same score computed
with the predictor's own speed search, held-out demos observed at unknown phase:
the conditioned task and goal distributions are overconfident, and a wider
prediction earns more than a wrong phase costs. So the choice is the grid's top,
40 mm, which bounds it; that is better than the constant 2 cm on four of those sets
but costs recognition on the recorded handovers, hence opt-in.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.fitting import by_task, observation_noise
from sandbox.core.floorscore import HeldOut
from sandbox.core.jitter import jitter_floors
from sandbox.core.promp import WeightDistribution
from sandbox.validation import FloatArray

#: Candidate floors (m): roughly geometric from the documented minimum (2 mm, twice a
#: motion-capture system's jitter) to 40 mm (twice the constant chosen for a Kinect).
GRID_M = (0.002, 0.003, 0.005, 0.007, 0.01, 0.014, 0.02, 0.028, 0.04)
#: Prefix ratios (observed fractions of each held-out motion) the score averages over.
RATIOS = (0.25, 0.5, 0.75)
#: The fewest demos a task needs for its demos to be held out (two stay to refit it).
MIN_TASK_DEMOS = 3
#: The most demos of one task held out (evenly spaced in the task's order).
MAX_HELD_OUT = 8


def candidates(jitter: float | None, grid: Sequence[float] = GRID_M) -> tuple[float, ...]:
    """The grid with every floor below ``jitter`` (m) raised to it, sorted, unique."""
    low = 0.0 if jitter is None or not np.isfinite(jitter) else float(jitter)
    return tuple(sorted({max(float(g), low) for g in grid}))


def held_out_set(weights: Mapping[str, FloatArray], dists: Mapping[str, WeightDistribution],
                 human_reg: FloatArray, counts: Mapping[str, FloatArray],
                 residual_var: Mapping[str, FloatArray], basis: GaussianBasis, P: int,
                 regularizer: float, log_prior: Mapping[str, float],
                 ratios: Sequence[float] = RATIOS) -> list[HeldOut]:
    """Every (held-out demo, ratio) of tasks with at least :data:`MIN_TASK_DEMOS` demos.

    Parameters
    ----------
    weights : mapping of str to ndarray, shape (n_k, (P+Q)*N)
        Each task's demo weights (human dims normalised).
    dists : mapping of str to WeightDistribution
        Each task's fitted distribution (the competitors of a held-out demo).
    human_reg : ndarray, shape (P,)
        The human dims' regulariser (the fit's, pooled over tasks: it does not depend on
        the floor, :mod:`sandbox.core.model`).
    counts : mapping of str to ndarray, shape (n_k,)
        Each demo's valid samples over its motion; a prefix of ratio rho holds
        rho x the task's median of them (one Gram matrix per task and ratio).
    residual_var : mapping of str to ndarray, shape (n_k, P)
        Each demo's own basis-fit residual variance (normalised units).
    """
    goal = basis.evaluate(np.array([1.0]))[0]
    out: list[HeldOut] = []
    cache: dict = {}
    for task, w in weights.items():
        if len(w) < MIN_TASK_DEMOS:
            continue
        others = {k: d for k, d in dists.items() if k != task}
        for i in held_out_demos(len(w)):
            rest = without_demo(w, i, regularizer, basis.n_basis, P, human_reg)
            for rho in ratios:
                M = int(max(3, round(rho * np.median(counts[task]))))
                psi = basis.evaluate(np.linspace(0.0, rho, M))
                out.append(HeldOut(rest, others, task, w[i], P, psi, goal,
                                   residual_var[task][i], log_prior, cache))
    return out


def without_demo(w: FloatArray, i: int, regularizer: float, n_basis: int, P: int,
                 human_reg: FloatArray) -> WeightDistribution:
    """The task's weight distribution refitted from its demos' weights ``w`` (n, D*N)
    without demo ``i``, its human regularisers (P,) set to ``human_reg``."""
    rest = WeightDistribution.from_weights(np.delete(w, i, axis=0), regularizer, n_basis)
    reg = rest.reg.copy()
    reg[:P] = human_reg
    return WeightDistribution(rest.mean, rest.factor, reg, n_basis)


def held_out_demos(n: int, most: int | None = None) -> FloatArray:
    """Which of a task's n demos are held out: all, or ``most`` (default
    :data:`MAX_HELD_OUT`) evenly spaced ones, so the cost stays bounded."""
    most = MAX_HELD_OUT if most is None else most
    return np.unique(np.round(np.linspace(0, n - 1, min(n, most))).astype(int))


def search(held: Sequence[HeldOut], sigma2_of, position: Sequence[tuple[str, slice]],
           start: Mapping[str, float], choices: Mapping[str, Sequence[float]]
           ) -> tuple[dict[str, float], dict[str, dict[float, float]]]:
    """Per position modality, the candidate floor with the highest total score.

    Parameters
    ----------
    held : sequence of HeldOut
    sigma2_of : callable
        Floors by modality name (m) -> observation variances, shape (P,).
    position : sequence of (name, dims)
        The position modalities, searched in this order.
    start : mapping of str to float
        The floors of the modalities not yet searched.
    choices : mapping of str to sequence of float
        Each modality's candidates (:func:`candidates`).

    Returns
    -------
    chosen : dict of str to float
    scores : dict of str to (dict of float to float)
        Each modality's total score per candidate (for reports).
    """
    floors, scores = dict(start), {}
    for name, _ in position:
        grid = list(choices[name])
        variances = np.array([sigma2_of({**floors, name: f}) for f in grid])
        totals = np.sum([h.score(variances) for h in held], axis=0)
        table = {f: float(t) for f, t in zip(grid, totals)}
        scores[name] = table
        floors[name] = max(table, key=lambda f: (table[f], f))
    return floors, scores


def auto_floors(fits: Sequence, modalities: Sequence, scale: FloatArray, floors: FloatArray,
                fixed: Sequence[str], noise_scale: float, regularizer: float,
                basis: GaussianBasis, priors: FloatArray | None = None
                ) -> tuple[FloatArray, dict[str, dict[float, float]]]:
    """The floors (P,) with every position modality's chosen by :func:`search`.

    Parameters
    ----------
    fits, modalities : sequences of DemoFit and of Modality
    scale : ndarray, shape (P,)
        Of the human dims (1 for positions).
    floors : ndarray, shape (P,)
        The floors of the dims not searched (and the start of those searched).
    fixed : sequence of str
        Modalities whose floor is given (``noise_floors``), not searched.
    noise_scale, regularizer : float
    basis : GaussianBasis
    priors : ndarray, shape (K,), optional
        Task priors in first-seen order of the tasks (uniform by default).

    Returns
    -------
    floors : ndarray, shape (P,)
    scores : dict of str to (dict of float to float)
        Each searched modality's score per candidate; empty if none was (no task has
        :data:`MIN_TASK_DEMOS` demos).
    """
    dims_of = _dims(modalities)
    position = [(m.name, dims_of[m.name]) for m in modalities
                if m.kind == "position" and m.name not in fixed]
    start = {name: float(floors[dims.start]) for name, dims in position}
    weights, _ = by_task(fits)
    if not position or max(len(w) for w in weights.values()) < MIN_TASK_DEMOS:
        return np.asarray(floors, dtype=np.float64), {}
    P, N = fits[0].residual.size, basis.n_basis
    divide = np.r_[scale, np.ones(fits[0].weights.size // N - P)].repeat(N)
    arrays = {k: np.array(v) / divide for k, v in weights.items()}
    dists = {k: WeightDistribution.from_weights(w, regularizer, N) for k, w in arrays.items()}
    human_reg = _pooled_human_reg(dists, modalities, P)
    counts, residual = _per_demo(fits, scale)
    p = np.full(len(arrays), 1.0 / len(arrays)) if priors is None else priors
    log_prior = {k: float(np.log(max(v, 1e-300))) for k, v in zip(arrays, np.asarray(p))}
    held = held_out_set(arrays, dists, human_reg, counts, residual, basis, P, regularizer,
                        log_prior)
    def sigma2_of(by_name: Mapping[str, float]) -> FloatArray:
        vector = np.array(floors, dtype=np.float64)
        for name, value in by_name.items():
            vector[dims_of[name]] = value
        return observation_noise(fits, scale, vector, noise_scale)

    jitter = _median_jitter(fits)
    choices = {name: candidates(np.nanmax(jitter[dims]) if np.isfinite(jitter[dims]).any()
                                else None) for name, dims in position}
    chosen, scores = search(held, sigma2_of, position, start, choices)
    out = np.array(floors, dtype=np.float64)
    for name, dims in position:
        out[dims] = chosen[name]
    return out, scores


def _dims(modalities: Sequence) -> dict[str, slice]:
    """Each modality's human dims."""
    out, at = {}, 0
    for m in modalities:
        out[m.name] = slice(at, at + m.size)
        at += m.size
    return out


def _per_demo(fits: Sequence, scale: FloatArray) -> tuple[dict, dict]:
    """By task, each demo's valid samples (n_k,) and basis-fit residual variance (n_k, P)."""
    counts: dict[str, list] = {}
    residual: dict[str, list] = {}
    for f in fits:
        counts.setdefault(f.task, []).append(float(f.moments[0].max()))
        residual.setdefault(f.task, []).append(f.residual / f.dof / scale**2)
    return ({k: np.array(v) for k, v in counts.items()},
            {k: np.array(v) for k, v in residual.items()})


def _pooled_human_reg(dists: Mapping[str, WeightDistribution], modalities: Sequence,
                      P: int) -> FloatArray:
    """Each human dim's regulariser as the fit sets it for equal floors within a modality:
    the mean over tasks and the modality's dims (:func:`~sandbox.core.fitting.task_models`)."""
    reg = np.mean([d.reg[:P] for d in dists.values()], axis=0)
    out, at = np.empty(P), 0
    for m in modalities:
        out[at:at + m.size] = reg[at:at + m.size].mean()
        at += m.size
    return out


def _median_jitter(fits: Sequence) -> FloatArray:
    """Median over demos of each human dim's jitter (m), shape (P,); NaN where unknown."""
    P = fits[0].residual.size
    rows = np.array([np.full(P, np.nan) if f.jitter is None else f.jitter for f in fits])
    known = np.isfinite(rows).any(axis=0)
    out = np.full(P, np.nan)
    out[known] = np.nanmedian(rows[:, known], axis=0)
    return out


#: The value of ``noise_floor`` that asks for the search.
AUTO = "auto"
#: Where the search starts (and what a modality keeps when no task has enough demos): the
#: constant chosen for a Kinect-class tracker (m).
START_FLOOR = 0.02


def check_noise_floor(value, check_floor) -> float | str:
    """``noise_floor``: :data:`AUTO`, or a floor checked by ``check_floor(value, name, bound)``."""
    if isinstance(value, str):
        if value != AUTO:
            raise ValueError(f"noise_floor: expected a number (m) or {AUTO!r}, got {value!r}")
        return AUTO
    return check_floor(value, "noise_floor", "noise_floor")


def model_floors(model, modalities: Sequence, fits: Sequence = (),
                 scale: FloatArray | None = None) -> FloatArray:
    """Noise floor of every human dim of ``model`` (an IProMP), normalised units, shape (P,).

    Positions: ``max(noise_floor, k x jitter)`` with ``jitter_floor`` k (``noise_floor``
    (m) when k is None or no jitter is known), or with ``noise_floor="auto"`` the floor
    :func:`auto_floors` learns from ``fits``
    (its scores kept as ``model.floor_scores``); signals: ``signal_floor``; and
    ``noise_floors[name]`` wins over all.
    """
    constant = START_FLOOR if model.noise_floor == AUTO else model.noise_floor
    out = np.array([constant if m.kind == "position" else model.signal_floor
                    for m in modalities for _ in range(m.size)])
    if model.jitter_floor is not None and fits and model.noise_floor != AUTO:
        jitters = np.array([np.full(out.size, np.nan) if f.jitter is None else f.jitter
                            for f in fits])
        out = jitter_floors(jitters, modalities, model.jitter_floor, constant, out)
    given = [model.noise_floors.get(m.name) for m in modalities for _ in range(m.size)]
    out = np.array([f if g is None else g for f, g in zip(out, given)])
    if model.noise_floor == AUTO and fits:
        scale = np.ones(out.size) if scale is None else scale
        out, model.floor_scores = auto_floors(
            fits, modalities, scale, out, tuple(model.noise_floors), model.noise_scale,
            model.regularizer, model.basis)
    return out

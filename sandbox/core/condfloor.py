"""A second observation noise floor for conditioning the robot, learned from the demos.

The observation noise :math:`\\Sigma_y` plays two roles: (1) in the likelihood of the
observations under each task and speed candidate (recognition and the phase search,
eq. 12-15) and (2) in conditioning the robot's part on the observed human part
(eq. 7-9: how far the observations pull the robot away from the prior mean).
``IProMP(condition_floor=...)`` gives role (2) its own floor, :math:`\\Sigma_c`;
role (1) keeps ``noise_floor``. ``None`` (the default) conditions with
:math:`\\Sigma_y`, as before; a number is a position floor (m); ``"auto"`` chooses
each position modality's floor from :data:`GRID_M` (raised to the modality's measured
jitter, as :mod:`sandbox.core.floorsearch` does) inside the fit.

The criterion is a point error a wider prediction cannot game: for every demo i of a
task with at least :data:`~sandbox.core.floorsearch.MIN_TASK_DEMOS` demos, the task's
weights are refitted without it, its human weights are observed at their true phases
over the prefixes :data:`~sandbox.core.floorsearch.RATIOS` (the demo's valid samples
within the prefix, 1 of :data:`SUBSAMPLE` kept, as the evaluation keeps them), and the
score of a floor is

.. math:: \\sum_i \\sum_\\rho \\lVert \\mu_{g \\mid y_{i,\\rho}} - g_i \\rVert^2,

:math:`g_i` the demo's robot goal (phase 1) and :math:`\\mu_{g|y}` its conditional mean
(eq. 7-9; :meth:`~sandbox.core.floorscore.HeldOut.goal_error`). A floor too small
follows the few demos' span (the new demo is not in it); too large, the prior
mean: the score has a finite minimum, the floor chosen. The cost is one
eigendecomposition of a P N square matrix per (held-out demo, ratio), whatever the
number of candidates. The predictors condition with :math:`\\Sigma_c`
(:class:`~sandbox.core.likelihood.Scorer`'s ``conditioner``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.fitting import by_task, observation_noise
from sandbox.core.floorscore import HeldOut
from sandbox.core.floorsearch import (
    AUTO,
    MIN_TASK_DEMOS,
    RATIOS,
    _dims,
    _median_jitter,
    _per_demo,
    _pooled_human_reg,
    candidates,
    without_demo,
)
from sandbox.core.promp import WeightDistribution
from sandbox.validation import FloatArray

#: Candidate conditioning floors (m): roughly geometric from 5 mm to 32 cm.
GRID_M = (0.005, 0.007, 0.01, 0.014, 0.02, 0.028, 0.04, 0.056, 0.08, 0.113, 0.16, 0.226,
          0.32)
#: 1 of this many valid samples of a held-out prefix is observed (the evaluation's
#: ``subsample``, :class:`~sandbox.eval.loocv.EvalConfig`).
SUBSAMPLE = 2


def check_condition_floor(value, check_floor) -> float | str | None:
    """``condition_floor``: None, :data:`~sandbox.core.floorsearch.AUTO`, or a floor (m)
    checked by ``check_floor(value, name, bound)``."""
    if value is None:
        return None
    if isinstance(value, str):
        if value != AUTO:
            raise ValueError(f"condition_floor: expected a number (m), {AUTO!r} or None, "
                             f"got {value!r}")
        return AUTO
    return check_floor(value, "condition_floor", "noise_floor")


def condition_noise(model, modalities: Sequence, fits: Sequence, scale: FloatArray,
                    floors: FloatArray) -> FloatArray | None:
    """The conditioning noise variances (P,) of ``model.condition_floor``, or None.

    ``floors`` (P,) are the fit's noise floors (normalised units): signal modalities and
    modalities given in ``noise_floors`` keep theirs. With ``"auto"`` the scores
    (squared goal error per candidate) are kept as ``model.condition_scores``.
    """
    choice = getattr(model, "condition_floor", None)
    if choice is None:
        return None
    out = np.array(floors, dtype=np.float64)
    dims_of = _dims(modalities)
    position = [(m.name, dims_of[m.name]) for m in modalities
                if m.kind == "position" and m.name not in model.noise_floors]
    if choice == AUTO:
        out, model.condition_scores = auto_condition_floors(
            fits, modalities, position, scale, out, model.noise_scale, model.regularizer,
            model.basis)
    else:
        for _, dims in position:
            out[dims] = choice
    return observation_noise(fits, scale, out, model.noise_scale)


def auto_condition_floors(fits: Sequence, modalities: Sequence,
                          position: Sequence[tuple[str, slice]],
                          scale: FloatArray, floors: FloatArray, noise_scale: float,
                          regularizer: float, basis: GaussianBasis) -> tuple[FloatArray, dict]:
    """Each position modality's floor with the least held-out goal error (module docstring).

    Returns the floors (P,) (``floors`` where nothing was searched) and, per searched
    modality, the total squared error (robot units squared) per candidate.
    """
    weights, _ = by_task(fits)
    out = np.array(floors, dtype=np.float64)
    if not position or max(len(w) for w in weights.values()) < MIN_TASK_DEMOS:
        return out, {}
    P, N = fits[0].residual.size, basis.n_basis
    divide = np.r_[scale, np.ones(fits[0].weights.size // N - P)].repeat(N)
    arrays = {k: np.array(v) / divide for k, v in weights.items()}
    dists = {k: WeightDistribution.from_weights(w, regularizer, N) for k, w in arrays.items()}
    human_reg = _pooled_human_reg(dists, modalities, P)
    counts, residual = _per_demo(fits, scale)
    held = _held_out(arrays, human_reg, counts, residual, basis, P, regularizer)
    jitter = _median_jitter(fits)
    scores = {}
    for name, dims in position:
        known = np.isfinite(jitter[dims]).any()
        grid = candidates(np.nanmax(jitter[dims]) if known else None, GRID_M)
        variances = []
        for f in grid:
            floor = out.copy()
            floor[dims] = f
            variances.append(observation_noise(fits, scale, floor, noise_scale))
        totals = np.sum([h.goal_error(np.array(variances)) for h in held], axis=0)
        scores[name] = {float(f): float(t) for f, t in zip(grid, totals)}
        out[dims] = min(scores[name], key=lambda f: (scores[name][f], f))
    return out, scores


def _held_out(arrays: dict, human_reg: FloatArray, counts: dict, residual: dict,
              basis: GaussianBasis, P: int, regularizer: float) -> list[HeldOut]:
    """Every (demo, ratio) of tasks with enough demos, each task refitted without it."""
    goal = basis.evaluate(np.array([1.0]))[0]
    out: list[HeldOut] = []
    for task, w in arrays.items():
        if len(w) < MIN_TASK_DEMOS:
            continue
        for i in range(len(w)):
            rest = without_demo(w, i, regularizer, basis.n_basis, P, human_reg)
            for rho in RATIOS:
                M = int(max(3, round(rho * np.median(counts[task]) / SUBSAMPLE)))
                psi = basis.evaluate(np.linspace(0.0, rho, M))
                out.append(HeldOut(rest, {}, task, w[i], P, psi, goal, residual[task][i],
                                   {task: 0.0}))
    return out

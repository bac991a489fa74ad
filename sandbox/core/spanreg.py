"""Each modality's weight regulariser raised to what a new demo departs from its task's span.

A task's weight covariance is its demos' sample covariance, of rank n - 1 (about
40 in the 21 x 9 human weight dims of the recorded handovers), plus the regulariser
:math:`\\Lambda` (:mod:`sandbox.core.model`: ``regularizer`` x the weights' variance,
1e-3). A new motion's deviation *outside* the span of the training demos is scored
against :math:`\\Lambda` and the white observation noise only, so a persistent offset
(a hand that stops short, an arm that drifts on after the meeting) accumulates
evidence with every sample, and the task posterior follows it (issue 21, item 4).

``IProMP(span_reg=...)`` raises modality m's regulariser to

.. math:: \\lambda_m = \\max(\\lambda_{m,0},\\; c_m\\, v_m),

:math:`\\lambda_{m,0}` today's, :math:`v_m` the **out-of-span variance** of m's
weights learned from the training demos (:func:`out_of_span_variance`): each demo
of a task with at least three is left out in turn, its deviation from the other
demos' mean is projected off their span, and the squared remainder is averaged
over m's weights and over the demos of every task. :math:`v_m` is the maximum
likelihood variance of an isotropic term for those departures, so :math:`c_m = 1`
is the empirical-Bayes estimate; smaller factors trust the span more.

The factor :math:`c_m` (``span_reg="auto"``) is chosen per modality from
:data:`GRID` by a held-out score computed from the training demos alone, inside the
fit: modality m observed **alone** (so the choice of one modality does not depend on
the others, as :math:`\\kappa_m` does not, :mod:`sandbox.core.model`), each held-out
demo's task refitted without it, its human weights observed at their true phases over
the prefixes :data:`RATIOS`, and the score is the held-out log probability of its
task, :math:`\\sum_i \\sum_\\rho \\log p(k_i \\mid y_{i,\\rho})`
(:class:`~sandbox.core.floorscore.HeldOut`, the noise floor's machinery with the
regulariser varied instead of the noise). The modality whose demos leave their span
by more in a way that misleads the held-out recognition gets the larger factor; a
modality whose span already tells the tasks apart keeps :math:`c_m = 0`, today's.
A number is one factor for every modality (a probe); ``None`` (the default) is
today's regulariser.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from sandbox.core.basis import GaussianBasis
from sandbox.core.floorscore import HeldOut, _equal, _general
from sandbox.core.floorsearch import MIN_TASK_DEMOS, _per_demo, held_out_demos
from sandbox.core.promp import WeightDistribution
from sandbox.limits import BOUNDS, check_factor
from sandbox.validation import FloatArray

#: The value of ``span_reg`` that asks for the search.
AUTO = "auto"
#: Candidate factors :math:`c_m` of the out-of-span variance (0: today's regulariser).
GRID = (0.0, 0.01, 0.03, 0.1, 0.3, 1.0)
#: Prefix ratios of the held-out score: the motion's early, middle and late parts and
#: the whole motion (where the late decay is).
RATIOS = (0.25, 0.5, 0.75, 1.0)
#: The largest factor a number may give (10 x the empirical-Bayes estimate).
MAX_FACTOR = BOUNDS["span_reg"].high
#: What a model loaded from a file written before ``span_reg`` says (its ``span_note``).
SPAN_NOTE = ("this model file predates span_reg: loaded with the weight regulariser alone "
             "(span_reg None, today's default)")


def check_span_reg(value) -> float | str | None:
    """``span_reg``: None, :data:`AUTO`, or a factor in [0, :data:`MAX_FACTOR`]
    (:func:`sandbox.limits.check_factor`)."""
    return check_factor("span_reg", value, AUTO)


def out_of_span_variance(weights: Mapping[str, FloatArray], rows: slice) -> float | None:
    """:math:`v_m`: mean squared departure per weight of a left-out demo from its task's
    other demos' span, over the weights ``rows`` (one modality's), pooled over the demos
    of every task with at least :data:`~sandbox.core.floorsearch.MIN_TASK_DEMOS`.

    Parameters
    ----------
    weights : mapping of str to ndarray, shape (n_k, D*N)
        Each task's demo weights (normalised units).
    rows : slice
        The modality's weights (its dims' N weights each).

    Returns
    -------
    float or None
        Normalised units squared; None when no task has enough demos.
    """
    out = []
    for w in weights.values():
        x = np.asarray(w, dtype=np.float64)[:, rows]
        if len(x) < MIN_TASK_DEMOS:
            continue
        out += [float(np.mean(r ** 2)) for r in left_out_residuals(x)]
    return float(np.mean(out)) if out else None


def left_out_residuals(x: FloatArray) -> FloatArray:
    """Each row of ``x`` (n, D) left out in turn: its departure from the other rows' mean,
    less its projection on their span (the right singular vectors above 1e-10 of the
    largest), shape (n, D). What the other demos' weight covariance cannot place of it."""
    out = np.empty_like(x)
    for i in range(len(x)):
        rest = np.delete(x, i, axis=0)
        mean = rest.mean(axis=0)
        _, s, vt = np.linalg.svd(rest - mean, full_matrices=False)
        span = vt[s > 1e-10 * max(float(s.max(initial=0.0)), 1e-300)]
        d = x[i] - mean
        out[i] = d - span.T @ (span @ d)
    return out


def span_floors(choice, weights: Mapping[str, FloatArray], modalities: Sequence,
                sigma2: FloatArray, regularizer: float, basis: GaussianBasis,
                counts: Mapping[str, FloatArray], residual: Mapping[str, FloatArray],
                log_prior: Mapping[str, float]) -> tuple[FloatArray | None, dict]:
    """The lower bound of each modality's regulariser (P,), normalised units, or None.

    Parameters
    ----------
    choice : None, float or "auto"
        ``IProMP.span_reg`` (:func:`check_span_reg`).
    weights : mapping of str to ndarray, shape (n_k, (P+Q)*N)
        Each task's demo weights (human dims normalised).
    modalities : sequence of Modality
    sigma2 : ndarray, shape (P,)
        The fit's observation noise variances (normalised units).
    regularizer : float
    basis : GaussianBasis
    counts, residual : mappings of str to ndarray
        By task, each demo's valid samples (n_k,) and basis-fit residual variance (n_k, P)
        (``sandbox.core.floorsearch._per_demo``).
    log_prior : mapping of str to float
        Log task priors.

    Returns
    -------
    floors : ndarray, shape (P,), or None
        :math:`c_m v_m` on every dim of modality m; None for ``choice`` None.
    report : dict
        Per modality: ``variance`` (:math:`v_m`), ``factor`` (:math:`c_m`) and, with
        ``"auto"``, ``scores`` (held-out log probability of the task per factor).
    """
    if choice is None:
        return None, {}
    P, N = sigma2.size, basis.n_basis
    out, report, at = np.zeros(P), {}, 0
    for m in modalities:
        dims = slice(at, at + m.size)
        at += m.size
        v = out_of_span_variance(weights, slice(dims.start * N, dims.stop * N))
        if v is None:
            report[m.name] = {"variance": None, "factor": 0.0}
            continue
        entry: dict = {"variance": v}
        if choice == AUTO:
            entry["scores"] = span_scores(weights, dims, v, sigma2, regularizer, basis,
                                          counts, residual, log_prior, GRID)
            factor = max(entry["scores"], key=lambda c: (entry["scores"][c], -c))
        else:
            factor = float(choice)
        entry["factor"] = float(factor)
        out[dims] = factor * v
        report[m.name] = entry
    return out, report


def span_scores(weights: Mapping[str, FloatArray], dims: slice, variance: float,
                sigma2: FloatArray, regularizer: float, basis: GaussianBasis,
                counts: Mapping[str, FloatArray], residual: Mapping[str, FloatArray],
                log_prior: Mapping[str, float], grid: Sequence[float] = GRID
                ) -> dict[float, float]:
    """Held-out log probability of the true task, modality ``dims`` observed alone, for
    each factor of ``grid`` (module docstring)."""
    N = basis.n_basis
    P_all = sigma2.size
    cols = np.r_[np.arange(dims.start * N, dims.stop * N),
                 np.arange(P_all * N, next(iter(weights.values())).shape[1])]
    sub = {k: np.asarray(w, dtype=np.float64)[:, cols] for k, w in weights.items()}
    P = dims.stop - dims.start
    s2 = np.asarray(sigma2[dims], dtype=np.float64)
    base = {k: WeightDistribution.from_weights(w, regularizer, N) for k, w in sub.items()}
    pooled = float(np.mean([d.reg[:P].mean() for d in base.values()]))
    goal = basis.evaluate(np.array([1.0]))[0]
    out = {}
    for c in grid:
        human_reg = max(pooled, c * variance) * s2 / s2.mean()
        dists = {k: _with_human_reg(d, human_reg, P) for k, d in base.items()}
        total = 0.0
        for task, w in sub.items():
            if len(w) < MIN_TASK_DEMOS:
                continue
            cache: dict = {}     # the other tasks' parts, per prefix length
            others = {k: d for k, d in dists.items() if k != task}
            for i in held_out_demos(len(w)):
                rest = _with_human_reg(WeightDistribution.from_weights(
                    np.delete(w, i, axis=0), regularizer, N), human_reg, P)
                for rho in RATIOS:
                    M = int(max(3, round(rho * np.median(counts[task]))))
                    psi = basis.evaluate(np.linspace(0.0, rho, M))
                    held = HeldOut(rest, others, task, w[i], P, psi, goal,
                                   residual[task][i][dims], log_prior, cache)
                    total += task_log_prob(held, s2)
        out[float(c)] = total
    return out


def task_log_prob(held: HeldOut, sigma2: FloatArray) -> float:
    """:math:`\\log p(k_i \\mid y)` of one held-out demo and prefix (eq. 12's marginal at the
    true phase), for observation variances ``sigma2`` (P,): the task part of
    :meth:`HeldOut.score <sandbox.core.floorscore.HeldOut.score>`."""
    inv = 1.0 / np.asarray(sigma2, dtype=np.float64)[None]
    equal = bool(np.all(inv == inv[:, :1]))
    logs = {}
    for name, part in held.parts.items():
        quad, logdet_b, trace, _ = (_equal if equal else _general)(inv, part, None)
        logdet = -held.M * np.log(inv).sum(axis=1) + logdet_b
        logs[name] = float((part[3] - 0.5 * (quad + logdet + (held.M * inv + trace) @ held.r))[0])
    values = np.array(list(logs.values()))
    top = values.max()
    return logs[held.task] - float(top + np.log(np.exp(values - top).sum()))


def model_span(model, modalities: Sequence, weights: Mapping[str, FloatArray],
               sigma2: FloatArray, fits: Sequence, scale: FloatArray) -> FloatArray | None:
    """:func:`span_floors` of ``model.span_reg`` (an IProMP) from its training ``fits``
    (``scale``, shape (P,), of the human dims; uniform task priors, as
    :func:`~sandbox.core.floorsearch.auto_floors`); the report is kept as
    ``model.span_report``."""
    if getattr(model, "span_reg", None) is None:     # the default: no per-demo work at fit
        model.span_report = {}
        return None
    counts, residual = _per_demo(fits, scale)
    p = np.full(len(weights), 1.0 / len(weights))
    log_prior = {k: float(np.log(v)) for k, v in zip(weights, p)}
    floors, model.span_report = span_floors(
        getattr(model, "span_reg", None), weights, modalities, sigma2, model.regularizer,
        model.basis, counts, residual, log_prior)
    return floors


def _with_human_reg(dist: WeightDistribution, human_reg: FloatArray, P: int
                    ) -> WeightDistribution:
    """``dist`` with its first P dims' regulariser set to ``human_reg``."""
    reg = dist.reg.copy()
    reg[:P] = human_reg
    return WeightDistribution(dist.mean, dist.factor, reg, dist.n_basis)

"""Observations past a motion's end scored with a held offset learned from the demos.

Past a candidate's end (t > T, :meth:`~sandbox.core.likelihood.Scorer.phases`) a
motion holds its final state, and each observation there is scored as that state
plus white noise :math:`\\sigma_p^2`. The post-meeting part of a recording (the hand
waiting short of the meeting point, lingering, drifting back; an arm that stays
where it overshot) departs from the motion's final state by an *offset held over
many samples*: scored sample by sample, the n samples of one held offset count as
n independent pieces of evidence, and a tail's persistent offset pulls the task
posterior further with every update (issue 21, item 4; the sixth pass: the arm's
log odds for the true task grew from -4.8 to -13.3 nats over an overshooting tail).

``IProMP(post_end=c)`` models the n observations a candidate has past its end as

.. math:: y_{jp} = \\phi(1)^T w_p + b_p + e_{jp}, \\quad
          b_p \\sim \\mathcal{N}(0, s_m^2), \\; e_{jp} \\sim \\mathcal{N}(0, \\sigma_p^2),

one offset :math:`b_p` shared by the samples, with :math:`s_m^2 = c\\, v_m` and
:math:`v_m` the **post-end offset variance** of modality m learned from the training
demos (:func:`post_end_variance`): the mean over the demos and m's dims of the
squared mean departure of a demo's samples after its motion's end (its recording's
tail, which the fit otherwise drops) from its value at the end. ``c = 1`` is that
estimate; ``c = 0`` is today's likelihood exactly. ``post_end="span"`` takes
:math:`s_m^2 = v_m + u_m`, :math:`u_m` the end state's out-of-span variance
(:func:`end_span_variance`): a new trial's held samples depart from the model's end state,
which its task's demos place only within their span (issue 21, ninth pass).

This is still a likelihood of every observation (so candidates of different
durations stay comparable): the post-end samples' scatter about their own mean is
scored as before, and their mean :math:`\\bar y_p` as **one** observation of the
final state with variance :math:`s_m^2 + \\sigma_p^2/n`, i.e. as

.. math:: n_{eff} = 1 / (\\rho_m + 1/n), \\quad \\rho_m = s_m^2 / \\bar\\sigma_m^2

observations at the end phase (:math:`\\bar\\sigma_m^2` the mean noise variance of m's
dims), plus :math:`\\tfrac12\\log(n_{eff}/n)` per dim, the determinant of
:math:`\\sigma^2(I + \\rho\\,11^T)`. :func:`adjust` rewrites the sufficient
statistics of the likelihood's factorisation (:math:`G = \\Psi^T\\Psi`,
:math:`\\Psi^T y`, :math:`y^Ty`, :mod:`sandbox.core.likelihood`) accordingly; the robot
is conditioned (eq. 8) on the same statistics, so a tail moves the predicted end
pose by at most what one observation would.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core.fitting import DemoFit
from sandbox.limits import BOUNDS, check_factor
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.likelihood import Scorer
    from sandbox.core.model import IProMP

#: The largest factor ``post_end`` may be (10 x the learned offset variance).
MAX_FACTOR = BOUNDS["post_end"].high
#: The ``post_end`` that adds the end state's out-of-span variance (:func:`end_span_variance`)
#: to the tail's (factor 1 on both: issue 21, ninth pass).
SPAN = "span"


def check_post_end(value) -> float | str | None:
    """``post_end``: None (today's likelihood), a factor in [0, :data:`MAX_FACTOR`] or
    :data:`SPAN` (:func:`sandbox.limits.check_factor`)."""
    return check_factor("post_end", value, SPAN)


def check_post_var(meta: dict, n_modalities: int) -> list | None:
    """A model file's ``post_var`` (``n_modalities`` non-negative numbers), which it must
    have exactly when its hyperparameters set ``post_end``; None when it has neither."""
    value, factor = meta.get("post_var"), meta["hyperparameters"].get("post_end")
    if value is None and factor is None:
        return None
    ok = isinstance(value, list) and len(value) == n_modalities and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v < np.inf
        for v in value)
    if not ok or factor is None:
        raise ValueError(f"metadata post_var: expected {n_modalities} non-negative numbers "
                         f"with post_end set, got {str(value)[:60]} (post_end {factor!r})")
    return value


def demo_offsets(human: FloatArray, end: int) -> tuple[FloatArray, int]:
    """Mean departure of one demo's samples after its motion's end from its value there.

    Parameters
    ----------
    human : ndarray, shape (T, P)
        The whole recording's human dims (raw units), NaN where missing.
    end : int
        Index of the motion's last sample (:func:`~sandbox.core.fitting.motion_end`).

    Returns
    -------
    offset : ndarray, shape (P,)
        :math:`\\bar y_p - y_p(\\text{end})` over the finite samples after ``end`` (raw
        units; NaN where a dim has none or no finite value up to ``end``).
    n : int
        Samples after the end.
    """
    motion, tail = human[: end + 1], human[end + 1:]
    P = human.shape[1]
    offset = np.full(P, np.nan)
    for p in range(P):
        seen = np.flatnonzero(np.isfinite(motion[:, p]))
        after = tail[np.isfinite(tail[:, p]), p]
        if seen.size and after.size:
            offset[p] = after.mean() - motion[seen[-1], p]
    return offset, int(tail.shape[0])


def post_end_variance(offsets: Sequence[FloatArray | None], scale: FloatArray,
                      modality_sizes: Sequence[int]) -> FloatArray:
    """:math:`v_m`: mean squared post-end offset per modality (normalised units squared).

    Parameters
    ----------
    offsets : sequence of ndarray, shape (P,), or None
        Each training demo's :func:`demo_offsets` (raw units; None or NaN: no tail).
    scale : ndarray, shape (P,)
        The model's normalisation of the human dims (values are divided by it).
    modality_sizes : sequence of int
        Dims per modality, in order (summing to P).

    Returns
    -------
    ndarray, shape (n_modalities,)
        0 for a modality no demo has a tail of.
    """
    rows = [o for o in offsets if o is not None]
    out = np.zeros(len(modality_sizes))
    if not rows:
        return out
    z = np.asarray(rows, dtype=np.float64) / np.asarray(scale, dtype=np.float64)
    bounds = np.cumsum([0, *modality_sizes])
    for m in range(len(modality_sizes)):
        block = z[:, bounds[m]:bounds[m + 1]]
        ok = np.isfinite(block)
        out[m] = float((block[ok] ** 2).mean()) if ok.any() else 0.0
    return out


def adjust(G: FloatArray, beta: FloatArray, yy: FloatArray, psi: FloatArray,
           y: FloatArray, post: np.ndarray, rho: float):
    """The likelihood's statistics with the post-end samples' mean counted n_eff times.

    Parameters
    ----------
    G : ndarray, shape (C, N, N)
        :math:`\\Psi^T\\Psi` of the rows a group observes, per candidate.
    beta : ndarray, shape (C, N, Pg)
        :math:`\\Psi^T y`.
    yy : ndarray, shape (Pg,)
        :math:`y^T y` per dim.
    psi : ndarray, shape (C, s, N)
        The basis at those rows' phases (rows past a candidate's end: :math:`\\phi(1)`).
    y : ndarray, shape (s, Pg)
    post : ndarray of bool, shape (C, s)
        Rows past each candidate's end.
    rho : float
        :math:`\\rho_m = s_m^2/\\bar\\sigma_m^2` (module docstring), >= 0.

    Returns
    -------
    G, beta : as given, adjusted (new arrays).
    yy : ndarray, shape (C, Pg)
    logdet : ndarray, shape (C,)
        :math:`\\log(1 + \\rho n)` per dim of the group (added to each dim's log-determinant).
    """
    n = post.sum(axis=1).astype(np.float64)                      # (C,)
    C = G.shape[0]
    if rho <= 0.0 or not n.any():
        return G, beta, np.broadcast_to(yy, (C, yy.size)), np.zeros(C)
    has = n > 0
    n_eff = np.where(has, 1.0 / (rho + 1.0 / np.maximum(n, 1.0)), 0.0)
    last = np.argmax(post, axis=1)                               # a post-end row, if any
    phi = psi[np.arange(C), last]                                # (C, N): phi(1) where has
    total = post.astype(np.float64) @ y                          # (C, Pg): sum of post rows
    mean = total / np.maximum(n, 1.0)[:, None]
    dn = np.where(has, n_eff - n, 0.0)
    G2 = G + dn[:, None, None] * (phi[:, :, None] * phi[:, None, :])
    ratio = np.where(has, n_eff / np.maximum(n, 1.0) - 1.0, 0.0)
    beta2 = beta + phi[:, :, None] * (ratio[:, None] * total)[:, None, :]
    yy2 = yy[None, :] + dn[:, None] * mean**2
    return G2, beta2, yy2, np.log1p(rho * n)


def active(model) -> FloatArray | None:
    """``model.post_var`` when it has one above 0, else None: today's likelihood, on today's
    paths (the compiled pair statistics, a stream's incremental grid), to the bit."""
    v = getattr(model, "post_var", None)
    return None if v is None or not np.any(np.asarray(v) > 0) else np.asarray(v, dtype=float)


def post_rows(scorer: Scorer, times: FloatArray, durations: FloatArray) -> np.ndarray | None:
    """Rows past each candidate's end, shape (C, s), when ``scorer`` has post-end offset
    variances (:func:`active`); else None (today's path)."""
    if scorer.post_var is None:
        return None
    return np.asarray(times)[None, :] > np.asarray(durations)[:, None]


def statistics(scorer: Scorer, psi: FloatArray, ys: list, post: np.ndarray | None,
               rows: np.ndarray, first: int):
    """:math:`G`, :math:`\\Psi^T y`, :math:`y^T y` of groups observed on the same rows, and
    the log-determinant to add per dim (:func:`adjust` when ``post`` is given).

    Parameters
    ----------
    scorer : Scorer
    psi : ndarray, shape (C, s', N)
        The basis at the rows the groups observe.
    ys : list of ndarray, shape (s', Pg)
        Each group's values at those rows.
    post : ndarray of bool, shape (C, s), or None
        :func:`post_rows` over every row.
    rows : ndarray of bool, shape (s,)
        The rows the groups observe.
    first : int
        Index of the first group (all of one modality when ``post`` is given).
    """
    ps_t = psi.transpose(0, 2, 1)
    G = ps_t @ psi
    betas = [ps_t @ y for y in ys]
    yys = [np.einsum("sp,sp->p", y, y) for y in ys]
    if post is None:
        return G, betas, yys, 0.0
    g, var = scorer.groups[first], np.asarray(scorer.post_var)
    rho = float(var[g.modality]) / float(scorer.sigma2[g.dims].mean())
    out = [adjust(G, b, q, psi, y, post[:, rows], rho) for b, q, y in zip(betas, yys, ys)]
    return out[0][0], [o[1] for o in out], [o[2] for o in out], out[0][3]


@dataclass(frozen=True, eq=False)
class TailFit(DemoFit):
    """A :class:`~sandbox.core.fitting.DemoFit` with its recording's post-end offset.

    Attributes
    ----------
    tail : ndarray, shape (P,), or None
        :func:`demo_offsets` (raw units), None when the recording ends with its motion.
    """

    tail: FloatArray | None = None


def with_tail(fit: DemoFit, human: FloatArray, end: int) -> TailFit:
    """``fit`` with the post-end offset of its recording ``human`` (T, P) cut at ``end``."""
    offset, n = demo_offsets(human, end)
    fields = {f.name: getattr(fit, f.name) for f in dataclasses.fields(DemoFit)}
    return TailFit(**fields, tail=offset if n else None)


def end_span_variance(fits: Sequence[DemoFit], scale: FloatArray, end: FloatArray,
                      modality_sizes: Sequence[int]) -> FloatArray:
    """:math:`u_m`: mean squared departure of a left-out demo's **end state** from its task's
    other demos' span, per modality (normalised units squared).

    Each demo of a task with at least :data:`~sandbox.core.floorsearch.MIN_TASK_DEMOS` is
    left out in turn; its human weights' deviation from the other demos' mean is projected
    off their span within modality m's weights (as
    :func:`~sandbox.core.spanreg.out_of_span_variance` does), and the remainder is taken to
    the end phase, :math:`\\phi(1)^T r_p` per dim: what the other demos' weight covariance
    cannot place of where this demo's motion ended. The squares are averaged over m's dims
    and the demos of every task (0 when no task has enough demos).

    Parameters
    ----------
    fits : sequence of DemoFit
    scale : ndarray, shape (P,)
        The normalisation of the human dims.
    end : ndarray, shape (N,)
        The basis at phase 1, :math:`\\phi(1)`.
    modality_sizes : sequence of int
        Dims per modality, in order (summing to P).
    """
    from sandbox.core.fitting import by_task
    from sandbox.core.floorsearch import MIN_TASK_DEMOS
    from sandbox.core.spanreg import left_out_residuals

    N, P = end.size, int(np.sum(modality_sizes))
    bounds = np.cumsum([0, *modality_sizes]) * N
    divide = np.repeat(np.asarray(scale, dtype=np.float64), N)
    sums, counts = np.zeros(len(modality_sizes)), np.zeros(len(modality_sizes))
    for w in by_task(fits)[0].values():
        x = np.asarray(w, dtype=np.float64)[:, : P * N] / divide
        if len(x) < MIN_TASK_DEMOS:
            continue
        for m in range(len(modality_sizes)):
            for res in left_out_residuals(x[:, bounds[m]:bounds[m + 1]]):
                r = res.reshape(-1, N) @ end                            # (dims of m,)
                sums[m] += float(r @ r)
                counts[m] += r.size
    return np.divide(sums, counts, out=np.zeros_like(sums), where=counts > 0)


def model_post_var(model: IProMP, fits: Sequence[DemoFit], scale: FloatArray
                   ) -> FloatArray | None:
    """:math:`s_m^2` per modality of ``model`` from the training fits (module docstring):
    :math:`c\\, v_m` for a factor ``post_end`` c, :math:`v_m + u_m` for :data:`SPAN`
    (:func:`end_span_variance`); None when ``post_end`` is None."""
    if model.post_end is None:
        return None
    sizes = [m.size for m in model.modalities]
    v = post_end_variance([getattr(f, "tail", None) for f in fits], scale, sizes)
    if model.post_end == SPAN:
        end = np.asarray(model.basis.evaluate(np.array([1.0])), dtype=np.float64)[0]
        return v + end_span_variance(fits, scale, end, sizes)
    return float(model.post_end) * v

"""Fast exact likelihoods of partial human observations for many speeds and tasks.

For task k and a candidate duration T (phase :math:`z_j = \\min(t_j / T, 1)`: past
its end a motion holds its final state), the human
observations :math:`y \\in \\mathbb{R}^{sP}` have the marginal (eq. 12, 15)

.. math::  y \\sim \\mathcal{N}(\\Phi\\mu_h, \\; \\Phi(\\Lambda_h + U_hU_h^T)\\Phi^T + R),
           \\quad \\Phi = I_P \\otimes \\Psi, \\; R = \\Sigma_y \\otimes I_s .

Computed densely this is an sP x sP Cholesky per (candidate, task) pair. Here:

1. :math:`B = \\Phi\\Lambda_h\\Phi^T + R` is block diagonal with blocks
   :math:`\\sigma_p^2 (I + \\kappa_m\\Psi_m\\Psi_m^T)`, where :math:`\\Psi_m` holds the
   rows at which dim p's modality m is observed (a modality missing from a row
   has no rows there: the masked rows of H, eq. 9, never a filled-in value).
   With the model's :math:`\\kappa_m = \\lambda_p/\\sigma_p^2` shared by a modality's
   dims, one N x N Cholesky of :math:`A_m = I + \\kappa_m G_m`,
   :math:`G_m = \\Psi_m^T\\Psi_m`, per candidate and modality serves every dim of
   the modality and every task (push-through identity:
   :math:`\\Psi_m^T B_p^{-1}\\Psi_m = (G_m - \\kappa_m G_m A_m^{-1} G_m)/\\sigma_p^2`).
   The cost grows with N and the number of modalities, not with s or P.
2. The low-rank part :math:`U_h` (rank r = n_demos - 1) enters through the
   r x r matrix :math:`K = I + U_h^T\\Phi^T B^{-1}\\Phi U_h` (Woodbury and the
   determinant lemma); its entries for all candidates of a task come out of two
   large matrix products.
3. One batched Cholesky of the augmented matrix
   :math:`\\begin{bmatrix} K & e \\\\ e^T & d^T B^{-1} d\\end{bmatrix}`,
   :math:`d = y - \\Phi\\mu_h`, :math:`e = U_h^T\\Phi^T B^{-1} d`, gives
   :math:`\\log|K|` from its first r pivots and the Mahalanobis term
   :math:`d^T S^{-1} d = d^TB^{-1}d - e^T K^{-1} e` from the last.

The same factor conditions the robot weights for free (see
:func:`~sandbox.core.factor.condition_robot`): :math:`\\mu_r' = \\mu_r + U_r K^{-1} e`,
:math:`\\Sigma_r' = \\Lambda_r + U_r K^{-1} U_r^T`.

The per-step alternative (``mode="marginal"``) multiplies the marginals of each
observation instead, as older public code does.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from sandbox.core import posthold
from sandbox.core.factor import b_parts, factor_scores
from sandbox.core.interaction import LOG_2PI
from sandbox.core.pairstats import pack_groups, pair_kernel, pair_statistics
from sandbox.core.promp import WeightDistribution
from sandbox.core.rest import start_distribution
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.model import IProMP


@dataclass(frozen=True, eq=False)
class Scores:
    """Log-likelihoods of (candidate, task) pairs.

    Attributes
    ----------
    loglik : list of ndarray
        ``loglik[k]`` has one entry per candidate in task k's span.
    factors : list of ndarray or None
        ``factors[k]`` (C_k, R+1, R+1): Cholesky factors of the augmented matrix
        (joint mode only), for :func:`~sandbox.core.factor.condition_robot`.
    """

    loglik: list
    factors: list | None


@dataclass(frozen=True, eq=False)
class Group:
    """Human dims that share an observation mask and a regulariser ratio.

    Attributes
    ----------
    dims : ndarray of int
        Human dims of the group (all of one modality).
    modality : int
        Index of that modality; its rows are present where all its dims are finite.
    kappa : float
        :math:`\\kappa = \\lambda_p/\\sigma_p^2` of the group's dims.
    member : ndarray of bool, shape (K, n_dims)
        Whether task k's dim has this kappa (all True for a fitted model).
    blocks : ndarray, shape (K, N, n_dims, R+1)
        Every task's :math:`[U_{kp}, \\mu_{kp}]/\\sigma_p` of the group's dims, in the
        padded layout (U in the first r_k columns, zeros up to R, mean at R).
    """

    dims: np.ndarray
    modality: int
    kappa: float
    member: np.ndarray
    blocks: FloatArray


def _robot_view(model: IProMP) -> IProMP:
    """A shallow copy of ``model`` whose tasks' weights are their robot-conditioning ones."""
    view = copy.copy(model)
    view.task_models = tuple(replace(t, weights=t.robot or t.weights, robot=None)
                             for t in model.task_models)
    return view


def _conditioner(scorer: Scorer, model: IProMP) -> Scorer:
    """The scorer that conditions the robot (see :attr:`Scorer.conditioner`)."""
    noise = getattr(model, "condition_noise", None)
    robot = any(t.robot is not None for t in model.task_models)
    if noise is None and not robot:
        return scorer
    return Scorer(_robot_view(model) if robot else model,
                  model.noise if noise is None else noise)


class Scorer:
    """Precomputed, per fitted model, everything the likelihood needs.

    The human dims are split into :class:`Group` s: dims of one modality (so
    they are observed together) with one :math:`\\kappa` (one per modality for
    every model :meth:`~sandbox.core.model.IProMP.fit` makes). Each group needs
    its own N x N factorisation per candidate; the r x r part is shared.

    Parameters
    ----------
    model : IProMP
        A fitted model.
    noise : ndarray, shape (P,), optional
        Observation variances instead of ``model.noise``.

    Attributes
    ----------
    conditioner : Scorer
        What conditions the robot (eq. 7-9): a scorer of the tasks' robot weights
        (``shrinkage="robot"``, :attr:`~sandbox.core.fitting.TaskModel.robot`) and of
        ``model.condition_noise`` (:mod:`sandbox.core.condfloor`), or this one when the
        model has neither.
    """

    def __init__(self, model: IProMP, noise: FloatArray | None = None) -> None:
        model._require_fit()
        self.basis = model.basis
        P, N = model.n_human, model.basis.n_basis
        self.P, self.N, self.K = P, N, len(model.task_models)
        self.sigma2 = np.asarray(model.noise if noise is None else noise, dtype=np.float64)
        self.log_sigma2 = np.log(self.sigma2)
        self.start_mean, self.start_var = start_distribution(model)   # the rest hypothesis
        #: Each task's weights with the factor's columns turned so that the human block
        #: spans the first ``rank[k]`` (:func:`compress_human`); the same distribution.
        self.weights, self.rank = zip(*[compress_human(t.weights, P) for t in model.task_models])
        self.R = max(self.rank)
        self.reg_h = np.array([t.weights.reg[:P] for t in model.task_models])  # (K, P)
        sizes = [m.size for m in model.modalities]
        self.modality_dims = np.split(np.arange(P), np.cumsum(sizes)[:-1])
        pad = np.zeros((self.K, N, P, self.R + 1))
        raw = []
        for k in range(self.K):
            ut = _human_block(self.weights[k], P, N, self.rank[k])   # (P, N, r+1): [U_h, mu_h]
            raw.append(ut)
            scaled = (ut / np.sqrt(self.sigma2)[:, None, None]).transpose(1, 0, 2)
            pad[k, :, :, : self.rank[k]] = scaled[..., :-1]
            pad[k, :, :, self.R] = scaled[..., -1]
        self._raw = raw
        kappa = self.reg_h / self.sigma2                          # (K, P)
        self.groups = _make_groups(kappa, self.modality_dims, pad)
        self._packed = pack_groups(self.groups, self.sigma2, self.log_sigma2)   # pairstats.py
        self.post_var = posthold.active(model)   # posthold.py (None: today's likelihood)
        self.conditioner = self if noise is not None else _conditioner(self, model)
        pair_kernel(self.R + 1)     # numba's kernels loaded now, not in an update

    @property
    def kappas(self) -> list[float]:
        """:math:`\\kappa` of every group."""
        return [g.kappa for g in self.groups]

    def present(self, values: FloatArray) -> np.ndarray:
        """Which modalities each row observes, shape (n_modalities, s): all dims finite."""
        ok = np.isfinite(values)
        return np.stack([ok[:, d].all(axis=1) for d in self.modality_dims])

    def phases(self, times: FloatArray, durations: FloatArray) -> FloatArray:
        """Basis at :math:`z = \\min(t/T, 1)` for every candidate, shape (C, s, N).

        Past its end (t > T) a motion holds its final state.
        """
        return self.basis.evaluate(np.minimum(times[None, :] / durations[:, None], 1.0))

    def _group_parts(self, psi: FloatArray, values: FloatArray, post=None):
        """Per group: :func:`~sandbox.core.factor.b_part` of the rows observing it and the
        likelihood's constant per dim; ``post`` (C, s): rows past each candidate's end,
        scored by :func:`sandbox.core.posthold.adjust` (None: as every other row)."""
        present = self.present(values)
        out: list[tuple | None] = [None] * len(self.groups)
        shared: dict[bytes, list[int]] = {}       # groups observed on the same rows share G
        for i, g in enumerate(self.groups):
            rows = present[g.modality]
            if rows.any():
                key = rows.tobytes() + (b"" if post is None else str(g.modality).encode())
                shared.setdefault(key, []).append(i)
        for members in shared.values():
            rows = present[self.groups[members[0]].modality]
            ps = psi if rows.all() else psi[:, rows]
            ys = [values[rows][:, self.groups[i].dims] for i in members]
            G, betas, yys, extra = posthold.statistics(self, ps, ys, post, rows, members[0])
            parts = b_parts(G, betas, yys, [self.groups[i].kappa for i in members])
            for i, part in zip(members, parts):
                dims = self.groups[i].dims
                out[i] = ((part[0] + extra, *part[1:]),
                          int(rows.sum()) * (LOG_2PI + self.log_sigma2[dims]))
        return out

    # --------------------------------------------------------------- joint
    def joint(self, times: FloatArray, values: FloatArray, durations: FloatArray,
              spans: np.ndarray) -> Scores:
        """Joint log-likelihood of all observations for every pair.

        Parameters
        ----------
        times : ndarray, shape (s,)
            Observation times (s) since the motion started.
        values : ndarray, shape (s, P)
            Observed human dims (normalised units); NaN where a modality is not
            observed (a row observes a modality if all its dims are finite).
        durations : ndarray, shape (C,)
            Candidate durations T (s); observations past T see the motion's end.
        spans : ndarray of int, shape (K, 2)
            Task k scores candidates ``durations[spans[k,0]:spans[k,1]]``.
        """
        parts = self._group_parts(self.phases(times, durations), values,
                                  posthold.post_rows(self, times, durations))
        loglik, factors = [], []
        for k in range(self.K):
            a, b = int(spans[k, 0]), int(spans[k, 1])
            if b <= a:
                loglik.append(np.empty(0))
                factors.append(np.empty((0, self.R + 1, self.R + 1)))
                continue
            Kt, eps, gamma_term, offset = self._stats(parts, k, slice(a, b), b - a)
            ll, L = factor_scores(Kt, eps, gamma_term, offset)   # eq. 12
            loglik.append(ll)
            factors.append(L)
        return Scores(loglik, factors)

    def joint_pairs(self, times: FloatArray, values: FloatArray, durations: FloatArray,
                    tasks: np.ndarray) -> tuple[FloatArray, FloatArray]:
        """Joint log-likelihood of a few (duration, task) pairs, vectorised over pairs.

        Parameters
        ----------
        times, values : as for :meth:`joint`.
        durations : ndarray, shape (M,)
        tasks : ndarray of int, shape (M,)

        Returns
        -------
        loglik : ndarray, shape (M,)
        factors : ndarray, shape (M, R+1, R+1)
            Augmented Cholesky factors (same layout as :meth:`joint`).
        """
        psi = self.phases(times, durations)
        post = posthold.post_rows(self, times, durations)
        stats = (None if post is not None else
                 pair_statistics(self._packed, self.R, psi, values, self.present(values), tasks))
        if stats is None:                                  # the numpy path
            stats = self._stats(self._group_parts(psi, values, post), np.asarray(tasks),
                                slice(None), len(tasks))
        return factor_scores(*stats)

    def _stats(self, parts, tasks, cand: slice, M: int):
        """Padded statistics of pairs: candidates ``cand`` of the parts with task ``tasks``.

        ``tasks`` is one task index (every candidate of one task: shared blocks, 2-D
        products) or an array with one task per candidate.
        """
        N, R1 = self.N, self.R + 1
        one = np.ndim(tasks) == 0
        Kt = np.zeros((M, R1, R1))
        eps = np.zeros((M, R1))
        gamma_term = np.zeros(M)
        offset = np.zeros(M)
        for g, part in zip(self.groups, parts):
            if part is None:
                continue
            (ld_a, W, ab, gamma), const = part
            W = W[cand]
            if one:
                Vf = g.blocks[tasks].reshape(-1, R1)                      # (N*Pg, R1)
                WV = (W.reshape(-1, N) @ Vf.reshape(N, -1)).reshape(M, -1, R1)
                member = np.broadcast_to(g.member[tasks], (M, g.dims.size))
            else:
                Vf = g.blocks[tasks].reshape(M, -1, R1)                   # (M, N*Pg, R1)
                WV = (W @ Vf.reshape(M, N, -1)).reshape(M, -1, R1)
                member = g.member[tasks]
            Kt += np.swapaxes(Vf, -1, -2) @ WV
            x = (ab[cand] / np.sqrt(self.sigma2[g.dims])).reshape(M, -1)
            eps += x @ Vf if one else (x[:, None, :] @ Vf)[:, 0]
            gamma_term += (member * gamma[cand] / self.sigma2[g.dims]).sum(axis=1)
            offset += member @ const + member.sum(axis=1) * ld_a[cand]
        return Kt, eps, gamma_term, offset

    # ------------------------------------------------------------ marginal
    def marginal(self, times: FloatArray, values: FloatArray, durations: FloatArray,
                 spans: np.ndarray) -> Scores:
        """Sum over observations of per-step marginal log-likelihoods.

        Arguments as for :meth:`joint`; each row is scored on the dims it observes.
        """
        psi = self.phases(times, durations)                              # (C, s, N)
        sq = (psi**2).sum(axis=2)                                        # (C, s)
        present = self.present(values)
        loglik = [np.zeros(int(b - a)) for a, b in spans]
        for pattern in np.unique(present.T, axis=0):
            rows = (present.T == pattern).all(axis=1)
            dims = np.concatenate([self.modality_dims[m] for m in np.flatnonzero(pattern)]
                                  + [np.zeros(0, int)])
            if dims.size == 0:
                continue
            for k in range(self.K):
                a, b = int(spans[k, 0]), int(spans[k, 1])
                loglik[k] += self._marginal_rows(k, psi[a:b, rows], sq[a:b, rows],
                                                 values[rows][:, dims], dims)
        return Scores(loglik, None)

    def _marginal_rows(self, k, psi, sq, y, dims):
        ut = self._raw[k][dims]                                          # (Pd, N, r+1)
        r = self.rank[k]
        blk = np.einsum("csn,pnj->cspj", psi, ut)
        low, mean = blk[..., :r], blk[..., r]
        S = low @ low.transpose(0, 1, 3, 2)
        idx = np.arange(dims.size)
        S[..., idx, idx] += self.sigma2[dims] + self.reg_h[k, dims] * sq[..., None]
        L = np.linalg.cholesky(S)
        w = np.linalg.solve(L, (y - mean)[..., None])[..., 0]
        logdet = 2.0 * np.log(np.diagonal(L, axis1=2, axis2=3)).sum(axis=2)
        return (-0.5 * (dims.size * LOG_2PI + logdet + (w**2).sum(axis=2))).sum(axis=1)


def compress_human(weights: WeightDistribution, P: int) -> tuple[WeightDistribution, int]:
    """The same weight distribution with the human block's factor in the fewest columns.

    The likelihood's r x r matrices (step 2 of the module docstring) have the rank r of
    the factor U (demos - 1), but only its human block :math:`U_h` (N P x r) enters
    them: with many demos (r > N P) :math:`U_h` has rank m <= N P. Turning the factor's
    columns by the orthogonal :math:`V` of the SVD :math:`U_h = A S V^T` (so
    :math:`(UV)(UV)^T = UU^T`) leaves the human block in the first m columns and zeros
    after them; the likelihood and the conditioning (:func:`~sandbox.core.factor.condition_robot`)
    then factor m x m matrices instead of r x r, exactly.

    Returns
    -------
    weights : WeightDistribution
        ``weights`` itself when r <= N P (nothing to gain), else the turned one.
    m : int
        Columns the human block spans (r when unchanged).
    """
    N, U = weights.n_basis, weights.factor
    r = U.shape[1]
    if r <= P * N:
        return weights, r
    _, sv, vt = np.linalg.svd(U[: P * N], full_matrices=True)
    m = int(np.count_nonzero(sv > sv.max() * 1e-12)) if sv.size and sv.max() > 0 else 0
    turned = U @ vt.T
    turned[: P * N, m:] = 0.0                   # U_h V beyond its rank: round-off only
    return WeightDistribution(weights.mean, turned, weights.reg, N), m


def _human_block(weights: WeightDistribution, P: int, N: int, rank: int) -> FloatArray:
    U = weights.factor[: P * N, :rank].reshape(P, N, -1)
    mu = weights.mean[: P * N].reshape(P, N, 1)
    return np.concatenate([U, mu], axis=2)


def _make_groups(kappa: FloatArray, modality_dims, pad: FloatArray) -> list[Group]:
    """One group per modality and distinct kappa (equal up to 1e-9 relative).

    A fitted model has one kappa per modality, shared by all tasks; a hand-made
    one may differ by task, and a task then belongs to a group only through the
    dims whose kappa it has (``member``).
    """
    groups = []
    for m, dims in enumerate(modality_dims):
        values: list[float] = []
        for x in kappa[:, dims].ravel():
            if not any(abs(x - u) <= 1e-9 * max(abs(u), 1e-300) for u in values):
                values.append(float(x))
        for v in values:
            same = np.abs(kappa[:, dims] - v) <= 1e-9 * max(abs(v), 1e-300)   # (K, |dims|)
            used = same.any(axis=0)
            member = same[:, used]
            blocks = pad[:, :, dims[used]] * member[:, None, :, None]
            groups.append(Group(dims[used], m, v, member, np.ascontiguousarray(blocks)))
    return groups

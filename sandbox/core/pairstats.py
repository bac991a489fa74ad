"""The statistics of a few (duration, task) pairs by the optional compiled kernel.

:meth:`~sandbox.core.likelihood.Scorer.joint_pairs` scores pairs whose durations are
off the lattice (the phase refinement of :func:`~sandbox.core.phase.estimate_phase`, an
oracle's duration): each needs its own N x N factorisation per group and the r x r
statistics of its task, built from every observation. On the numpy path that is some
sixty numpy calls per update whatever the number of pairs; with numba installed
(``sandbox/core/_kernels.py``) :func:`pair_statistics` builds them in one compiled call.
Its statistics agree with the numpy path's within 1e-13 of their largest entry; the
log-likelihood, a difference of terms a thousand times its size, within 1e-15 of those
terms (a few 1e-12 of itself; ``tests/core/test_kernels.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sandbox.core import _kernels
from sandbox.core.interaction import LOG_2PI
from sandbox.validation import FloatArray

if TYPE_CHECKING:
    from sandbox.core.likelihood import Group


def pack_groups(groups: list[Group], sigma2: FloatArray, log_sigma2: FloatArray) -> tuple:
    """The groups in the compiled kernel's layout (precomputed once per scorer).

    Returns
    -------
    tuple
        ``dims`` (cols,) the human dim of every group column, ``starts`` (G+1,) each group's
        columns, ``modality`` (G,), ``kappa`` (G,), ``columns`` (3, cols) each column's
        :math:`\\sigma_p`, :math:`\\sigma_p^2`, :math:`\\log 2\\pi + \\log\\sigma_p^2`,
        ``member`` (K, cols) and ``blocks`` (K, cols, N, R+1).
    """
    dims = np.concatenate([g.dims for g in groups]).astype(np.int64)
    starts = np.concatenate([[0], np.cumsum([g.dims.size for g in groups])]).astype(np.int64)
    columns = np.stack([np.sqrt(sigma2[dims]), sigma2[dims], LOG_2PI + log_sigma2[dims]])
    member = np.ascontiguousarray(np.concatenate([g.member for g in groups], axis=1))
    blocks = np.concatenate([g.blocks.transpose(0, 2, 1, 3) for g in groups], axis=1)
    return (dims, starts, np.array([g.modality for g in groups], dtype=np.int64),
            np.array([g.kappa for g in groups], dtype=np.float64), columns, member,
            np.ascontiguousarray(blocks))


def pair_statistics(packed: tuple, R: int, psi: FloatArray, values: FloatArray,
                    present: np.ndarray, tasks: np.ndarray):
    """``(Kt, eps, gamma_term, offset)`` of pairs (as ``Scorer._stats``), or None without
    the compiled kernel.

    Parameters
    ----------
    packed : tuple
        :func:`pack_groups` of the scorer.
    R : int
        The scorer's padded rank.
    psi : ndarray, shape (M, s, N)
        The basis at every pair's phases of the observations.
    values : ndarray, shape (s, P)
        The observations (NaN where a modality is not observed).
    present : ndarray of bool, shape (n_modalities, s)
        Which modalities each row observes.
    tasks : ndarray of int, shape (M,)
    """
    kernel = _kernels.pair_kernel(R + 1)
    if kernel is None:
        return None
    M = psi.shape[0]
    Kt, eps = np.zeros((M, R + 1, R + 1)), np.zeros((M, R + 1))
    gamma_term, offset = np.zeros(M), np.zeros(M)
    kernel(np.ascontiguousarray(psi), np.ascontiguousarray(values, dtype=np.float64),
           np.ascontiguousarray(present), np.asarray(tasks, dtype=np.int64), *packed,
           Kt, eps, gamma_term, offset)
    return Kt, eps, gamma_term, offset

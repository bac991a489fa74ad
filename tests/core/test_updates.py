"""The stream's factor updates (sandbox/core/_updates.py): each observed dim folded into
every pair's augmented Cholesky factor, against factoring the augmented matrix (the numpy
path keeps), with masked modalities, padding ranks and the kernel switched mid-stream.
The tests that compile skip without numba; the pure-Python kernel runs everywhere."""

import numpy as np
import pytest

from sandbox.core import _kernels, _updates
from sandbox.core.likelihood import Scorer
from sandbox.core.model import IProMP
from sandbox.core.phase import Lattice
from sandbox.core.statistics import StreamStatistics

from . import synth


def _store(rng, ranks, counts, R):
    """Factors of random augmented matrices (I + X^T X in the first r, a last row) in the
    store's layout, the x rows of a few new dims and the matrices those rows make."""
    at = _updates.layout(ranks, counts)
    store, rows = np.zeros(at[-1]), 4
    x = np.zeros((counts.sum(), ranks.size, rows, R + 1))
    coef, member = rng.standard_normal((counts.sum(), rows)), np.ones((ranks.size, rows))
    before, after = [], []
    for k, (r, C) in enumerate(zip(ranks, counts)):
        c0 = counts[:k].sum()
        X = rng.standard_normal((C, 5, r + 1))
        A = X.transpose(0, 2, 1) @ X
        A[:, np.arange(r), np.arange(r)] += 1.0
        store[at[k]:at[k + 1]] = np.linalg.cholesky(A).transpose(2, 1, 0).ravel()
        new = rng.standard_normal((C, rows, r + 1))
        x[c0:c0 + C, k, :, :r] = new[..., :r]
        x[c0:c0 + C, k, :, R] = coef[c0:c0 + C] - new[..., r]        # z_R = c - x_R
        before.append(A)
        after.append(A + new.transpose(0, 2, 1) @ new)
    return store, at, x, coef, member, after


@pytest.mark.parametrize("compiled", [False, True])
def test_folded_rows_give_the_factor_of_the_grown_matrix(compiled):
    """U^T U + z z^T per row, z = [x_U, c - x_R] (known answer: the factor of the sum)."""
    if compiled:
        pytest.importorskip("numba")
        _kernels.factor_kernel(8)
    rng = np.random.default_rng(0)
    ranks, counts, R = np.array([3, 6, 1]), np.array([5, 2, 4]), 6
    store, at, x, coef, member, after = _store(rng, ranks, counts, R)
    update = _updates._update if compiled else _updates._update_py
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    scratch = np.empty((x.shape[2] + 1) * (R + 2) * counts.max() + 5 * counts.max())
    update(store, at, ranks, starts, counts, x, coef, member, scratch)
    for k, (r, C) in enumerate(zip(ranks, counts)):
        U = store[at[k]:at[k + 1]].reshape(r + 1, r + 1, C).transpose(2, 0, 1)
        assert np.all(np.tril(U, -1) == 0.0) and np.all(np.diagonal(U, axis1=1, axis2=2) > 0)
        np.testing.assert_allclose(U, np.linalg.cholesky(after[k]).transpose(0, 2, 1),
                                   rtol=0, atol=1e-12 * np.abs(after[k]).max())
    ll = np.empty(counts.sum())
    offset = rng.standard_normal(counts.sum())
    _updates._loglik_py(store, at, ranks, counts, offset, ll)
    A = after[0]
    L = np.linalg.cholesky(A)
    want = -0.5 * (offset[:5] + 2 * np.log(np.diagonal(L[:, :3, :3], axis1=1, axis2=2)).sum(1)
                   + L[:, 3, 3] ** 2)
    np.testing.assert_allclose(ll[:5], want, rtol=1e-12)


def test_a_zero_row_leaves_a_factor_unchanged_bit_for_bit():
    rng = np.random.default_rng(1)
    ranks, counts, R = np.array([4]), np.array([3]), 4
    store, at, x, coef, member, _ = _store(rng, ranks, counts, R)
    x[1] = 0.0                                         # candidate 1: nothing observed
    coef[1] = 0.0
    before = store.copy().reshape(5, 5, 3)
    _updates._update_py(store, at, ranks, np.zeros(1, dtype=np.int64), counts, x, coef,
                        member, np.empty(200))
    np.testing.assert_array_equal(store.reshape(5, 5, 3)[:, :, 1], before[:, :, 1])
    assert not np.array_equal(store.reshape(5, 5, 3)[:, :, 0], before[:, :, 0])


def _stream(model, t, y, n_candidates=20):
    stats = StreamStatistics(Scorer(model), Lattice.for_tasks(model.task_models, n_candidates))
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    return stats


def _multimodal():
    demos = synth.multimodal(np.random.default_rng(5), n_per_task=6)
    model = IProMP(n_basis=9).fit(demos[1:])
    t, y = demos[0].times[:160:4], demos[0].human[:160:4] / model.scale
    y[5:9, 3:9] = np.nan                              # arm and EMG missing in some rows
    y[::3, 9:] = np.nan
    return model, t, y


def test_kept_factors_match_the_kept_matrices_with_masked_modalities(monkeypatch):
    """The kernel path (factors updated row by row) against the numpy path (the augmented
    matrices grown and factored): log-likelihoods within 1e-12 of their largest, factors
    within 1e-12 of theirs; the ranks of the tasks differ (padding)."""
    pytest.importorskip("numba")
    model, t, y = _multimodal()
    monkeypatch.setenv(_kernels.ENV, "numpy")
    ll0, L0 = _stream(model, t, y).packed_scores()
    monkeypatch.setenv(_kernels.ENV, "numba")
    stats = _stream(model, t, y)
    assert stats._factored and len(set(stats.scorer.rank)) > 1
    ll1, L1 = stats.packed_scores()
    np.testing.assert_allclose(ll1, ll0, rtol=0, atol=1e-12 * np.abs(ll0).max())
    np.testing.assert_allclose(L1, L0, rtol=0, atol=1e-12 * np.abs(L0).max())
    np.testing.assert_array_equal(stats.packed_loglik(), ll1)
    pick = np.array([2, ll1.size - 1, 2])
    np.testing.assert_array_equal(stats.pair_factors(pick), L1[pick])


def test_the_kernel_can_be_switched_in_the_middle_of_a_stream(monkeypatch):
    """SANDBOX_KERNEL changed between updates: the kept matrices are turned into factors
    and back, and the stream goes on to the same numbers (round-off)."""
    pytest.importorskip("numba")
    model, t, y = _multimodal()
    monkeypatch.setenv(_kernels.ENV, "numba")
    ll_ref = _stream(model, t, y).packed_loglik()
    stats = _stream(model, t[:15], y[:15])
    for choice, rows in (("numpy", slice(15, 25)), ("numba", slice(25, None))):
        monkeypatch.setenv(_kernels.ENV, choice)
        stats.packed_loglik()                          # an update on the other path
        for ti, yi in zip(t[rows], y[rows]):
            stats.add(ti, yi)
        assert stats._factored == (choice == "numba")
    np.testing.assert_allclose(stats.packed_loglik(), ll_ref, rtol=0,
                               atol=1e-12 * np.abs(ll_ref).max())

"""The optional compiled kernel of the phase stage (sandbox/core/_kernels.py) against the
numpy path, and the switch between them. The tests that compile skip without numba."""

import os
import subprocess
import sys

import numpy as np
import pytest

from sandbox.core import _kernels
from sandbox.core.factor import factor_scores
from sandbox.core.inference import predict
from sandbox.core.likelihood import Scorer
from sandbox.core.model import IProMP
from sandbox.core.phase import Lattice
from sandbox.core.statistics import StreamStatistics

from . import synth


def _pairs(rng, M, R):
    """Statistics of M pairs as a stream makes them: Kt = X^T X, eps = X^T c, gamma = c^T c."""
    X = rng.standard_normal((M, 3 * R, R + 1))
    c = rng.standard_normal((M, 3 * R))
    Kt = X.transpose(0, 2, 1) @ X
    eps = (X.transpose(0, 2, 1) @ c[..., None])[..., 0]
    return Kt, eps, (c * c).sum(axis=1) + 0.5, rng.standard_normal(M)


def _both(monkeypatch, *args):
    monkeypatch.setenv(_kernels.ENV, "numpy")
    ref = factor_scores(*[a.copy() for a in args])
    monkeypatch.setenv(_kernels.ENV, "numba")
    return ref, factor_scores(*[a.copy() for a in args])


@pytest.mark.parametrize(("M", "R"), [(1, 1), (37, 9), (70, 30), (16, 55), (16, 93)])
def test_kernel_matches_the_numpy_path(monkeypatch, M, R):
    pytest.importorskip("numba")
    (ll0, L0), (ll1, L1) = _both(monkeypatch, *_pairs(np.random.default_rng(R), M, R))
    np.testing.assert_allclose(ll1, ll0, rtol=1e-12, atol=0)
    np.testing.assert_allclose(L1, L0, rtol=1e-12, atol=1e-12 * np.abs(L0).max())
    assert np.all(np.triu(L1, 1) == 0.0)


@pytest.mark.parametrize(("M", "R"), [(3, 93), (15, 49)])
def test_a_few_large_matrices_take_lapack(monkeypatch, M, R):
    """Fewer than FEW_LANES matrices of more than LARGE_ROWS rows: the numpy path's numbers
    bit for bit with the kernel on (its lanes would be mostly empty); one more matrix, or
    one row fewer, and the kernel factors them (within round-off, not bit for bit)."""
    pytest.importorskip("numba")
    from sandbox.core import factor

    assert R + 1 > factor.LARGE_ROWS and M < factor.FEW_LANES
    (ll0, L0), (ll1, L1) = _both(monkeypatch, *_pairs(np.random.default_rng(R), M, R))
    np.testing.assert_array_equal(ll1, ll0)
    np.testing.assert_array_equal(L1, L0)
    for args in (_pairs(np.random.default_rng(R), factor.FEW_LANES, R),
                 _pairs(np.random.default_rng(R), M, factor.LARGE_ROWS - 1)):
        (ll0, _), (ll1, _) = _both(monkeypatch, *args)
        np.testing.assert_allclose(ll1, ll0, rtol=1e-12, atol=0)
        assert not np.array_equal(ll1, ll0)        # the kernel's own order of operations


def test_kernel_clamps_a_lost_last_pivot_as_the_numpy_path(monkeypatch):
    pytest.importorskip("numba")
    Kt, eps, gamma, offset = _pairs(np.random.default_rng(1), 40, 6)
    gamma[[3, 33]] = -1e6                     # d^T B^-1 d below e^T K^-1 e: no last pivot
    (ll0, L0), (ll1, L1) = _both(monkeypatch, Kt, eps, gamma, offset)
    assert L1[3, -1, -1] == L0[3, -1, -1] == np.sqrt(1e-300)
    np.testing.assert_allclose(ll1, ll0, rtol=1e-12)


def test_a_matrix_that_is_not_positive_definite_fails_as_on_the_numpy_path(monkeypatch):
    pytest.importorskip("numba")
    Kt, eps, gamma, offset = _pairs(np.random.default_rng(2), 4, 5)
    Kt[2, 1, 1] = -10.0
    for choice in ("numpy", "numba"):
        monkeypatch.setenv(_kernels.ENV, choice)
        with pytest.raises(np.linalg.LinAlgError):
            factor_scores(Kt.copy(), eps, gamma, offset)


def test_predictions_match_with_and_without_the_kernel(monkeypatch):
    pytest.importorskip("numba")
    rng = np.random.default_rng(0)
    model = IProMP(n_basis=11).fit(synth.demos(rng, n_per_task=8, n_tasks=3, noise=0.003))
    test = synth.replay(0, 2.1, noise=0.003, rng=rng)
    t, y = test.times[:150:5], test.human[:150:5]
    scorer = Scorer(model)
    out = []
    for choice in ("numpy", "numba"):
        monkeypatch.setenv(_kernels.ENV, choice)
        stats = StreamStatistics(scorer, Lattice.for_tasks(model.task_models, 20))
        for ti, yi in zip(t, y):
            stats.add(ti, yi)
        out.append(predict(model, scorer, t, y, n_candidates=20, stats=stats))
    a, b = out
    assert a.task_index == b.task_index
    np.testing.assert_allclose(b.durations, a.durations, rtol=1e-12)
    np.testing.assert_allclose(b.log_likelihood, a.log_likelihood, rtol=1e-12)
    np.testing.assert_allclose(b.task_posterior, a.task_posterior, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(b.robot.mean, a.robot.mean, rtol=1e-9, atol=1e-12)


def test_numpy_is_forced_by_the_environment_and_large_matrices_take_lapack(monkeypatch):
    monkeypatch.setenv(_kernels.ENV, "numpy")
    assert _kernels.factor_kernel(10) is None
    monkeypatch.delenv(_kernels.ENV)
    assert _kernels.factor_kernel(_kernels.MAX_SIZE + 1) is None
    monkeypatch.setenv(_kernels.ENV, "fast")
    with pytest.raises(ValueError, match="SANDBOX_KERNEL: expected 'numpy', 'numba' or unset"):
        _kernels.factor_kernel(10)


def test_without_numba_the_numpy_path_is_taken_and_numba_cannot_be_forced():
    code = ("import sys; sys.modules['numba'] = None\n"        # import numba -> ImportError
            "import os, numpy as np\n"
            "from sandbox.core import _kernels\n"
            "from sandbox.core.factor import factor_scores\n"
            "assert _kernels.factor_kernel(10) is None\n"
            "ll, L = factor_scores(np.zeros((2, 3, 3)), np.zeros((2, 3)), np.ones(2),"
            " np.zeros(2))\n"
            "assert np.allclose(ll, -0.5) and np.allclose(L[:, :2, :2], np.eye(2))\n"
            "os.environ['SANDBOX_KERNEL'] = 'numba'\n"
            "try:\n    _kernels.factor_kernel(10)\nexcept ImportError as e:\n    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "SANDBOX_KERNEL": ""})
    assert "numba is not installed" in out.stdout


@pytest.mark.parametrize("choice", ["numpy", "numba"])
def test_a_work_buffer_leaves_the_statistics_unchanged(monkeypatch, choice):
    if choice == "numba":
        pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, choice)
    Kt, eps, gamma, offset = _pairs(np.random.default_rng(4), 6, 4)
    before = Kt.copy()
    ll_kept, _ = factor_scores(Kt, eps, gamma, offset, work=np.empty_like(Kt))
    assert np.array_equal(Kt, before)
    ll, _ = factor_scores(Kt, eps, gamma, offset)
    np.testing.assert_array_equal(ll_kept, ll)


def _padded(Kt, eps, R):
    """The statistics in the padded layout of rank R > r: zero rows and columns from r on,
    the augmented row and column moved to R (as a task of lower rank than another's)."""
    M, r1, _ = Kt.shape
    idx = list(range(r1 - 1)) + [R]
    big = np.zeros((M, R + 1, R + 1))
    big[:, np.array(idx)[:, None], np.array(idx)] = Kt
    e = np.zeros((M, R + 1))
    e[:, idx] = eps
    return big, e


def test_the_kernel_skips_a_padding_of_zero_rows_bit_for_bit(monkeypatch):
    pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, "numba")
    Kt, eps, gamma, offset = _pairs(np.random.default_rng(5), 45, 7)      # rank 7, 45 pairs
    ll, L = factor_scores(Kt.copy(), eps, gamma, offset)
    big, e = _padded(Kt, eps, 12)
    ll_pad, L_pad = factor_scores(big, e, gamma, offset)
    np.testing.assert_array_equal(ll_pad, ll)                         # the same numbers
    np.testing.assert_array_equal(L_pad[:, :7, :7], L[:, :7, :7])
    np.testing.assert_array_equal(L_pad[:, 12, :7], L[:, 7, :7])
    np.testing.assert_array_equal(L_pad[:, 12, 12], L[:, 7, 7])
    assert np.all(L_pad[:, 7:12, 7:12] == np.eye(5)) and np.all(L_pad[:, 12, 7:12] == 0.0)
    monkeypatch.setenv(_kernels.ENV, "numpy")                         # and as LAPACK does
    ll_np, L_np = factor_scores(big, e, gamma, offset)
    np.testing.assert_allclose(ll_pad, ll_np, rtol=1e-12, atol=0)
    np.testing.assert_allclose(L_pad, L_np, rtol=1e-12, atol=1e-12 * np.abs(L_np).max())


@pytest.mark.parametrize("choice", ["numpy", "numba"])
def test_a_few_pairs_factored_alone_are_those_of_the_whole_grid(monkeypatch, choice):
    """The phase grid asks for log-likelihoods only, then factors its best pairs alone
    (StreamStatistics.pair_factors): the same numbers bit for bit as the whole batch."""
    if choice == "numba":
        pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, choice)
    rng = np.random.default_rng(6)
    model = IProMP(n_basis=9).fit(synth.demos(rng, n_per_task=6, n_tasks=3, noise=0.003))
    test = synth.replay(1, 2.0, noise=0.003, rng=rng)
    stats = StreamStatistics(Scorer(model), Lattice.for_tasks(model.task_models, 70))
    for ti, yi in zip(test.times[:120:5], test.human[:120:5]):
        stats.add(ti, yi)
    ll, L = stats.packed_scores()
    np.testing.assert_array_equal(stats.packed_loglik(), ll)
    pick = np.array([3, ll.size - 1, 40, 3])
    np.testing.assert_array_equal(stats.pair_factors(pick), L[pick])


@pytest.mark.parametrize("step", [4, 20])
def test_the_pair_kernel_matches_the_numpy_path_with_masked_modalities(monkeypatch, step):
    """Scorer.joint_pairs (the refinement's pairs) by the compiled kernel of pairstats.py:
    the statistics within round-off of the numpy path's; the log-likelihood, a difference
    of terms ~1e3 x its size, within 1e-15 of those terms. ``step`` 20: 8 rows, fewer than
    the 9 basis functions (the EMG on 5), so the kernel takes the rows' space."""
    pytest.importorskip("numba")
    from sandbox.core.pairstats import pair_statistics

    demos = synth.multimodal(np.random.default_rng(5), n_per_task=6)
    model = IProMP(n_basis=9).fit(demos[1:])
    t, y = demos[0].times[:160:step], demos[0].human[:160:step] / model.scale
    y[5:9, 3:9] = np.nan                              # arm and EMG missing in some rows
    y[::3, 9:] = np.nan
    sc = Scorer(model)
    durations = np.array([1.2, 2.0, 2.6, 0.9, 3.1])
    tasks = np.array([0, 1, 0, 1, 1])
    psi = sc.phases(t, durations)
    monkeypatch.setenv(_kernels.ENV, "numpy")
    assert pair_statistics(sc._packed, sc.R, psi, y, sc.present(y), tasks) is None
    ref = sc._stats(sc._group_parts(psi, y), tasks, slice(None), tasks.size)
    ll0, L0 = sc.joint_pairs(t, y, durations, tasks)
    monkeypatch.setenv(_kernels.ENV, "numba")
    got = pair_statistics(sc._packed, sc.R, psi, y, sc.present(y), tasks)
    for a, b in zip(ref, got):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-13 * np.abs(a).max())
    ll1, L1 = sc.joint_pairs(t, y, durations, tasks)
    # in the rows' space (step 20) W is summed in another order: 1.7e-13 of itself seen
    tol = 1e-15 * np.abs(ref[2]).max() if step == 4 else 1e-12 * np.abs(ll0).max()
    np.testing.assert_allclose(ll1, ll0, rtol=0, atol=tol)
    np.testing.assert_allclose(L1, L0, rtol=0, atol=1e-12 * np.abs(L0).max())


def test_the_blend_kernel_matches_the_numpy_path_and_leaves_singular_knots_to_it(monkeypatch):
    pytest.importorskip("numba")
    from sandbox.core.blending import blend_pair

    rng = np.random.default_rng(7)
    T, Q = 40, 7
    m1, m2 = rng.normal(size=(2, T, Q))
    A = rng.normal(size=(2, T, Q, Q))
    S1, S2 = A @ A.transpose(0, 1, 3, 2) + 0.05 * np.eye(Q)
    a2 = 1.0 / (1.0 + np.exp(-np.linspace(-12, 12, T)))
    a2[:3] = 0.0                                   # the old plan alone at the first knots
    args = (m1, S1, 1.0 - a2, m2, S2, a2)
    monkeypatch.setenv(_kernels.ENV, "numpy")
    ref = blend_pair(*args)
    monkeypatch.setenv(_kernels.ENV, "numba")
    got = blend_pair(*args)
    for a, b in zip(ref, got):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * np.abs(a).max())
    S1[5] = S2[5] = 0.0                            # M singular at one knot: the pseudo-inverse
    monkeypatch.setenv(_kernels.ENV, "numpy")
    ref = blend_pair(*args)
    monkeypatch.setenv(_kernels.ENV, "numba")
    got = blend_pair(*args)
    for a, b in zip(ref, got):
        np.testing.assert_array_equal(b, a)


def test_the_log_determinant_survives_pivots_whose_product_overflows(monkeypatch):
    """The kernel sums log|K| as the log of the pivots' running product, flushed every
    factor of 1e100: pivots of 1e40 over 30 rows (a product of 1e1200) and of 1e-4 (1e-120:
    a matrix that is not I + J, for the other side) give the numpy path's log-likelihoods."""
    pytest.importorskip("numba")
    M, R = 6, 30
    Kt, eps, gamma, offset = _pairs(np.random.default_rng(8), M, R)
    Kt *= 1e-3
    idx = np.arange(R)
    Kt[:3, idx, idx] += 1e80                          # K = I + J with pivots about 1e40
    Kt[3:, :R, :R] = np.eye(R) * (1e-8 - 1.0)           # K = I + J = 1e-8 I: pivots 1e-4
    Kt[3:, :R, R] = Kt[3:, R, :R] = eps[3:, :R] = 0.0    # e = 0: the last pivot is kept
    (ll0, _), (ll1, _) = _both(monkeypatch, Kt, eps, gamma, offset)
    assert np.all(np.isfinite(ll0))
    np.testing.assert_allclose(ll1, ll0, rtol=1e-12, atol=0)

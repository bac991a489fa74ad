"""The blend of an update in one compiled call (sandbox/core/blendkernel.py) against the
numpy path, the product written in place against the one returned, and the switch between
the paths. The tests that compile skip without numba."""

import numpy as np
import pytest

from sandbox.core import _kernels, blendkernel
from sandbox.core.blending import blend_pair, blend_pair_into
from sandbox.core.inference import predict
from sandbox.core.likelihood import Scorer
from sandbox.core.model import IProMP
from sandbox.core.plan import Blending, Held, Plan, _activations
from sandbox.core.predictor import DynamicPredictor

from . import synth


@pytest.fixture(scope="module", params=[True, False], ids=["normalized", "plain"])
def fitted(request):
    rng = np.random.default_rng(4)
    model = IProMP(n_basis=11, normalized_basis=request.param).fit(
        synth.demos(rng, n_per_task=8, n_tasks=3, noise=0.003))
    test = synth.replay(1, 2.1, noise=0.003, rng=rng)
    pred = predict(model, Scorer(model), test.times[:120:5], test.human[:120:5])
    return model, pred


def _close(got, want):
    for a, b in zip(got, want):
        assert np.shape(a) == np.shape(b)
        if np.size(b):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(b).max())


def _knots(plan, t, held, how):
    """The knots kernel's raw outputs for an update at ``t``."""
    new_t = np.arange(np.floor(t / how.dt + 1e-9) + 1.0, (t + 3.0) / how.dt) * how.dt
    m, (Q, N) = new_t.size, (held.robot.n_dims, held.robot.n_basis)
    out = np.empty((m + 1, Q)), np.empty((m + 1, Q, Q))
    parts = [np.empty(m), np.empty(m), np.empty((m, Q)), np.empty((m, Q, Q)),
             np.empty((m, Q)), np.empty((m, Q, Q))]
    n, ok = blendkernel.knots_kernel()(
        plan.times, plan.mean, plan.cov, t, new_t, t + how.delay, how.rate, how.blend,
        held.robot.mean.reshape(Q, N), held.robot.factor.reshape(Q, N, -1), held.robot.reg,
        held.basis._centers, held.basis._neg_half_h, held.basis.normalized, held.duration,
        *out, *parts)
    assert ok
    return new_t, n, out, parts


@pytest.mark.parametrize("t", [0.0, 0.35, 1.2, 2.9, 6.0])
@pytest.mark.parametrize("how", [Blending(0.01, 50.0, 0.1, True, 2.0),
                                 Blending(0.01, 50.0, 0.1, False, 0.0),
                                 Blending(0.02, 5.0, 0.6, True, 0.5)],
                         ids=["blend", "replace", "slow"])
def test_kernel_matches_the_numpy_steps_it_replaces(monkeypatch, fitted, t, how):
    pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, "numba")
    model, pred = fitted
    held = Held(pred.robot, pred.duration, model.basis)
    plan = Plan.prior(model, how.dt).blended(0.2, held, held.duration, how)[0]
    new_t, n, (mean, cov), (fall, rise, om, oc, nm, nc) = _knots(plan, t, held, how)
    ref_fall, ref_rise, ref_n = _activations(new_t, t + how.delay, how.rate)
    assert n == (ref_n if how.blend else 0)
    _close((fall, rise), (ref_fall, ref_rise))
    _close(plan.at(t), (mean[0], cov[0]))                      # the old plan at t
    _close(plan.interpolate(new_t[:max(n, 1)]), (om[:max(n, 1)], oc[:max(n, 1)]))
    _close(held(new_t), (nm, nc))                               # eq. 4, held after its end
    scale = rise[n:, None, None] if how.blend else 1.0       # past the blend: new / rise
    _close((nm[n:], nc[n:] / scale), (mean[1 + n:], cov[1 + n:]))
    if n:              # the product (Cholesky) against the numpy path's (LU) of the same knots
        monkeypatch.setenv(_kernels.ENV, "numpy")
        want = blend_pair(om[:n], oc[:n], fall[:n], nm[:n], nc[:n], rise[:n])
        for a, b in zip((mean[1:n + 1], cov[1:n + 1]), want):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-11 * np.abs(b).max())


def test_a_product_that_is_not_positive_definite_goes_to_the_numpy_path(monkeypatch, fitted):
    """A knot whose M has no Cholesky factor in floating point: the kernel says so and the
    blend makes every product as the numpy path does (its pseudo-inverse where singular)."""
    pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, "numba")
    model, pred = fitted
    how = Blending(0.01, 50.0, 0.1, True, 2.0)
    held = Held(pred.robot, pred.duration, model.basis)
    prior = Plan.prior(model, 0.01)
    cov = prior.cov.copy()
    cov[130:] *= -1e3               # from 1.3 s: a2 S1 + a1 S2 negative definite, not singular
    plan = Plan(prior.times, prior.mean, cov)
    calls = []
    monkeypatch.setattr(blendkernel, "blend_pair_into",
                        lambda *args: calls.append(blend_pair_into(*args)))
    got = plan.blended(1.2, held, held.duration, how)
    assert len(calls) == 1                           # the kernel gave its products up
    ref = plan.blended(1.2, lambda ts: held(ts), held.duration, how)
    for a, b in zip((got[0].times, got[0].mean, got[0].cov), (ref[0].times, ref[0].mean,
                                                              ref[0].cov)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * np.abs(b).max())


@pytest.mark.parametrize("how", [Blending(0.01, 50.0, 0.1, True, 2.0),
                                 Blending(0.01, 50.0, 0.1, False, 0.0)], ids=["blend", "replace"])
def test_fused_blend_matches_the_step_by_step_one(monkeypatch, fitted, how):
    """The whole blend, fused (a Held) or step by step (any callable: the numpy steps, with
    the same compiled product): within 1e-10 of the largest entry, as the product of two
    distributions at a knot where one's activation is tiny solves a matrix of condition
    1e4-1e5 here, which scales the kernel's round-off (1e-15) as it does numpy's."""
    pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, "numba")
    model, pred = fitted
    held = Held(pred.robot, pred.duration, model.basis)
    plan = Plan.prior(model, how.dt)
    for t in (0.0, 0.35, 1.2, 2.9, 6.0):
        got, jump = plan.blended(t, held, held.duration, how)
        ref, ref_jump = plan.blended(t, lambda ts: held(ts), held.duration, how)
        for a, b in zip((got.times, got.mean, got.cov), (ref.times, ref.mean, ref.cov)):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * np.abs(b).max())
        assert jump == pytest.approx(ref_jump, rel=1e-6, abs=1e-12)
        step = np.flatnonzero(got.times > t)[0]
        assert jump == pytest.approx(np.linalg.norm(got.mean[step] - plan.at(got.times[step])[0]),
                                     rel=1e-12, abs=1e-15)
        plan = ref


def test_the_numpy_path_is_the_held_trajectory_blended(monkeypatch, fitted):
    """A Held on the numpy path gives what any callable of the same distribution gives."""
    model, pred = fitted
    monkeypatch.setenv(_kernels.ENV, "numpy")
    how = Blending(0.01, 50.0, 0.1, True, 2.0)
    plan = Plan.prior(model, 0.01)
    held = Held(pred.robot, pred.duration, model.basis)
    got, jump = plan.blended(1.1, held, pred.duration, how)
    ref, ref_jump = plan.blended(1.1, lambda ts: pred.trajectory(model.basis, ts),
                                 pred.duration, how)
    for a, b in zip((got.times, got.mean, got.cov), (ref.times, ref.mean, ref.cov)):
        np.testing.assert_array_equal(a, b)
    assert jump == ref_jump


def test_predictors_agree_on_both_paths(monkeypatch, fitted):
    """Every kernel on (the phase grid's, the product's, the knots') or none: the same plans
    within 1e-10 of their largest entry (the product of two distributions at a knot where
    one's activation is tiny solves a matrix of condition 1e4-1e5 by LU on either path)."""
    pytest.importorskip("numba")
    model, _ = fitted
    test = synth.replay(2, 2.0, noise=0.003, rng=np.random.default_rng(9))
    plans = []
    for choice in ("numpy", "numba"):
        monkeypatch.setenv(_kernels.ENV, choice)
        pred = DynamicPredictor(model, dow_t=0.2)
        for t, y in zip(test.times, test.human):
            pred.observe(t, y)
        pred.update(3.5)
        plans.append(pred.plan())
    for a, b in zip(*plans):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-10 * np.abs(a).max())


def test_the_kernel_is_off_on_the_numpy_path(monkeypatch):
    monkeypatch.setenv(_kernels.ENV, "numpy")
    assert blendkernel.knots_kernel() is None


def _two(rng, T=9, Q=4):
    A = rng.standard_normal((2, T, Q, Q))
    S = A @ A.transpose(0, 1, 3, 2) + 0.1 * np.eye(Q)
    return rng.standard_normal((2, T, Q)), S


@pytest.mark.parametrize("choice", ["numpy", "numba"])
def test_product_in_place_is_the_product_returned(monkeypatch, choice):
    if choice == "numba":
        pytest.importorskip("numba")
    monkeypatch.setenv(_kernels.ENV, choice)
    rng = np.random.default_rng(5)
    (m1, m2), (S1, S2) = _two(rng)
    rise = np.linspace(0.0, 1.0, 9)
    for a1, a2 in ((1 - rise, rise), (1 - rise[1:-1], rise[1:-1])):   # with zeros and without
        T = a1.size
        want = blend_pair(m1[:T], S1[:T], a1, m2[:T], S2[:T], a2)
        mean, cov = np.full((T, 4), np.nan), np.full((T, 4, 4), np.nan)
        blend_pair_into(m1[:T], S1[:T], a1, m2[:T], S2[:T], a2, mean, cov)
        np.testing.assert_array_equal(mean, want[0])
        np.testing.assert_array_equal(cov, want[1])

"""Covariance shrinkage toward the pooled one (sandbox.core.shrinkage)."""

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.core.promp import WeightDistribution
from sandbox.core.shrinkage import intensity, pooled_factor, shrink
from sandbox.data.synthetic import make_dataset


def _dense_intensity(w, target):
    """Schafer-Strimmer with an arbitrary target, element by element (the definition)."""
    n = w.shape[0]
    s = np.sqrt(np.diag(target))
    z = (w - w.mean(axis=0)) / s
    t = target / np.outer(s, s)
    cov = z.T @ z / (n - 1)
    prods = z[:, :, None] * z[:, None, :]
    var = n / (n - 1) ** 3 * ((prods - prods.mean(axis=0)) ** 2).sum(axis=0)
    return float(np.clip(var.sum() / ((cov - t) ** 2).sum(), 0, 1))


def _tasks(rng, n, dim=12, scales=(1.0, 1.0)):
    base = rng.normal(size=(dim, dim)) / np.sqrt(dim)
    return {f"t{i}": rng.normal(size=(n, dim)) @ (s * base).T + i for i, s in enumerate(scales)}


def test_pooled_factor_is_the_pooled_within_task_covariance():
    rng = np.random.default_rng(0)
    w = {"a": rng.normal(size=(6, 5)), "b": rng.normal(size=(9, 5)) + 3.0}
    u = pooled_factor(w)
    want = (5 * np.cov(w["a"].T) + 8 * np.cov(w["b"].T)) / (15 - 2)
    np.testing.assert_allclose(u @ u.T, want, atol=1e-12)


def test_intensity_matches_the_elementwise_definition():
    rng = np.random.default_rng(1)
    w = _tasks(rng, 15, dim=8, scales=(1.0, 2.0))
    u = pooled_factor(w)
    for x in w.values():
        assert intensity(x, u) == pytest.approx(_dense_intensity(x, u @ u.T), rel=1e-10)


def test_intensity_does_not_depend_on_units():
    rng = np.random.default_rng(2)
    w = _tasks(rng, 15, dim=8, scales=(1.0, 2.0))
    units = np.exp(rng.normal(size=8) * 3)
    scaled = {k: v * units for k, v in w.items()}
    for k in w:
        assert intensity(scaled[k], pooled_factor(scaled)) == pytest.approx(
            intensity(w[k], pooled_factor(w)), rel=1e-9)


def test_few_demos_of_one_spread_shrink_fully_many_of_different_spreads_do_not():
    rng = np.random.default_rng(3)
    same = _tasks(rng, 8, dim=30, scales=(1.0, 1.0))
    lams = [intensity(x, pooled_factor(same)) for x in same.values()]
    assert min(lams) > 0.8
    apart = _tasks(rng, 2000, dim=6, scales=(1.0, 4.0))
    lams = [intensity(x, pooled_factor(apart)) for x in apart.values()]
    assert max(lams) < 0.05


def test_shrink_gives_the_mixed_covariance_and_keeps_it_definite():
    rng = np.random.default_rng(4)
    w = _tasks(rng, 5, dim=9, scales=(1.0, 3.0))
    pooled = pooled_factor(w)
    dist = WeightDistribution.from_weights(w["t1"], 1e-3, 3)
    out = shrink(dist, pooled, 0.3)
    want = 0.7 * (dist.cov() - np.diag(dist.reg_diag)) + 0.3 * pooled @ pooled.T
    np.testing.assert_allclose(out.cov(), want + np.diag(dist.reg_diag), atol=1e-12)
    assert np.all(np.linalg.eigvalsh(out.cov()) > 0)
    np.testing.assert_array_equal(out.mean, dist.mean)
    np.testing.assert_array_equal(shrink(dist, pooled, 0.0).cov(), dist.cov())


def test_pooling_needs_more_demos_than_tasks():
    with pytest.raises(ValueError, match="more demos than tasks"):
        pooled_factor({"a": np.zeros((1, 3)), "b": np.ones((1, 3))})


@pytest.fixture(scope="module")
def demos():
    return make_dataset("diverging", 8, np.random.default_rng(0))


def test_the_model_records_its_intensities_and_none_keeps_each_task_its_own(demos):
    auto = IProMP(n_basis=11, shrinkage="auto").fit(demos)
    own = IProMP(n_basis=11).fit(demos)
    assert own.shrinkage == "none" and set(own.shrinkage_used.values()) == {0.0}
    assert set(auto.shrinkage_used) == set(auto.tasks)
    assert all(0.0 <= v <= 1.0 for v in auto.shrinkage_used.values())
    for a, o in zip(auto.task_models, own.task_models):
        np.testing.assert_array_equal(a.weights.mean, o.weights.mean)
        assert a.weights.factor.shape[1] > o.weights.factor.shape[1]
        assert np.all(np.linalg.eigvalsh(a.weights.cov()) > 0)


def test_shrinkage_is_saved_with_the_model(demos, tmp_path):
    model = IProMP(n_basis=11, shrinkage="auto").fit(demos)
    model.save(tmp_path / "m.npz")
    back = IProMP.load(tmp_path / "m.npz")
    assert back.shrinkage == "auto"
    np.testing.assert_array_equal(back.task_models[2].weights.factor,
                                  model.task_models[2].weights.factor)


def _halfway(model, demo):
    from sandbox.eval.loocv import kept_observations

    t, y = kept_observations(model, demo.times - demo.times[0], demo.human, 2)
    return t[: t.size // 2], y[: t.size // 2]


def test_robot_shrinkage_conditions_the_robot_as_auto_and_recognises_as_none(demos):
    """Issue 21: the shrunk covariance conditions the robot only (eq. 8)."""
    from sandbox.core import predict
    from sandbox.core.likelihood import Scorer

    models = {mode: IProMP(n_basis=11, shrinkage=mode).fit(demos)
              for mode in ("none", "auto", "robot")}
    for o, r in zip(models["none"].task_models, models["robot"].task_models):
        np.testing.assert_array_equal(r.weights.factor, o.weights.factor)
        assert o.robot is None and r.robot.factor.shape[1] > o.weights.factor.shape[1]
    times, values = _halfway(models["none"], demos[5])
    pred = {mode: predict(m, Scorer(m), times, values) for mode, m in models.items()}
    np.testing.assert_allclose(pred["robot"].task_posterior, pred["none"].task_posterior)
    np.testing.assert_allclose(pred["robot"].durations, pred["none"].durations)
    k, T = pred["robot"].task_index, pred["robot"].duration
    auto = predict(models["auto"], Scorer(models["auto"]), times, values, task=k, duration=T)
    np.testing.assert_allclose(pred["robot"].robot.mean, auto.robot.mean, atol=1e-9)
    assert np.abs(pred["robot"].robot.mean - pred["none"].robot.mean).max() > 1e-3
    other = (k + 1) % len(models["robot"].tasks)           # the hold's re-conditioning too
    held = pred["robot"].for_task(models["robot"], other)
    want = predict(models["auto"], Scorer(models["auto"]), times, values, task=other,
                   duration=float(pred["robot"].durations[other]))
    np.testing.assert_allclose(held.robot.mean, want.robot.mean, atol=1e-9)


def test_robot_shrinkage_is_saved_with_the_model(demos, tmp_path):
    model = IProMP(n_basis=11, shrinkage="robot").fit(demos)
    model.save(tmp_path / "m.npz")
    back = IProMP.load(tmp_path / "m.npz")
    assert back.shrinkage == "robot"
    for a, b in zip(model.task_models, back.task_models):
        np.testing.assert_array_equal(b.robot.factor, a.robot.factor)
        np.testing.assert_array_equal(b.weights.factor, a.weights.factor)
    plain = IProMP(n_basis=11).fit(demos)
    plain.save(tmp_path / "p.npz")
    assert all(t.robot is None for t in IProMP.load(tmp_path / "p.npz").task_models)


def test_an_unknown_shrinkage_is_refused():
    with pytest.raises(ValueError, match="shrinkage"):
        IProMP(shrinkage="pooled")


def test_motion_the_tasks_share_leaves_the_posterior_near_the_prior():
    """Issue 27: the diverging tasks' common first half says nothing about the task."""
    from sandbox.core.predictor import DynamicPredictor

    train = make_dataset("diverging", 20, np.random.default_rng(0))
    fresh = make_dataset("diverging", 1, np.random.default_rng(1))
    tops = {}
    for mode in ("none", "auto"):
        model = IProMP(shrinkage=mode).fit(train)
        tops[mode] = []
        for demo in fresh:
            pred, t, top = DynamicPredictor(model, dow_t=0.2), demo.times - demo.times[0], 0.0
            for ti, y in zip(t[t <= 0.35 * t[-1]], demo.human):      # before any branch starts
                if pred.observe(float(ti), y) is not None:
                    top = max(top, max(pred.task_posterior.values()))
            tops[mode].append(top)
    prior = 1.0 / len(fresh)
    assert max(tops["auto"]) <= prior + 0.2, tops
    assert max(tops["none"]) > max(tops["auto"]) + 0.1, tops   # the tasks' own covariances


def test_settings_files_take_every_shrinkage(tmp_path):
    from sandbox.commands._settings import CHOICES, load
    from sandbox.core.shrinkage import SHRINKAGE

    assert CHOICES["shrinkage"] == SHRINKAGE
    path = tmp_path / "s.json"
    path.write_text('{"shrinkage": "robot"}')
    assert load(str(path))["shrinkage"] == "robot"

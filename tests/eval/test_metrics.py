import numpy as np
import pytest

from sandbox.eval import metrics
from sandbox.robot import BaxterKinematics


def test_perfect_prediction_gives_zero_errors():
    rng = np.random.default_rng(0)
    q = rng.uniform(-0.5, 0.5, (50, 7))
    fk = BaxterKinematics().fk
    assert metrics.joint_rms(q, q) == 0.0
    assert metrics.goal_error(q[-1], q[-1], fk) == 0.0


def test_shifted_prediction_gives_the_shift():
    q = np.zeros((40, 7))
    assert metrics.joint_rms(q + 0.1, q) == pytest.approx(0.1)
    shift = np.zeros(7)
    shift[0] = 0.2                     # first joint only
    assert metrics.joint_rms(q + shift, q) == pytest.approx(np.sqrt(0.2**2 / 7))
    fk = lambda x: np.asarray(x)[:3]   # noqa: E731 - a Cartesian "robot"
    assert metrics.goal_error(np.array([0.03, 0.04, 0.0]), np.zeros(3), fk) == pytest.approx(0.05)


def test_time_to_correct():
    f = np.array([0.2, 0.4, 0.6, 0.8, 1.0])
    assert metrics.time_to_correct(f, np.array([0.2, 0.01, 0.2, 0.01, 0.02])) == 0.8
    assert metrics.time_to_correct(f, np.full(5, 0.01)) == 0.2
    assert metrics.time_to_correct(f, np.array([0.01, 0.01, 0.01, 0.01, 0.3])) == 1.0
    assert metrics.time_to_correct(np.array([]), np.array([])) == 1.0


def test_calibration_of_a_known_gaussian():
    rng = np.random.default_rng(1)
    Q, T = 3, 20000
    cov = np.diag([0.1, 0.2, 0.3])
    q = rng.multivariate_normal(np.zeros(Q), cov, size=T)
    mean = np.zeros((T, Q))
    covs = np.broadcast_to(cov, (T, Q, Q))
    assert metrics.coverage(q, mean, covs) == pytest.approx(0.95, abs=0.01)
    expected = 0.5 * (Q * np.log(2 * np.pi) + np.log(np.linalg.det(cov)) + Q)
    assert metrics.gaussian_nll(q, mean, covs) == pytest.approx(expected, rel=0.01)


def test_window_metric_normalises_by_the_worst_window():
    errors = {"e_p": [1.0, 2.0], "e_q": [3.0, 3.0], "e_phi": [0.0, 0.0]}
    m = metrics.window_metric(errors, (0.5, 0.25, 0.25))
    np.testing.assert_allclose(m, [0.5 * 0.5 + 0.25, 0.5 + 0.25])


def test_bootstrap_interval_contains_the_mean_and_shrinks_with_n():
    rng = np.random.default_rng(2)
    small = rng.normal(1.0, 1.0, 30)
    large = rng.normal(1.0, 1.0, 3000)
    lo, hi = metrics.bootstrap_ci(small)
    assert lo < small.mean() < hi
    lo2, hi2 = metrics.bootstrap_ci(large, n_boot=300)
    assert hi2 - lo2 < (hi - lo) / 4
    groups = np.repeat([0, 1], 15)
    lo3, hi3 = metrics.bootstrap_ci(np.r_[np.zeros(15), np.ones(15)], groups)
    assert lo3 == hi3 == 0.5        # macro-average keeps task weights exactly


def _loop_bootstrap(values, groups, n_boot, rng):
    """The per-resample reference: draw, then take the macro mean, one resample at a time."""
    members = [np.flatnonzero(groups == g) for g in np.unique(groups)]
    samples = []
    for _ in range(n_boot):
        pick = np.concatenate([rng.choice(m, size=m.size, replace=True) for m in members])
        v, g = values[pick], groups[pick]
        samples.append(np.mean([v[g == label].mean() for label in np.unique(g)]))
    return tuple(np.quantile(samples, [(1 - 0.95) / 2, (1 + 0.95) / 2]))


def test_vectorised_bootstrap_equals_the_per_resample_loop_exactly():
    rng = np.random.default_rng(5)
    groups = np.array(["b"] * 7 + ["a"] * 12 + ["c"] * 3)
    rng.shuffle(groups)
    values = rng.normal(size=groups.size)
    expected = _loop_bootstrap(values, groups, 400, np.random.default_rng(9))
    assert metrics.bootstrap_ci(values, groups, n_boot=400,
                                rng=np.random.default_rng(9)) == expected
    draws = metrics.within_group_draws(groups, 400, np.random.default_rng(9))
    assert metrics.bootstrap_ci(values, groups, draws=draws) == expected
    # a custom statistic sees the same resamples
    custom = metrics.bootstrap_ci(values, groups, draws=draws,
                                  statistic=lambda v, g: float(np.mean([v[g == x].mean()
                                                                        for x in np.unique(g)])))
    np.testing.assert_allclose(custom, expected, rtol=0, atol=1e-15)


def test_within_group_draws_are_the_per_resample_choices_and_leave_the_rng_alike():
    groups = np.array(["b"] * 7 + ["a"] * 12 + ["c"] * 3 + ["d"])      # "d": one member
    np.random.default_rng(2).shuffle(groups)
    ref_rng, rng = np.random.default_rng(11), np.random.default_rng(11)
    members = [np.flatnonzero(groups == g) for g in np.unique(groups)]
    expected = [np.empty((50, m.size), dtype=int) for m in members]
    for b in range(50):
        for d, m in zip(expected, members):
            d[b] = ref_rng.choice(m, size=m.size, replace=True)
    got = metrics.within_group_draws(groups, 50, rng)
    assert len(got) == len(expected)
    for a, b in zip(got, expected):
        np.testing.assert_array_equal(a, b)
    assert rng.integers(0, 2**62) == ref_rng.integers(0, 2**62)       # same state after
    assert [d.shape for d in metrics.within_group_draws(groups, 0, rng)] == \
        [(0, m.size) for m in members]


def test_pooled_statistic_equals_the_per_resample_mean_and_names_are_checked():
    rng = np.random.default_rng(4)
    groups = np.array(["x"] * 9 + ["y"] * 5 + ["z"] * 17)
    values = (rng.random(groups.size) < 0.6).astype(float)        # a share, as recognition
    draws = metrics.within_group_draws(groups, 300, np.random.default_rng(0))
    assert metrics.bootstrap_ci(values, groups, draws=draws, statistic="pooled") == \
        metrics.bootstrap_ci(values, groups, draws=draws, statistic=lambda v, g: v.mean())
    with pytest.raises(ValueError, match="pooled"):
        metrics.bootstrap_ci(values, groups, draws=draws, statistic="median")


def test_report_sections_reuse_draws_without_changing_intervals():
    from sandbox.eval.report import _section

    rng = np.random.default_rng(1)
    trials = [{"task": t, "m": {"x": float(rng.normal()), "y": float(rng.normal())}}
              for t in ["p"] * 6 + ["q"] * 4]
    out = _section(trials, ["p", "q"], lambda r: r["m"], ("x", "y"), 200)
    for task in ("p", "q", "mean"):
        rows = [r for r in trials if task in ("mean", r["task"])]
        groups = np.array([r["task"] for r in rows])
        for key in ("x", "y"):
            values = np.array([r["m"][key] for r in rows])
            expected = _loop_bootstrap(values, groups, 200, np.random.default_rng(0))
            assert tuple(out[task][f"{key}_ci"]) == expected

import numpy as np
import pytest

from sandbox.core.likelihood import Scorer
from sandbox.core.model import IProMP
from sandbox.core.phase import Lattice, estimate_phase

from . import synth


def candidate_grid(nominal, mean, std, n_candidates):
    tasks = [type("T", (), {"nominal_duration": n, "alpha_mean": m, "alpha_std": s})()
             for n, m, s in zip(nominal, mean, std)]
    lattice = Lattice.for_tasks(tasks, n_candidates)
    return lattice.durations, lattice.spans(), lattice.step


@pytest.fixture(scope="module")
def model():
    rng = np.random.default_rng(0)
    # noise floor matched to the 2 mm noise of these demos (the default 2 cm is for live tracks);
    # whole demos as the motion, so a replay of the whole shape has a known duration
    return IProMP(n_basis=21, noise_floor=1e-3, jitter_floor=None, settle_tol=None,
                  arrive_tol=None).fit(
        synth.demos(rng, n_per_task=12, duration_std=0.15))


@pytest.mark.parametrize("factor", [0.8, 1.0, 1.25])
@pytest.mark.parametrize("mode", ["joint", "marginal"])
def test_known_speed_is_recovered(model, factor, mode):
    task = model.task_models[0]
    true_T = factor * task.nominal_duration
    demo = synth.replay(0, true_T, noise=0.002, rng=np.random.default_rng(1))
    keep = demo.times <= 0.6 * true_T
    est = estimate_phase(Scorer(model), model.task_models, demo.times[keep][::5],
                         demo.human[keep][::5], mode=mode)
    assert est.alphas[0] == pytest.approx(true_T / task.nominal_duration, rel=0.02)


def test_grid_is_shared_and_wide_enough():
    nominal = np.array([2.0, 2.2, 3.0])
    durations, spans, step = candidate_grid(nominal, np.ones(3), np.array([0.1, 0.15, 0.1]),
                                            n_candidates=50)
    assert np.all(np.diff(durations) > 0)
    for k in range(3):
        T = durations[spans[k, 0]:spans[k, 1]]
        assert T.size >= 50
        assert T[0] >= nominal[k] * (1 - 0.3 * (1 + (k == 1) * 0.5)) - step
        assert T[-1] <= nominal[k] * (1 + 0.3 * (1 + (k == 1) * 0.5)) + step
        np.testing.assert_allclose(np.diff(T), step)


@pytest.mark.parametrize("mode", ["joint", "marginal"])
def test_observations_past_the_end_see_the_motion_hold(model, mode):
    """Regression (late decay): an idle tail after the motion used to force every candidate
    to last as long as the observations, stretching the estimate over the tail."""
    task = model.task_models[0]
    true_T = 1.1 * task.nominal_duration
    demo = synth.replay(0, true_T, noise=0.002, rng=np.random.default_rng(5))
    tail_t = true_T + np.arange(0.05, 1.0, 0.05)                 # one second holding still
    tail = demo.human[-1] + 0.002 * np.random.default_rng(6).standard_normal((tail_t.size, 3))
    t = np.r_[demo.times[::5], tail_t]
    y = np.vstack([demo.human[::5], tail])
    est = estimate_phase(Scorer(model), model.task_models, t, y, mode=mode)
    assert est.durations[0] == pytest.approx(true_T, rel=0.03)
    assert est.durations[0] < t[-1] - 0.5


def test_refinement_never_lowers_the_objective(model):
    demo = synth.replay(1, 2.07, noise=0.002, rng=np.random.default_rng(2))
    t, y = demo.times[:120:5], demo.human[:120:5]
    scorer = Scorer(model)
    grid = estimate_phase(scorer, model.task_models, t, y, refine_steps=0)
    fine = estimate_phase(scorer, model.task_models, t, y, refine_steps=3)
    objective = fine.log_likelihood + fine.log_prior
    assert np.all(objective >= grid.log_likelihood + grid.log_prior - 1e-9)


def test_the_grid_layout_is_kept_by_the_statistics_and_is_what_the_lattice_gives(model):
    """StreamStatistics.layout: made once per tasks sequence (the same object afterwards),
    equal to GridLayout.of on the lattice, read-only; the estimates with and without the
    statistics share its grid and agree to round-off."""
    from sandbox.core.phase import GridLayout
    from sandbox.core.statistics import StreamStatistics

    tasks = model.task_models
    scorer = Scorer(model)
    lattice = Lattice.for_tasks(tasks, 30)
    stats = StreamStatistics(scorer, lattice)
    demo = synth.replay(1, 2.0, noise=0.002, rng=np.random.default_rng(3))
    t, y = demo.times[:90:5] - demo.times[0], demo.human[:90:5]
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    layout = stats.layout(tasks)
    assert stats.layout(tasks) is layout
    fresh = GridLayout.of(tasks, lattice.durations, lattice.spans())
    for name in ("nominal", "alpha_mean", "alpha_std", "lengths", "starts", "T", "log_prior"):
        np.testing.assert_array_equal(getattr(layout, name), getattr(fresh, name))
        assert not getattr(layout, name).flags.writeable
    assert layout.cuts == fresh.cuts
    assert layout.T.size == int(layout.lengths.sum()) == stats.pairs.shape[1]
    a = estimate_phase(scorer, tasks, t, y, n_candidates=30, stats=stats)
    b = estimate_phase(scorer, tasks, t, y, n_candidates=30)
    np.testing.assert_allclose(a.durations, b.durations, rtol=1e-9)
    for (Ta, wa), (Tb, wb) in zip(a.grid, b.grid):
        np.testing.assert_array_equal(Ta, Tb)
        np.testing.assert_allclose(wa, wb, rtol=1e-6, atol=1e-12)


@pytest.mark.parametrize("refine_steps", [0, 1, 3])
def test_the_factors_are_each_tasks_at_its_best_duration(model, refine_steps):
    """Each task's factor is the one of its best duration, whether the refinement moved
    it (its own factor) or not (the grid's, copied from the stream's statistics only
    for those tasks): the same as the pair scored alone at that duration."""
    from sandbox.core.statistics import StreamStatistics

    tasks = model.task_models
    scorer = Scorer(model)
    stats = StreamStatistics(scorer, Lattice.for_tasks(tasks, 30))
    demo = synth.replay(1, 2.07, noise=0.002, rng=np.random.default_rng(4))
    t, y = demo.times[:60:5] - demo.times[0], demo.human[:60:5]
    for ti, yi in zip(t, y):
        stats.add(ti, yi)
    grid = estimate_phase(scorer, tasks, t, y, n_candidates=30, stats=stats, refine_steps=0)
    est = estimate_phase(scorer, tasks, t, y, n_candidates=30, stats=stats,
                         refine_steps=refine_steps)
    moved = est.durations != grid.durations
    assert moved.tolist() == [False, refine_steps > 0]      # one task refined, one not
    ll, alone = scorer.joint_pairs(t, y, est.durations, np.arange(len(tasks)))
    assert est.factors.shape == alone.shape
    np.testing.assert_allclose(est.log_likelihood, ll, rtol=1e-10)
    scale = np.abs(alone).max(axis=(1, 2))[:, None, None]
    assert np.all(np.abs(est.factors - alone) <= 1e-9 * scale)
    np.testing.assert_array_equal(est.factors[~moved], grid.factors[~moved])

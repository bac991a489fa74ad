import numpy as np
import pytest

from sandbox.core.model import IProMP

from . import synth


def test_fit_structure_and_priors():
    demos = synth.demos(np.random.default_rng(0), n_per_task=6, n_tasks=3)
    model = IProMP(n_basis=9).fit(demos)
    assert model.tasks == ("task0", "task1", "task2")
    assert (model.n_human, model.n_robot) == (3, 7)
    np.testing.assert_allclose(model.priors, 1 / 3)
    for t in model.task_models:
        assert t.n_demos == 6
        assert t.alpha_mean == 1.0
        assert t.weights.factor.shape == (10 * 9, 5)      # rank n - 1
        assert np.linalg.eigvalsh(t.weights.cov()).min() > 0
    kappa = np.array([t.weights.reg[:3] / model.noise for t in model.task_models])
    np.testing.assert_allclose(kappa, kappa[0, 0])      # shared by dims and tasks


def test_noise_estimate_recovers_white_noise():
    rng = np.random.default_rng(1)
    demos = synth.demos(rng, n_per_task=10, noise=0.01)
    model = IProMP(n_basis=21, noise_floor=1e-4, jitter_floor=None).fit(demos)
    np.testing.assert_allclose(np.sqrt(model.noise), 0.01, rtol=0.1)


def test_alpha_prior_from_durations():
    demos = synth.demos(np.random.default_rng(2), n_per_task=30, duration_std=0.1)
    model = IProMP(n_basis=9, settle_tol=None, arrive_tol=None).fit(demos)
    for task in model.task_models:
        dur = np.array([d.times[-1] for d in demos if d.task == task.name])
        assert task.nominal_duration == pytest.approx(dur.mean())
        assert task.alpha_std == pytest.approx(np.std(dur / dur.mean(), ddof=1))


def test_priors_are_normalised_and_validated():
    demos = synth.demos(np.random.default_rng(3), n_per_task=3)
    model = IProMP(n_basis=7, priors={"task0": 3.0, "task1": 1.0}).fit(demos)
    np.testing.assert_allclose(model.priors, [0.75, 0.25])
    with pytest.raises(ValueError, match="unknown"):
        model.with_priors({"nope": 1.0})


def test_errors():
    rng = np.random.default_rng(4)
    demos = synth.demos(rng, n_per_task=3)
    with pytest.raises(ValueError, match="none"):
        IProMP().fit([])
    with pytest.raises(ValueError, match="two demonstrations"):
        IProMP(n_basis=7).fit(demos[:4])
    bad = synth.Demo(demos[0].times, demos[0].human[:, :2], demos[0].robot, "task0")
    with pytest.raises(ValueError, match="P=3"):
        IProMP(n_basis=7).fit(demos + [bad])
    with pytest.raises(ValueError, match="regularizer"):
        IProMP(regularizer=0)
    with pytest.raises(RuntimeError, match="not fitted"):
        _ = IProMP().tasks


def _creeping(rng, n_per_task: int = 8, creep: float = 0.04):
    """Demos whose robot arrives within ``creep`` rad of its final pose at the motion's end
    and creeps the rest of the way while the hand waits (0.6 s of tail)."""
    out = []
    for d in synth.demos(rng, n_per_task=n_per_task):
        t = np.r_[d.times, d.times[-1] + 0.01 * np.arange(1, 61)]
        final = d.robot[-1] + creep / np.sqrt(7)
        s = np.linspace(0, 1, 60)[:, None]
        robot = np.vstack([d.robot, d.robot[-1] + (final - d.robot[-1]) * (3 * s**2 - 2 * s**3)])
        human = np.vstack([d.human, np.repeat(d.human[-1:], 60, axis=0)])
        out.append(synth.Demo(t, human, robot, d.task))
    return out


def test_the_robot_ends_where_it_settles():
    """Known answer: with ``robot_tol`` the model's robot end state is the settled pose (the
    demos' final configurations), while the motion's phase still ends when both partners
    arrived; without it the end state falls short by most of the creep."""
    demos = _creeping(np.random.default_rng(4))
    settled = IProMP(n_basis=15, robot_tol=0.005).fit(demos)
    short = IProMP(n_basis=15, robot_tol=None).fit(demos)
    assert settled.task_models[0].nominal_duration == pytest.approx(
        short.task_models[0].nominal_duration)              # the same motion end
    for k, name in enumerate(settled.tasks):
        final = np.mean([d.robot[-1] for d in demos if d.task == name], axis=0)
        ends = []
        for model in (settled, short):
            w = model.task_models[k].weights
            mean = w.mean.reshape(-1, 15) @ model.basis.evaluate(np.ones(1))[0]
            ends.append(np.linalg.norm(mean[3:] - final))
        assert ends[0] < 0.006 and ends[1] > 0.03

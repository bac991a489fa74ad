import numpy as np
import pytest

from sandbox.core import DynamicPredictor, IProMP
from sandbox.data.synthetic import make_dataset
from sandbox.eval.loocv import EvalConfig, evaluate_trial, kept_observations, run_loocv
from sandbox.robot import BaxterKinematics


@pytest.fixture(scope="module")
def setup():
    demos = make_dataset("diverging", 6, np.random.default_rng(0))
    demos = [d for d in demos if d.task in ("left", "right")]
    model = IProMP(n_basis=15).fit(demos[1:])
    return model, demos


def test_shared_estimates_equal_a_streamed_predictor(setup):
    """The evaluation's shortcut (one estimate per update time) equals streaming each window."""
    model, demos = setup
    test = demos[0]
    config = EvalConfig(windows=(0.5, 0.2), ratios=(0.5,), subsample=2, n_basis=15)
    fk = BaxterKinematics().fk
    res = evaluate_trial(model, test, config, fk)
    t = test.times - test.times[0]
    for w in (0.5, 0.2):
        pred = DynamicPredictor(model, dow_t=w, **config.predictor_options())
        for ti, yi in zip(t, test.human):
            pred.observe(ti, yi)
        mean, _ = pred.commands(t)
        rms = np.sqrt(np.mean((mean - test.robot) ** 2))
        assert res["dynamic"][f"{w:.1f}"]["e_q"] == pytest.approx(rms, rel=1e-9)
        assert res["dynamic"][f"{w:.1f}"]["n_updates"] == len(pred.updates)


def test_kept_observations_skip_nan_and_subsample():
    t = np.arange(10.0)
    y = np.ones((10, 3))
    y[[1, 4]] = np.nan
    kt, _ = kept_observations(t, y, 2)
    np.testing.assert_array_equal(kt, [0, 3, 6, 8])


def test_loocv_runs_every_trial_and_checks_alignment(setup):
    _, demos = setup
    config = EvalConfig(windows=(0.5,), ratios=(0.3, 0.9), n_basis=15)
    results, wall = run_loocv(demos, demos, config)
    assert len(results) == len(demos) and wall > 0
    assert {r["task"] for r in results} == {"left", "right"}
    with pytest.raises(ValueError, match="same trials"):
        run_loocv(demos, demos[::-1], config)

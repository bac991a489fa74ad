import json

import numpy as np
import pytest

from sandbox.eval.loocv import EvalConfig
from sandbox.eval.report import build_report, to_markdown


def _trial(task, e, rec=1.0):
    base = {"e_p": e, "e_q": 2 * e, "e_phi": 3 * e, "nll": 0.0, "coverage": 0.9}
    return {
        "task": task, "source": "x", "duration": 2.0,
        "oracle": dict(base),
        "static": {f"{f:.1f}": {**base, "e_p": e + f, "recognition": rec} for f in (0.1, 0.5)},
        "dynamic": {f"{w:.1f}": {**base, "e_p": e * w, "recognition": rec,
                                 "time_to_correct": 0.5, "jumps": [0.01, 0.02],
                                 "recognition_curve": [rec] * 10, "n_updates": 3}
                    for w in (1.0, 0.2)},
    }


def test_report_keys_and_known_means():
    trials = [_trial("a", 0.1), _trial("a", 0.3), _trial("b", 0.2, rec=0.0)]
    config = EvalConfig(ratios=(0.1, 0.5), windows=(1.0, 0.2)).to_dict()
    rep = build_report(trials, config, "synthetic:test", 1.5, n_boot=50)
    for key in ("dataset", "tasks", "n_trials", "config", "static", "dynamic", "oracle",
                "window_metric", "best_window", "runtime_s"):
        assert key in rep
    assert rep["n_trials"] == {"a": 2, "b": 1}
    assert rep["static"]["0.1"]["a"]["e_p"] == pytest.approx(0.3)
    assert rep["static"]["0.1"]["mean"]["e_p"] == pytest.approx((0.3 + 0.3) / 2)  # macro
    assert rep["dynamic"]["0.2"]["mean"]["recognition"] == pytest.approx(0.5)
    assert set(rep["dynamic"]["1.0"]["a"]) >= {"e_p", "e_q", "e_phi", "recognition",
                                              "time_to_correct"}
    assert rep["oracle"]["mean"]["e_q"] == pytest.approx(2 * (0.2 + 0.2) / 2)
    assert set(rep["window_metric"]) == {"0.33,0.33,0.33", "0.50,0.25,0.25",
                                         "0.25,0.50,0.25", "0.25,0.25,0.50"}
    assert rep["best_window"]["0.33,0.33,0.33"] == "0.2"      # smaller e_p, same e_q, e_phi
    d = rep["differences"]["0.5"]["0.2"]["e_p"]
    assert d == pytest.approx(rep["static"]["0.5"]["mean"]["e_p"]
                              - rep["dynamic"]["0.2"]["mean"]["e_p"])
    json.dumps(rep)
    text = to_markdown(rep)
    assert "Table II" in text and "dow_t = 0.2 s" in text
    assert np.isfinite(rep["jumps"]["0.2"]["max"])


def test_two_recognition_figures_are_named_apart():
    """Issue 30: task-averaged (the paper's) and share of trials differ when tasks are
    unbalanced; both are reported and labelled, the curve both ways too."""
    trials = [_trial("a", 0.1), _trial("a", 0.3), _trial("a", 0.2), _trial("b", 0.2, rec=0.0)]
    config = EvalConfig(ratios=(0.1, 0.5), windows=(1.0, 0.2)).to_dict()
    rep = build_report(trials, config, "synthetic:test", 1.5, n_boot=50)
    mean = rep["dynamic"]["0.2"]["mean"]
    assert mean["recognition"] == pytest.approx(0.5)             # (1 + 0) / 2 tasks
    assert mean["recognition_share"] == pytest.approx(0.75)      # 3 of 4 trials
    lo, hi = mean["recognition_share_ci"]
    assert lo <= 0.75 <= hi
    assert rep["static"]["0.5"]["mean"]["recognition_share"] == pytest.approx(0.75)
    assert rep["recognition_over_time"]["0.2"][-1] == pytest.approx(0.75)
    assert rep["recognition_over_time_task_averaged"]["0.2"][-1] == pytest.approx(0.5)
    text = to_markdown(rep)
    assert "recognition (task-averaged)" in text and "recognition (share of trials)" in text


def test_tune_keeps_the_current_value_unless_clearly_better(monkeypatch):
    from contextlib import nullcontext

    from sandbox.eval import evaluation, executors
    from sandbox.eval import tune as tune_mod

    fake = {0.01: 3.00, 0.02: 2.98, 0.04: 2.80}     # J by noise_floor

    def report(cfg):
        J = fake[cfg.noise_floor]
        entry = {"e_p": J * 0.05, "e_q": 0.0, "e_phi": 0.0, "recognition": 1.0, "coverage": 1.0}
        return {"dynamic": {"0.2": {"mean": entry}}, "static": {"0.3": {"mean": entry}},
                "oracle": {"mean": entry}, "jumps": {"0.2": {"p95": 0.0}}, "runtime_s": 0.0,
                "recognition_over_time": {"0.2": [1.0] * 10}}

    class Evaluation:               # the leave-one-out replaced by the fake objective
        def __init__(self, executor):
            pass

        def add(self, train, test):
            return "trials"

        def run(self, jobs, on_trials=None):
            for cfg, token in jobs:
                yield evaluation.Evaluated(evaluation.config_key(cfg, token), cfg, report(cfg),
                                          None)

    monkeypatch.setattr(executors, "open_executor", lambda *a: nullcontext())
    monkeypatch.setattr(evaluation, "Evaluation", Evaluation)
    best, rows = tune_mod.tune([], [], grid={"noise_floor": (0.01, 0.02, 0.04)},
                               log=lambda _: None)
    assert best.noise_floor == 0.04 and len(rows) == 3
    fake[0.04] = 2.96                                 # within tol of the default 0.02
    best, _ = tune_mod.tune([], [], grid={"noise_floor": (0.01, 0.02, 0.04)},
                            log=lambda _: None)
    assert best.noise_floor == 0.02
    assert tune_mod.objective({"e_p": 0.05, "e_phi": 0.2, "recognition": 0.7}, 0.03) == \
        pytest.approx(1 + 1 + 1 + 2)

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

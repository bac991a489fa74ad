"""Records of normal and OOD motions (sandbox.eval.oodsets): held-out normal motions, OOD
sets by the model of all normal ones, or every motion by a given calibrated model."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.eval import ood, oodreport, oodsets
from sandbox.eval.datasets import load_pair
from sandbox.eval.loocv import EvalConfig

CONFIG = EvalConfig(n_candidates=10, n_basis=9)


@pytest.fixture(scope="module")
def normal():
    return load_pair("synthetic:objects", n_per_task=3)[:2]


@pytest.fixture(scope="module")
def still():
    return load_pair("synthetic-ood:still@objects", n_per_task=1)[:2]


def test_every_normal_and_ood_trial_is_scored_once(normal, still):
    recs = oodsets.score_sets(*normal, {"still": still}, CONFIG, dow_t=0.5)
    assert sum(r["held_in"] for r in recs) == 9 and sum(not r["held_in"] for r in recs) == 3
    assert {r["group"] for r in recs if not r["held_in"]} == {"still"}
    for r in recs:
        assert r["times"] and np.all(np.isfinite(r["stats"])) and r["end"] > 0
    # the OOD set's handover moment is the one its data says
    assert [r["end"] for r in recs if not r["held_in"]] == [d.meta["handover_time"]
                                                           for d in still[1]]
    ranked = ood.rank(recs)
    assert all(len(r["familiarity"]) == len(r["times"]) for r in ranked)
    summary = oodreport.summarize(ranked)
    assert summary["still"]["n_normal"] == 9 and summary["still"]["auc"] > 0.8


def test_a_task_with_fewer_than_three_trials_is_refused(still):
    train, test, _ = load_pair("synthetic:objects", n_per_task=2)
    with pytest.raises(ValueError, match="at least 3 trials"):
        oodsets.score_sets(train, test, {"still": still}, CONFIG)


def test_a_given_model_needs_its_calibration(normal, still):
    model = CONFIG.model().fit(normal[0])
    with pytest.raises(ValueError, match="calibration"):
        oodsets.score_with_model(model, normal, {"still": still}, CONFIG)


def test_a_given_model_ranks_with_its_own_calibration(normal, still):
    model = CONFIG.model().fit(normal[0])
    model.calibrate(normal[0], normal[1], n_candidates=10, dow_t=0.5)
    held_out = load_pair("synthetic:objects", n_per_task=1, seed=7)[:2]
    recs = oodsets.score_with_model(model, held_out, {"still": still}, CONFIG)
    assert len(recs) == 6
    assert all(r["threshold"] == model.calibration.threshold and r["reference"] is None
               for r in recs)
    assert all(0 < f <= 1 for r in recs for f in r["familiarity"])
    assert np.diff(recs[0]["times"]).min() >= 0.5 - 1e-9      # the calibration's dow_t

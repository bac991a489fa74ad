"""The methods harness: the same folds for every method, the dynamic formulation's figures
equal to the leave-one-out's, resumption per method, the held-out split."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sandbox.eval import compare
from sandbox.eval.compare import CompareConfig, run_compare, splits, to_markdown, write_outputs
from sandbox.eval.datasets import load_pair
from sandbox.eval.loocv import EvalConfig, run_loocv

EVAL = EvalConfig(windows=(0.2,), ratios=(0.5,), n_basis=9, n_candidates=20)


@pytest.fixture(scope="module")
def trials():
    train, test, _ = load_pair("synthetic:two_task", n_per_task=3, seed=0)
    return train, test


def test_leave_one_out_folds_hold_out_each_trial_once():
    folds = splits(["a", "a", "b", "b", "b"], 0, 0)
    assert [i for i, _ in folds] == list(range(5))
    assert all(i not in rest and len(rest) == 4 for i, rest in folds)


def test_a_holdout_draws_n_per_task_and_fits_on_the_rest_of_that_task():
    tasks = ["a"] * 6 + ["b"] * 5
    folds = splits(tasks, 2, 0)
    held = [i for i, _ in folds]
    assert sorted(tasks[i] for i in held) == ["a", "a", "b", "b"]
    for i, rest in folds:
        assert {tasks[j] for j in rest} == {tasks[i]}
        assert not set(rest) & set(held) and len(rest) == tasks.count(tasks[i]) - 2
    assert splits(tasks, 2, 0) == folds and splits(tasks, 2, 1) != folds
    with pytest.raises(ValueError, match="holdout: expected at least 6 trials of task 'b'"):
        splits(tasks, 4, 0)


def test_the_dynamic_row_is_the_leave_one_outs_dynamic_formulation(trials, tmp_path):
    train, test = trials
    result = run_compare(train, test, CompareConfig(("dynamic",), evaluation=EVAL), tmp_path,
                         log=lambda text: None)
    mine = json.loads((tmp_path / "methods" / "dynamic.json").read_text())["trials"]
    theirs, _ = run_loocv(train, test, EVAL)
    for a, b in zip(mine, theirs):
        for key in ("e_p", "e_q", "e_phi", "recognition", "recognition_curve"):
            np.testing.assert_allclose(a[key], b["dynamic"]["0.2"][key], atol=1e-9)
    assert result["rows"]["dynamic"]["n_trials"] == len(train)


def test_every_method_gets_a_row_and_a_rerun_resumes_per_method(trials, tmp_path, monkeypatch):
    train, test = trials
    config = CompareConfig(("nearest", "bip"), evaluation=EVAL)
    first = run_compare(train, test, config, tmp_path, log=lambda text: None)
    paths = write_outputs(first, tmp_path)
    assert [p.name for p in paths] == ["compare.json", "compare.md", "recognition.png"]
    table = to_markdown(first).splitlines()
    assert [line.split("|")[1].strip() for line in table if line.startswith("| ")][1:] \
        == ["nearest", "bip"]
    ran = []
    real = compare.run_method
    monkeypatch.setattr(compare, "run_method",
                        lambda prepared, cfg, method, **kw: ran.append(method)
                        or real(prepared, cfg, method, **kw))
    again = run_compare(train, test, CompareConfig(("nearest", "bip", "dtw"), evaluation=EVAL),
                        tmp_path, log=lambda text: None)
    assert ran == ["dtw"]
    assert again["rows"]["bip"] == first["rows"]["bip"]
    changed = CompareConfig(("bip",), window=0.3, evaluation=EVAL)
    run_compare(train, test, changed, tmp_path, log=lambda text: None)
    assert ran == ["dtw", "bip"]


def test_a_row_has_every_measure_with_its_interval(trials, tmp_path):
    train, test = trials
    row = run_compare(train, test, CompareConfig(("dtw",), evaluation=EVAL), tmp_path,
                      log=lambda text: None)["rows"]["dtw"]
    for key in ("e_p", "e_q", "e_phi", "recognition_0.3", "recognition_0.5",
                "recognition_1.0", "late_decay", "update_s_median", "e_p_median"):
        lo, hi = row[f"{key}_ci"]
        assert lo <= row[key] + 1e-12 and row[key] <= hi + 1e-12, key
    assert row["recognition_1.0"] == pytest.approx(row["recognition"])

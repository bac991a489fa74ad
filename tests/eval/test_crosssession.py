"""Cross-session evaluation: fit on some sets of trials, predict another (issue 21, item 3)."""

from __future__ import annotations

import pytest

from sandbox.core import IProMP
from sandbox.eval import crosssession as cs
from sandbox.eval import heldout
from sandbox.eval.datasets import load_pair
from sandbox.eval.loocv import EvalConfig
from sandbox.eval.report import build_report

#: One window and one ratio: the quickest evaluation that has every section.
CONFIG = EvalConfig(windows=(0.2,), ratios=(0.5,))


def trial_set(name: str, seed: int, shift: float = 0.0, **options) -> cs.TrialSet:
    """synthetic:two_task (3 trials per task) with ``seed``; ``shift`` (m) moves the hand."""
    train, test, _ = load_pair("synthetic:two_task", seed=seed, n_per_task=3, **options)
    if shift:
        train = [d.replace(human=d.human + shift) for d in train]
        test = [d.replace(human=d.human + shift) for d in test]
    return cs.TrialSet(name, tuple(train), tuple(test))


@pytest.fixture(scope="module")
def sessions() -> list[cs.TrialSet]:
    """Three sessions; the last one seen by a tracker calibrated 3 cm off."""
    return [trial_set("s0", 0), trial_set("s1", 1), trial_set("s2", 2, shift=0.03)]


@pytest.fixture(scope="module")
def loso(sessions) -> list[dict]:
    return cs.run_leave_one_session_out(sessions, CONFIG)[0]


def test_a_trial_set_holds_the_same_trials_twice(sessions):
    s = sessions[0]
    with pytest.raises(ValueError, match="expected the same trials"):
        cs.TrialSet("x", s.train, s.test[::-1])
    with pytest.raises(ValueError, match="expected the same trials"):
        cs.TrialSet("x", s.train, s.test[:-1])


def test_cross_session_predicts_as_a_model_fitted_on_the_training_set(sessions):
    """Known answer: the test-only runner with IProMP().fit on the training trials."""
    fit, test = sessions[0], sessions[1]
    trials, runtime = cs.run_cross_session([fit], test, CONFIG)
    model = IProMP().fit(list(fit.train))
    expected, _ = heldout.run_heldout(model, list(test.train), list(test.test), CONFIG)
    assert trials == expected and runtime > 0
    assert [r["source"] for r in trials] == [d.source for d in test.test]


def test_sets_fitted_on_are_pooled(sessions):
    pooled = cs.TrialSet("pooled", sessions[0].train + sessions[2].train,
                         sessions[0].test + sessions[2].test)
    assert (cs.run_cross_session([sessions[0], sessions[2]], sessions[1], CONFIG)[0]
            == cs.run_cross_session([pooled], sessions[1], CONFIG)[0])


def test_each_session_is_predicted_by_the_others_once(sessions, loso):
    assert [r["session"] for r in loso] == [s.name for s in sessions for _ in s.test]
    for i, session in enumerate(sessions):
        others = sessions[:i] + sessions[i + 1:]
        alone, _ = cs.run_cross_session(others, session, CONFIG)
        assert [r for r in loso if r["session"] == session.name] == [
            {**r, "session": session.name} for r in alone]


def test_per_session_figures_are_the_report_means_of_that_session(sessions, loso):
    figures = cs.per_session(loso)
    assert list(figures) == [s.name for s in sessions]
    for session in sessions:
        rows = [r for r in loso if r["session"] == session.name]
        report = build_report(rows, CONFIG.to_dict(), session.name, 0.0, n_boot=2)
        entry = figures[session.name]
        assert entry["n_trials"] == report["n_trials"]
        for section in ("static", "dynamic"):
            for key, part in report[section].items():
                assert entry[section][key] == {k: part["mean"][k]
                                               for k in cs.SESSION_MEASURES[section]}
        assert entry["oracle"] == {k: report["oracle"]["mean"][k]
                                   for k in cs.SESSION_MEASURES["oracle"]}


def test_per_trial_rows_name_their_session(loso):
    rows = cs.per_trial(loso)
    assert [r["session"] for r in rows] == [r["session"] for r in loso]
    assert rows[0]["static"]["0.5"].keys() == {"e_p", "e_phi", "recognition"}


def test_the_test_tasks_must_be_among_those_fitted_on(sessions):
    only_left = trial_set("left-only", 0, tasks=["left"])
    with pytest.raises(ValueError, match=r"s1 has tasks \['right'\] that left-only has no"):
        cs.run_cross_session([only_left], sessions[1], CONFIG)
    with pytest.raises(ValueError, match=r"s0 has tasks \['right'\] that left-only has no"):
        cs.run_leave_one_session_out([sessions[0], only_left], CONFIG)


def test_one_session_is_nothing_to_leave_out(sessions):
    with pytest.raises(ValueError, match="expected at least 2"):
        cs.run_leave_one_session_out(sessions[:1], CONFIG)


def test_the_report_config_says_what_was_fitted_and_tested(sessions):
    cross = cs.describe_cross(CONFIG, sessions[:2], sessions[2])
    assert cross["mode"] == cs.CROSS_SESSION and cross["test"] == "s2"
    assert cross["train"] == "s0, s1" and cross["train_sessions"] == ["s0", "s1"]
    assert (cross["n_train"], cross["n_test"]) == (12, 6)
    assert cross["train_tasks"] == {"left": 6, "right": 6}
    loso = cs.describe_sessions(CONFIG, sessions)
    assert loso["mode"] == cs.LEAVE_ONE_SESSION_OUT and loso["sessions"] == ["s0", "s1", "s2"]
    assert loso["session_trials"] == {"s0": 6, "s1": 6, "s2": 6}
    assert loso["windows"] == CONFIG.windows          # the options, as leave-one-out's config

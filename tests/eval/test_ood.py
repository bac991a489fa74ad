"""Leave-task-out evaluation of the familiarity (sandbox.eval.ood)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from sandbox.eval import ood


@dataclass(frozen=True)
class Trial:
    task: str


def test_fold_jobs_leave_the_trial_and_the_task_out():
    train = [Trial(t) for t in "aaabbbccc"]
    jobs = ood.fold_jobs(train)
    assert len(jobs) == 3 * len(train)           # every trial once per left-out task
    for left, i, fit_on in jobs:
        assert all(train[j].task != left for j in fit_on)
        assert i not in fit_on
        if train[i].task == left:                # left-out: all trained trials
            assert len(fit_on) == 6
        else:                                    # held-in: the others
            assert len(fit_on) == 5


def records(rng, shift: float, n_per_task: int = 12):
    """Fake records of three tasks; left-out motions' statistics times ``shift``."""
    out = []
    tasks = ["a", "b", "c"]
    for left in tasks:
        trained = [k for k in tasks if k != left]
        for trial, task in enumerate(np.repeat(tasks, n_per_task)):
            times = np.arange(1, 9) * 0.2
            held_in = task != left
            stats = rng.lognormal(0.0, 0.3, times.size) * (1.0 if held_in else shift)
            chosen = [task if held_in else trained[0]] * times.size
            out.append({"left_out": left, "trial": trial, "task": task, "held_in": held_in,
                        "end": 1.2, "times": times.tolist(), "stats": stats.tolist(),
                        "chosen": chosen, "tasks": trained, "mean_duration": 1.0})
            if held_in:                          # it chose its own task throughout
                out[-1]["own_stats"] = out[-1]["stats"]
    return out


def test_clearly_different_motions_are_detected_and_false_alarms_stay_near_alpha():
    judged = ood.judge(ood.rank(records(np.random.default_rng(0), shift=20.0)), alpha=0.05)
    r = ood.rates(judged)
    for rule in ood.RULES:
        assert r[rule]["all"]["detection"] == 1.0
        assert r[rule]["all"]["false_alarm"] <= 0.15
    assert r[ood.RULES[0]]["all"]["n_held_in"] == 72
    assert r[ood.RULES[0]]["all"]["n_left_out"] == 36


def test_motions_like_the_trained_ones_are_detected_at_chance():
    judged = ood.judge(ood.rank(records(np.random.default_rng(1), shift=1.0)), alpha=0.1)
    r = ood.rates(judged)["any update"]["all"]
    assert abs(r["detection"] - r["false_alarm"]) < 0.15


def test_rules_judge_different_updates():
    """A motion that goes wrong only after its end fires at 'any update' and 'final update'
    but not 'to the handover'."""
    recs = records(np.random.default_rng(2), shift=1.0)
    late = next(r for r in recs if not r["held_in"])
    late["stats"] = [1.0] * 6 + [1e4, 1e4]          # updates at 1.4 and 1.6 s, after end 1.2
    judged = next(j for j in ood.judge(ood.rank(recs), alpha=0.05)
                  if j["trial"] == late["trial"] and j["left_out"] == late["left_out"])
    assert judged["flags"] == {"any update": True, "any update to the handover": False,
                               "final update": True}


def test_tradeoff_is_monotone_in_alpha():
    rows = ood.tradeoff(ood.rank(records(np.random.default_rng(3), shift=1.5)),
                       alphas=(0.01, 0.1, 0.3))
    for rule in ood.RULES:
        fa = [row[rule]["false_alarm"] for row in rows]
        det = [row[rule]["detection"] for row in rows]
        assert fa == sorted(fa) and det == sorted(det)


def test_markdown_has_every_rule_and_alpha():
    recs = records(np.random.default_rng(4), shift=3.0)
    result = ood.summarize(recs, data="fake", observe="hand", dow_t=0.2, seconds=1.0)
    text = ood.markdown(result)
    for rule in ood.RULES:
        assert f"| all | {rule} |" in text
    for a in ood.ALPHAS:
        assert f"| {a:g} |" in text


def test_needs_three_tasks():
    with pytest.raises(ValueError, match="at least three tasks"):
        ood.run("synthetic:two_task")


def test_end_to_end_on_a_small_synthetic_set():
    """Each stream is scored once per left-out task, with finite statistics and chosen
    tasks among the trained ones."""
    from sandbox.eval.datasets import load_pair
    from sandbox.eval.loocv import EvalConfig

    train, test, _ = load_pair("synthetic:objects", n_per_task=3)
    recs = ood.score_all(train, test, EvalConfig(n_candidates=10, n_basis=9), dow_t=0.5)
    assert len(recs) == 3 * len(train)
    for r in recs:
        assert r["times"] and np.all(np.isfinite(r["stats"]))
        assert len(r["ended"]) == len(r["times"]) and 0 <= min(r["ended"]) <= max(r["ended"]) <= 1
        assert set(r["chosen"]) <= set(r["tasks"]) and r["left_out"] not in r["tasks"]
    judged = ood.judge(ood.rank(recs))
    assert all(0.0 <= j["threshold"] <= 1.0 for j in judged)
    # split-conformal: with alpha (n + 1) < 1 the threshold lies below every reference
    # motion's lowest familiarity (so none of them would have fired)
    for j in judged:
        if 0.05 * (len(j["reference"]) + 1) < 1:
            assert j["threshold"] <= min(j["reference"])


def test_the_score_chooses_the_statistics_ranked_and_records_keep_all():
    """Five statistics per update; only the goal (last, a p-value bound) of left-out
    motions is off: ranked with it they are detected, with the four of timing at chance."""
    recs = records(np.random.default_rng(4), shift=1.0)
    rng = np.random.default_rng(5)
    for r in recs:
        base = np.asarray(r["stats"])[:, None] * rng.lognormal(0.0, 0.3, (len(r["stats"]), 4))
        goal = np.full((len(r["stats"]), 1), 0.1 if r["held_in"] else 30.0)
        r["stats"] = r["own_stats"] = np.hstack([base, goal]).tolist()
    detected = {}
    for score in ("timing", "goal"):
        judged = ood.judge(ood.rank(recs, score=score), alpha=0.05)
        detected[score] = np.mean([j["flags"]["any update"] for j in judged if not j["held_in"]])
        assert all(len(j["stats"][0]) == 5 for j in judged)
    assert detected["goal"] > 0.95 and detected["timing"] < 0.3
    with pytest.raises(ValueError, match="score"):
        ood.rank(recs, score="mahalanobis")


def test_a_gate_ranks_only_the_updates_before_the_estimated_end():
    """Normal motions whose updates past their estimated end (from a random update on)
    scatter widely set the ungated threshold low; gated, those updates are not ranked
    (NaN), and left-out motions raised mid-motion are detected far more often."""
    recs = records(np.random.default_rng(6), shift=1.0)
    rng = np.random.default_rng(7)
    for r in recs:
        stats, m = np.asarray(r["stats"]), int(rng.integers(3, 8))
        stats[m:] *= rng.lognormal(1.5, 1.5)
        if not r["held_in"]:
            stats[2] *= 3.0
        r["stats"], r["ended"] = stats.tolist(), [0.0] * m + [0.7] + [0.2] * (7 - m)
        r["own_stats"] = r["stats"]
    detected = {}
    for gate in (None, 0.5):
        judged = ood.judge(ood.rank(recs, gate=gate), alpha=0.05)
        detected[gate] = np.mean([j["flags"]["any update"] for j in judged if not j["held_in"]])
        for j in judged:
            past = np.isnan(j["familiarity"])
            assert past.sum() == (0 if gate is None else 8 - j["ended"].index(0.7))
    assert detected[0.5] > detected[None] + 0.3


def test_own_task_cells_change_only_what_a_motion_choosing_another_task_files():
    """Held-in motions that chose their own task throughout file the same cells either way
    (the same familiarities); when their first two updates chose the other trained task and
    scored large under it, filed by the chosen task those scores widen the other task's
    early cells, filed by the true task they do not, so the held-out motions' own early
    updates rank lower and the threshold falls (a systematic wrong early choice costs the
    own-task filing; docs, Results). Records without ``own_stats`` are refused."""
    recs = records(np.random.default_rng(8), shift=3.0)
    same = [ood.rank(recs, cells=cells) for cells in ("own", "chosen")]
    for a, b in zip(*same):
        np.testing.assert_array_equal(a["familiarity"], b["familiarity"])
    rng = np.random.default_rng(9)
    for r in recs:
        if r["held_in"]:
            stats = np.asarray(r["stats"])
            stats[:2] *= rng.lognormal(3.0, 0.5, 2)
            r["stats"] = stats.tolist()
            r["chosen"] = [next(k for k in r["tasks"] if k != r["task"])] * 2 + [r["task"]] * 6
    low = {cells: np.median([j["threshold"] for j in ood.judge(ood.rank(recs, cells=cells))])
           for cells in ("own", "chosen")}
    assert low["own"] < 0.5 * low["chosen"]
    for r in recs:
        r.pop("own_stats", None)
    with pytest.raises(ValueError, match="own_stats"):
        ood.rank(recs)
    assert len(ood.rank(recs, cells="chosen")) == len(recs)

"""The ood report (sandbox.eval.oodreport): scores, thresholds at false-alarm rates, AUC,
delays and the calibrated operating point, on records whose answers are known."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.eval import oodreport as rep


def record(fam, *, normal: bool, group=None, end: float = 1.0, times=None, **extra) -> dict:
    fam = list(map(float, fam))
    times = list(np.linspace(0.2, 1.6, len(fam))) if times is None else list(times)
    return {"held_in": normal, "group": group, "left_out": "normal", "end": end,
            "times": times, "familiarity": fam, "reference": [0.2] * 20, **extra}


def population(rng, n_normal=200, n_ood=100, shift=0.5, groups=("a",)):
    """Normal motions with uniform familiarities; OOD ones scaled down by ``shift``."""
    out = [record(rng.uniform(0.0, 1.0, 8) ** 0.2, normal=True) for _ in range(n_normal)]
    for g in groups:
        out += [record(shift * rng.uniform(0.0, 1.0, 8) ** 0.2, normal=False, group=g)
                for _ in range(n_ood)]
    return out


def test_score_is_the_lowest_familiarity_up_to_the_handover():
    r = record([0.9, 0.5, 0.7, 0.01], normal=True, times=[0.2, 0.4, 0.8, 1.2], end=1.0)
    assert rep.score(r) == 0.5
    assert rep.score(record([0.3], normal=True, times=[1.5], end=1.0)) == float("inf")
    assert rep.score(record([np.nan, 0.4], normal=True, times=[0.1, 0.2])) == 0.4


def test_threshold_keeps_false_alarms_at_or_below_the_rate():
    rng = np.random.default_rng(0)
    for n in (7, 50, 101, 400):
        normal = rng.uniform(size=n)
        for rate in (0.0, 0.01, 0.02, 0.05, 0.1, 0.5):
            h = rep.threshold_at(normal, rate)
            assert np.mean(normal < h) <= rate + 1e-12
            # and it is the largest such: one more normal motion would be flagged above it
            assert np.mean(normal <= h) > rate or h == np.inf
    assert rep.threshold_at([0.3, 0.3, 0.3], 0.5) == 0.3      # ties: none flagged


def test_auc_known_answers():
    assert rep.auc([0.5, 0.6], [0.1, 0.2]) == 1.0
    assert rep.auc([0.1, 0.2], [0.5, 0.6]) == 0.0
    assert rep.auc([0.3, 0.3], [0.3]) == 0.5
    assert np.isnan(rep.auc([], [0.1]))


def test_delays_are_negative_before_the_handover():
    normal = [record([0.9] * 5, normal=True) for _ in range(20)]
    early = record([0.9, 0.01, 0.01, 0.9, 0.9], normal=False, group="x",
                   times=[0.2, 0.4, 0.6, 0.8, 1.0], end=1.0)
    late = record([0.9, 0.9, 0.9, 0.9, 0.01], normal=False, group="x",
                  times=[0.2, 0.4, 0.6, 1.2, 1.4], end=1.0)
    point = rep.operating_point(normal, [early, late], 0.05)
    assert point["detection"] == 0.5 and point["false_alarm"] == 0.0
    assert point["median_delay_s"] == pytest.approx(-0.6)


def test_summary_rates_are_bounded_and_monotone():
    rng = np.random.default_rng(1)
    out = rep.summarize(population(rng, groups=("a", "b")))
    assert set(out) == {"a", "b", rep.ALL}
    for v in out.values():
        fa = [v["at_false_alarm"][f"{a:g}"]["false_alarm"] for a in rep.FA_RATES]
        det = [v["at_false_alarm"][f"{a:g}"]["detection"] for a in rep.FA_RATES]
        assert all(f <= a + 1e-12 for f, a in zip(fa, rep.FA_RATES))
        assert det == sorted(det) and v["auc"] > 0.8
    assert out["a"]["n_normal"] == 200 and out[rep.ALL]["n_ood"] == 200


def test_like_normal_motions_are_detected_at_chance():
    rng = np.random.default_rng(2)
    v = rep.summarize(population(rng, n_normal=400, n_ood=400, shift=1.0))["a"]
    assert abs(v["auc"] - 0.5) < 0.06
    for a in rep.FA_RATES:
        assert abs(v["at_false_alarm"][f"{a:g}"]["detection"] - a) < 0.05


def test_leave_task_out_groups_use_their_own_held_in_motions():
    recs = [{**record([0.9], normal=True), "left_out": t} for t in "ab" for _ in range(3)]
    recs += [{**record([0.01], normal=False), "left_out": "a"}]
    for r in recs:
        del r["group"]                    # records of sandbox.eval.ood.rank have no group
    g = rep.groups(recs)
    assert list(g) == ["a"] and len(g["a"][0]) == 3 and len(g["a"][1]) == 1


def test_calibrated_uses_the_reference_or_the_given_threshold():
    with_ref = record([0.1, 0.9], normal=True, times=[0.5, 1.5], end=1.0)
    assert rep.calibrated([with_ref], 0.05) == {"any update": 1.0, "before the handover": 1.0}
    late = record([0.9, 0.1], normal=True, times=[0.5, 1.5], end=1.0, threshold=0.15)
    late["reference"] = None
    assert rep.calibrated([late], 0.05) == {"any update": 1.0, "before the handover": 0.0}


def test_roc_runs_from_nothing_to_everything_and_markdown_names_every_group():
    rng = np.random.default_rng(3)
    recs = population(rng, n_normal=30, n_ood=10, groups=("p", "q"))
    normal, ood = rep.groups(recs)["p"]
    fa, det = rep.roc(normal, ood)
    assert (fa[0], det[0], fa[-1], det[-1]) == (0.0, 0.0, 1.0, 1.0)
    assert np.all(np.diff(fa) >= 0) and np.all(np.diff(det) >= 0)
    result = {"mode": "ood-sets", "data": "d", "ood_data": ["p", "q"], "observe": "hand",
              "dow_t": 0.2, "alpha": 0.05, "seconds": 1.0, "n_streams": len(recs),
              "groups": rep.summarize(recs), "records": recs}
    text = rep.markdown(result)
    for g in ("p", "q", rep.ALL):
        assert f"| {g} | " in text
    assert "score" not in text.splitlines()[0]
    assert "; score goal)" in rep.markdown({**result, "score": "goal"}).splitlines()[0]
    assert "detection @ 5 % FA" in text

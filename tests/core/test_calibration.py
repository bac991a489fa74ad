"""The familiarity calibration (sandbox.core.calibration): the conformal threshold's coverage,
Fisher's combination and the ranking, by known answers and properties on i.i.d. draws."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from sandbox.core.calibration import (
    COMPONENTS,
    LEVELS,
    NAMES,
    Calibration,
    conformal_threshold,
    fisher,
    ongoing,
    rank,
)
from sandbox.core.questions import motion_rank


def fresh_rate(draw, n: int, alpha: float, reps: int = 2000, fresh: int = 50,
               rule=conformal_threshold, seed: int = 0) -> float:
    """Mean share of fresh i.i.d. values below the threshold of n calibration values."""
    rng = np.random.default_rng(seed)
    rates = [np.mean(draw(rng, fresh) < rule(draw(rng, n), alpha)) for _ in range(reps)]
    return float(np.mean(rates))


@pytest.mark.parametrize("draw", [lambda rng, n: rng.random(n),
                                  lambda rng, n: rng.lognormal(-8.0, 3.0, n)],
                         ids=["uniform", "lognormal"])
def test_conformal_threshold_covers_alpha_whatever_the_distribution(draw):
    """k = alpha (n + 1) an integer: the fresh rate is k / (n + 1) = alpha exactly
    (Monte Carlo standard errors 0.0004 and 0.001 here)."""
    assert fresh_rate(draw, 199, 0.05) == pytest.approx(0.05, abs=0.002)
    assert fresh_rate(draw, 39, 0.1, seed=1) == pytest.approx(0.1, abs=0.003)


def test_between_order_statistics_the_rate_is_between_their_rates():
    """n = 30, alpha 0.05: rank 1.55, so the rate lies in [1/31, 2/31]."""
    rate = fresh_rate(lambda rng, n: rng.random(n), 30, 0.05)
    assert 1 / 31 - 0.002 < rate < 2 / 31 + 0.002


def test_fewer_motions_than_one_over_alpha_still_fire_about_alpha():
    """n = 9 < 1/alpha - 1: the threshold is r = alpha (n + 1) times the lowest value;
    for uniform values the rate is E[r U_(1)] = r / (n + 1) = alpha."""
    rate = fresh_rate(lambda rng, n: rng.random(n), 9, 0.05)
    assert rate == pytest.approx(0.05, abs=0.003)
    assert conformal_threshold([0.2, 0.4, np.inf, np.nan], 0.05) == pytest.approx(0.05 * 3 * 0.2)
    assert conformal_threshold([np.inf], 0.05) == 0.0


def test_np_quantile_fires_more_than_alpha():
    """Regression (issue 30): the threshold used to be np.quantile(lowest, alpha), at rank
    1 + alpha (n - 1): with 19 motions about 9.5 % of new ones fired at alpha 0.05."""
    old = fresh_rate(lambda rng, n: rng.random(n), 19, 0.05,
                     rule=lambda v, a: float(np.quantile(v, a)))
    assert old > 0.085
    assert fresh_rate(lambda rng, n: rng.random(n), 19, 0.05) == pytest.approx(0.05, abs=0.003)


def test_fisher_matches_the_chi_square_survival_function():
    rng = np.random.default_rng(2)
    for J in (1, 2, 4):
        p = rng.random(J)
        expected = stats.chi2.sf(-2.0 * np.log(p).sum(), 2 * J)
        assert fisher(p) == pytest.approx(expected, rel=1e-10)
    assert fisher(np.ones(4)) == 1.0
    assert fisher(np.array([1e-300, 1e-300, 1.0, 1.0])) < 1e-290


def test_fisher_of_independent_uniform_ranks_is_uniform():
    p = np.random.default_rng(3).random((4000, 4))
    f = np.array([fisher(row) for row in p])
    assert stats.kstest(f, "uniform").pvalue > 0.01


def test_rank_ties_at_the_bottom_rank_one_and_the_tail_is_graded():
    q = np.quantile(np.r_[np.zeros(50), np.arange(1.0, 51.0)], LEVELS)
    assert rank(q, 0.0) == 1.0                 # a tie with half the cell is no evidence
    assert rank(q, 25.0) == pytest.approx(0.25, abs=0.02)
    flat = np.zeros(LEVELS.size)                 # a cell that never moved
    assert rank(flat, 1e-3) == pytest.approx(0.0, abs=1e-30)         # Mahalanobis tail
    assert 0.0 < rank(flat, 1e-3, min_tail=10.0) < 0.05


def records(rng, n: int, J: int = len(COMPONENTS), shift: float = 0.0):
    return [(np.arange(8) * 0.2, rng.lognormal(shift, 0.5, (8, J)), rng.integers(0, 2, 8))
            for _ in range(n)]


@pytest.mark.parametrize("names", NAMES[1:], ids=["timing", "goal", "position", "all"])
def test_several_statistics_calibrate_and_a_new_record_fires_at_about_alpha(names):
    """Exchangeable records of four (before the goal), five or six statistics: fresh
    records fire at about alpha, a shifted one nearly always. The bounds are 99.9 % ones
    for one calibration of 200 records (its rate is Beta-distributed, sd 0.021, plus the
    binomial 0.012 of 600 fresh records); the mean over calibrations is tested on the
    threshold itself above."""
    rng = np.random.default_rng(4)
    J = len(names)
    cal = Calibration.from_records(records(rng, 200, J), 2, alpha=0.1, edges=[0.0, 0.6, 1.2],
                                   components=names)
    assert cal.components == names and cal.extra.shape == (J - 1, 2, 3, LEVELS.size)

    def fires(recs):
        return [min(cal.familiarity(t, v, k) for t, v, k in zip(*r)) < cal.threshold
                for r in recs]

    assert 0.02 < np.mean(fires(records(rng, 600, J))) < 0.18
    assert np.mean(fires(records(rng, 100, J, shift=1.5))) > 0.9


def test_a_calibration_before_the_goal_ranks_its_own_four_of_all_statistics():
    """Older calibrations (four statistics) take theirs from a full vector, the goal
    ignored. A full one makes each question's answer (the four's combination, the goal's
    exp(-s)) a per-motion p-value against the calibration motions' lowest answers, and
    takes the lower, doubled; without those (files before them) the answers themselves,
    as 1 - (1 - min)^2."""
    rng = np.random.default_rng(6)
    five = records(rng, 30, 5)
    old = Calibration.from_records([(t, v[:, :4], k) for t, v, k in five], 2, edges=[0.0])
    new = Calibration.from_records(five, 2, edges=[0.0], per_motion=True)
    v = np.array([1.0, 0.5, 2.0, 1.5, 0.0])
    f4 = old.familiarity(0.5, v[:4], 1)
    assert old.familiarity(0.5, v, 1) == f4 and old.motion is None
    assert old.familiarity(0.5, v + [0, 0, 0, 0, 30.0], 1) == f4
    assert new.motion.shape == (2, 30) and np.all(np.diff(new.motion, axis=1) >= 0)
    assert new.answers(0.5, v, 1) == pytest.approx([f4, 1.0], rel=1e-12)
    assert Calibration.from_records(five, 2, edges=[0.0]).motion is None     # the default
    pi = motion_rank(new.motion[0], f4)
    assert new.familiarity(0.5, v, 1) == pytest.approx(min(1.0, 2.0 * pi), rel=1e-12)
    far = new.familiarity(0.5, v + [0, 0, 0, 0, 30.0], 1)   # below every motion's goal
    assert far == pytest.approx(2.0 * new.motion[1, -1] / 30.0 / 31, rel=1e-9)
    legacy = replace(new, motion=None)
    assert legacy.familiarity(0.5, v, 1) == pytest.approx(f4 * (2.0 - f4), rel=1e-12)
    far = legacy.familiarity(0.5, v + [0, 0, 0, 0, 30.0], 1)
    assert far == pytest.approx(2.0 * np.exp(-30.0), rel=1e-9)
    with pytest.raises(ValueError, match="expected 1 or 4 or 5 or 6 statistics"):
        Calibration.from_records(records(rng, 5, 3), 2, edges=[0.0])
    with pytest.raises(ValueError, match="expected 1 or 4 or 5 or 6 statistics"):
        Calibration.from_records(five, 2, edges=[0.0], components=COMPONENTS)
    with pytest.raises(ValueError, match="motion quantiles"):
        replace(new, motion=new.motion[:, ::-1])


def test_the_goal_and_the_position_are_combined_apart_from_the_fit():
    """With both, the where-question's answer is the Fisher combination of the goal's
    exp(-s) and the position's rank; the position is ranked against all of the task's
    updates (one quantile row in every time bin); a position calibration takes its five
    of a full vector of six (the goal ignored)."""
    rng = np.random.default_rng(7)
    six = records(rng, 30, 6)
    four = Calibration.from_records([(t, v[:, :4], k) for t, v, k in six], 2,
                                    edges=[0.0, 0.6])
    pos = Calibration.from_records([(t, v[:, [0, 1, 2, 3, 5]], k) for t, v, k in six], 2,
                                   edges=[0.0, 0.6], components=NAMES[3])
    both = Calibration.from_records(six, 2, edges=[0.0], components=COMPONENTS)
    assert pos.components == NAMES[3] and both.components == COMPONENTS
    assert np.array_equal(pos.extra[-1, :, 0], pos.extra[-1, :, 1])          # binless
    assert not np.array_equal(pos.quantiles[:, 0], pos.quantiles[:, 1])     # binned
    v = np.array([1.0, 0.5, 2.0, 1.5, 0.0, 1.0])
    f4 = four.familiarity(0.5, v, 1)
    p_x = rank(pos.extra[-1, 1, 0], 1.0, 0.1)
    assert pos.answers(0.5, v, 1) == pytest.approx([f4, p_x], rel=1e-12)
    assert pos.familiarity(0.5, v + [0, 0, 0, 0, 30.0, 0], 1) == pos.familiarity(0.5, v, 1)
    assert both.answers(0.5, v + [0, 0, 0, 0, 30.0, 0], 1)[1] == pytest.approx(
        fisher(np.array([np.exp(-30.0), rank(both.extra[-1, 1, 0], 1.0, 0.1)])), rel=1e-9)


def test_a_question_whose_calibration_motions_reach_tiny_answers_keeps_the_other_its_alpha():
    """Calibration motions whose goal is at one update huge (a tail after the handover):
    compared as they are, the goal's tiny answers set the threshold and new motions that
    only the fit sees (its statistics tripled) are missed; each made a per-motion p-value
    first, the fit keeps about half of alpha and catches them. Fresh motions fire at
    about alpha either way (99.9 % bounds: one calibration of 100 at alpha 0.1, Beta sd
    0.03, and 300 fresh, binomial 0.017)."""
    rng = np.random.default_rng(8)

    def tailed(n, shift=0.0):
        out = []
        for t, v, k in records(rng, n, 5):
            v[:, :4] *= np.exp(shift)
            v[-1, 4] = rng.exponential(40.0)         # the goal's p-value e^-s: tiny
            out.append((t, v, k))
        return out

    def lowest(c, recs):
        return np.array([min(c.familiarity(t, v, k) for t, v, k in zip(*r)) for r in recs])

    cal = Calibration.from_records(tailed(100), 2, alpha=0.1, edges=[0.0, 0.6, 1.2],
                                   per_motion=True)
    legacy = replace(cal, motion=None)                 # split-conformal on 100 others
    legacy = replace(legacy, threshold=conformal_threshold(lowest(legacy, tailed(100)), 0.1))
    fresh, shifted = tailed(300), tailed(100, shift=np.log(3.0))
    for c in (cal, legacy):
        assert 0.02 < np.mean(lowest(c, fresh) < c.threshold) < 0.22
    assert np.mean(lowest(cal, shifted) < cal.threshold) > 0.8
    assert np.mean(lowest(legacy, shifted) < legacy.threshold) < 0.3


def test_the_statistics_vector_must_match_the_components():
    cal = Calibration.from_records(records(np.random.default_rng(5), 30), 2, edges=[0.0])
    with pytest.raises(ValueError, match="expected 6 statistics"):
        cal.familiarity(0.5, 1.0, 0)
    one = Calibration.from_records(records(np.random.default_rng(5), 30, J=1), 2, edges=[0.0])
    assert one.components == ("mahalanobis",) and one.extra is None
    with pytest.raises(ValueError, match="expected 1 statistics"):
        one.familiarity(0.5, np.ones(4), 0)


def test_ongoing_latches_at_the_first_update_past_the_level():
    ended = np.array([0.0, 0.2, 0.6, 0.3, 0.9])
    assert ongoing(ended, 0.5).tolist() == [True, True, False, False, False]
    assert ongoing(ended, None).all() and ongoing(ended, 0.95).all()
    assert ongoing(np.empty(0), 0.5).size == 0


def tailed(rng, n: int, anomaly: float = 0.0):
    """Records of 10 updates whose last 3 are past the motion's end (ended 1) and scatter
    far more than the 7 before them; ``anomaly`` raises update 3's statistics."""
    out = []
    for _ in range(n):
        v = rng.lognormal(0.0, 0.3, (10, 4))
        v[7:] *= rng.lognormal(1.0, 1.0, (3, 1))
        v[3] += anomaly
        out.append((np.arange(10) * 0.2, v, np.zeros(10, int), np.r_[np.zeros(7), np.ones(3)]))
    return out


def test_a_gated_calibration_ignores_the_updates_past_the_end():
    """Tails past the motion's end that vary more than the motion set an ungated
    threshold low; gated to the ongoing motion, a raised update mid-motion fires far
    more often, at the same false-alarm rate on fresh records (about alpha)."""
    rng = np.random.default_rng(8)
    gated = Calibration.from_records(tailed(rng, 200), 1, alpha=0.1, edges=[0.0, 0.7],
                                     end_prob=0.5)
    plain = Calibration.from_records([r[:3] for r in tailed(rng, 200)], 1, alpha=0.1,
                                     edges=[0.0, 0.7])
    assert gated.end_prob == 0.5 and plain.end_prob is None
    assert np.isnan(gated.familiarity(1.6, np.ones(4), 0, ended=0.9))
    assert np.isfinite(plain.familiarity(1.6, np.ones(4), 0, ended=0.9))

    def fires(cal, recs):
        return np.mean([np.nanmin([cal.familiarity(t, v, k, e) for t, v, k, e in
                                   zip(*r)]) < cal.threshold for r in recs])

    assert 0.05 < fires(gated, tailed(rng, 400)) < 0.16
    odd = tailed(rng, 100, anomaly=3.0)
    assert fires(gated, odd) > fires(plain, odd) + 0.3


def test_a_gated_calibration_needs_the_ended_probabilities():
    rng = np.random.default_rng(9)
    with pytest.raises(ValueError, match="ended probability"):
        Calibration.from_records([r[:3] for r in tailed(rng, 5)], 1, end_prob=0.5)
    with pytest.raises(ValueError, match="end_prob"):
        Calibration.from_records(tailed(rng, 5), 1, end_prob=1.5)

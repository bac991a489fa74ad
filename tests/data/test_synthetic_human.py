"""Clean human reaches: via-points, bell-shaped speed, branches, intent blending."""

from __future__ import annotations

import numpy as np

from sandbox.data.synthetic.human import Reach, reach_positions, spline_through, switch_paths

POINTS = np.array([[1.10, -0.12, 0.25], [0.92, 0.0, 0.20], [0.80, 0.20, 0.20]])
TIMES = np.linspace(0.0, 2.0, 201)


def _speed(path: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.gradient(path, TIMES, axis=0), axis=1)


def test_spline_passes_through_its_points_at_chord_length_parameters():
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(POINTS, axis=0), axis=1))]
    assert np.allclose(spline_through(POINTS, chord / chord[-1]), POINTS, atol=1e-12)
    line = spline_through(POINTS[[0, 2]], np.array([0.0, 0.5, 1.0]))
    assert np.allclose(line[1], POINTS[[0, 2]].mean(axis=0))


def test_reach_rests_before_and_after_and_has_one_speed_peak():
    reach = Reach(points=POINTS, t_on=0.1, t_off=1.4)
    path = reach_positions(reach, TIMES)
    assert np.allclose(path[TIMES <= 0.1], POINTS[0])
    assert np.allclose(path[TIMES >= 1.4], POINTS[-1])
    speed = _speed(path)
    peak = int(np.argmax(speed))
    # bell-shaped: rises then falls (no second peak), peak near 40 % of the reach (skew 0.8)
    assert np.all(np.diff(speed[: peak + 1]) >= -1e-9)
    assert np.all(np.diff(speed[peak:]) <= 1e-9)
    assert 0.1 + 0.3 * 1.3 <= TIMES[peak] <= 0.1 + 0.5 * 1.3


def test_primary_and_corrective_submovements_still_end_at_the_end_point():
    reach = Reach(points=POINTS, t_on=0.0, t_off=1.5, primary=0.6, correction=0.15,
                  aim=np.array([0.03, -0.02, 0.04]))
    path = reach_positions(reach, TIMES)
    assert np.allclose(path[0], POINTS[0]) and np.allclose(path[TIMES >= 1.5], POINTS[-1])
    plain = reach_positions(Reach(points=POINTS, t_on=0.0, t_off=1.5), TIMES)
    # the primary submovement is faster than a single reach over the same time
    assert _speed(path).max() > 1.2 * _speed(plain).max()


def test_drift_moves_the_hand_only_after_the_reach():
    reach = Reach(points=POINTS, t_on=0.0, t_off=1.0, drift=np.array([0.01, 0.0, 0.01]))
    still = Reach(points=POINTS, t_on=0.0, t_off=1.0)
    a, b = reach_positions(reach, TIMES), reach_positions(still, TIMES)
    assert np.array_equal(a[TIMES <= 1.0], b[TIMES <= 1.0])
    moved = np.linalg.norm(a - b, axis=1)
    assert 0.003 < moved.max() <= np.sqrt(2) * 0.01 + 1e-12


def test_branch_is_zero_before_the_divergence_and_complete_at_the_end():
    branch = np.array([0.0, 0.18, 0.0])
    shared = reach_positions(Reach(points=POINTS, t_on=0.0, t_off=1.7), TIMES)
    left = reach_positions(Reach(points=POINTS, t_on=0.0, t_off=1.7, branch=branch, t_div=1.0),
                           TIMES)
    assert np.array_equal(left[TIMES <= 1.0], shared[TIMES <= 1.0])
    assert np.allclose(left[-1] - shared[-1], branch)
    assert np.allclose(Reach(points=POINTS, t_on=0, t_off=1, branch=branch).end,
                       POINTS[-1] + branch)


def test_switch_follows_a_then_b_continuously():
    a = reach_positions(Reach(points=POINTS, t_on=0.0, t_off=1.6), TIMES)
    b = a + np.array([0.0, -0.2, 0.0])
    out = switch_paths(a, b, TIMES, 0.8, 0.3)
    assert np.array_equal(out[TIMES <= 0.8], a[TIMES <= 0.8])
    assert np.allclose(out[TIMES >= 1.1], b[TIMES >= 1.1])
    assert np.abs(np.diff(out, axis=0)).max() < 0.02  # no jump between 10 ms rows

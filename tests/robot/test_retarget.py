"""Retargeting (issue 23 item 2): Baxter's or a task-space plan carried out by any arm."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.robot import Q_HOME, TIP_LINK, BaxterKinematics
from sandbox.robot.arms import ROBOTS, arm_spec
from sandbox.robot.retarget import Retargeter, check_reach, reachability


def _reachable_points(name: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """World tip positions of random configurations within the inner half of the limits."""
    arm = Retargeter(name)
    lo, hi = arm.kinematics.lower, arm.kinematics.upper
    mid, half = (lo + hi) / 2, np.minimum((hi - lo) / 4, np.pi / 2)
    return arm.tip(rng.uniform(mid - half, mid + half, (n, arm.dof)))


@pytest.mark.parametrize("name", ROBOTS)
def test_ik_round_trips_within_a_millimetre_on_reachable_points(name):
    points = _reachable_points(name, 40, np.random.default_rng(1))
    arm = Retargeter(name, tol=0.001)
    solved = arm.solve(points, arm_spec(name).q_home)
    assert solved.reached.all()
    assert np.max(np.linalg.norm(arm.tip(solved.q) - points, axis=1)) <= 0.001


@pytest.mark.parametrize("name", ROBOTS[1:])
def test_retargeted_plans_respect_the_arms_joint_and_speed_limits(name):
    """Baxter's recorded-like reach (home to a front point) through another arm."""
    baxter = BaxterKinematics()
    goal = baxter.ik([0.85, 0.15, 0.15]).q[0]
    times = np.linspace(0.0, 2.0, 41)
    s = (times / 2.0)[:, None]
    plan = Q_HOME + (10 * s**3 - 15 * s**4 + 6 * s**5) * (goal - Q_HOME)
    arm = Retargeter(name)
    out = arm.plan(times, plan)
    assert out.q.shape == (41, arm.dof) and out.reached.all()
    assert np.all(out.q >= arm.kinematics.lower) and np.all(out.q <= arm.kinematics.upper)
    speed = np.abs(np.diff(out.q, axis=0)) / np.diff(times)[:, None]
    assert np.all(speed <= arm.max_velocity + 1e-9)
    np.testing.assert_allclose(out.points, baxter.fk(plan, link=TIP_LINK))


def test_a_task_space_plan_is_followed_as_it_is():
    arm = Retargeter("panda")
    points = np.array([[0.7, 0.3, 0.1], [0.75, 0.25, 0.1], [0.8, 0.2, 0.1]])
    out = arm.plan([0.0, 0.5, 1.0], points)
    np.testing.assert_array_equal(out.points, points)
    assert out.reached.all() and np.all(out.error <= arm.tol)


def test_a_point_out_of_reach_is_reported_not_raised():
    arm = Retargeter("ur5")
    out = arm.solve(np.array([[0.8, 0.2, 0.1], [3.0, 0.0, 0.0]]), arm_spec("ur5").q_home)
    assert out.reached.tolist() == [True, False] and out.error[1] > 1.0
    assert np.all(out.q >= arm.kinematics.lower) and np.all(out.q <= arm.kinematics.upper)


def test_reachability_and_its_warning_below_095():
    near = np.array([[0.8, 0.2, 0.1]] * 19 + [[3.0, 0.0, 0.0]])
    assert reachability("kinova", near) == pytest.approx(0.95)
    with pytest.warns(UserWarning, match="reaches 0.50 of the training meeting points"):
        assert check_reach("panda", near[-2:]) == 0.5


@pytest.mark.parametrize("bad, match", [(np.zeros((3, 5)), "robot_part: expected Baxter joints"),
                                        (np.zeros(7), "robot_part"),
                                        (np.full((2, 3), np.nan), "robot_part")])
def test_bad_plans_are_refused(bad, match):
    with pytest.raises(ValueError, match=match):
        Retargeter("panda").task_points(bad)


def test_bad_plan_times_and_lengths_are_refused():
    arm = Retargeter("ur5")
    with pytest.raises(ValueError, match="times"):
        arm.plan([0.0, 0.0], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="expected 3 rows"):
        arm.plan([0.0, 1.0, 2.0], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="q_start"):
        arm.plan([0.0, 1.0], np.zeros((2, 3)), q_start=np.zeros(7))
    with pytest.raises(ValueError, match="robot: expected one of"):
        Retargeter("iiwa")

"""The paired robot motion: IK at the handover point, from Q_HOME, smooth, within limits."""

from __future__ import annotations

import numpy as np
import pytest

import sandbox.data.synthetic.generator as generator
from sandbox.data.synthetic import diverging_demos, objects_demos
from sandbox.data.synthetic.generator import generate
from sandbox.data.synthetic.robot import bump, joint_trajectory
from sandbox.data.synthetic.tasks import TaskSpec, Variability
from sandbox.robot import GRASP_OFFSET, Q_HOME, TIP_LINK, BaxterKinematics


@pytest.fixture(scope="module")
def kin():
    return BaxterKinematics()


@pytest.fixture(scope="module")
def demos():
    rng = np.random.default_rng(11)
    return objects_demos(15, rng) + diverging_demos(6, rng)


def test_final_configuration_puts_the_gripper_at_the_handover_target(kin, demos):
    q_end = np.array([d.robot[-1] for d in demos])
    targets = np.array([d.meta["handover_target"] for d in demos])
    errors = np.linalg.norm(kin.fk(q_end, link=TIP_LINK) - targets, axis=1)
    assert errors.max() <= 0.01 + 1e-9
    # the target is where the gripper meets the hand: the measured offset, +/- a few cm
    ends = np.array([d.meta["hand_end"] for d in demos])
    assert np.linalg.norm(np.median(targets - ends, axis=0) - GRASP_OFFSET) < 0.01
    assert np.linalg.norm(targets - ends - GRASP_OFFSET, axis=1).max() < 0.06


def test_robot_starts_at_home_and_stays_within_the_joint_limits(kin, demos):
    for d in demos:
        assert np.allclose(d.robot[0], Q_HOME, atol=1e-9)
        assert np.all(d.robot >= kin.lower - 1e-12) and np.all(d.robot <= kin.upper + 1e-12)


def test_robot_motion_is_smooth_and_ends_at_rest(demos):
    for d in demos:
        dt = np.diff(d.times)[:, None]
        vel = np.diff(d.robot, axis=0) / dt
        acc = np.diff(vel, axis=0) / dt[1:]
        assert np.abs(vel).max() < 3.0  # rad/s
        assert np.abs(acc).max() < 30.0  # rad/s^2
        assert np.abs(vel[-5:]).max() < 1e-6  # the arm has stopped before the recording ends


def test_robot_is_time_aligned_with_the_human(demos):
    for d in demos:
        on, off = d.meta["robot_time"]
        h_on, h_off = d.meta["reach_time"]
        assert 0.0 <= on <= 0.05 * d.duration
        assert abs(off - h_off) < 0.2 * d.duration
        assert off <= d.duration


def test_joint_trajectory_known_answer():
    times = np.linspace(0.0, 2.0, 201)
    goal = Q_HOME + 0.3
    lim = (np.full(7, -5.0), np.full(7, 5.0))
    q = joint_trajectory(times, goal, 0.2, 1.6, np.zeros(7), lim, skew=1.0)
    assert np.allclose(q[times <= 0.2], Q_HOME) and np.allclose(q[times >= 1.6], goal)
    assert np.allclose(q[times == 0.9], Q_HOME + 0.15)  # half-way at mid-time
    wobbly = joint_trajectory(times, goal, 0.2, 1.6, np.full(7, 0.1), lim, skew=1.0)
    assert np.allclose(wobbly[times == 0.9], Q_HOME + 0.25)
    assert np.allclose(wobbly[-1], goal)
    clipped = joint_trajectory(times, goal, 0.2, 1.6, np.zeros(7), (lim[0], Q_HOME + 0.1))
    assert np.allclose(clipped[-1], Q_HOME + 0.1)
    assert bump(np.array([0.0, 0.5, 1.0])).tolist() == [0.0, 1.0, 0.0]


def test_unreachable_handover_point_raises_instead_of_pairing_wrongly():
    far = TaskSpec("far", end=(2.5, 0.0, 0.2))
    with pytest.raises(ValueError, match="far.*reach"):
        generate([far], 2, np.random.default_rng(0), family="test", variability=Variability(),
                 max_redraws=2)


def test_failed_ik_redraws_the_end_point(monkeypatch, kin):
    real = generator.solve_handover
    calls = []

    def flaky(targets, tol):
        res = real(targets, tol)
        calls.append(len(targets))
        if len(calls) == 1:  # the first demonstration fails once
            res.success[0] = False
        return res

    monkeypatch.setattr(generator, "solve_handover", flaky)
    spec = TaskSpec("box", end=(0.81, 0.22, 0.17))
    var = Variability()
    demos = generate([spec], 3, np.random.default_rng(0), family="t", variability=var)
    monkeypatch.setattr(generator, "solve_handover", real)
    again = generate([spec], 3, np.random.default_rng(0), family="t", variability=var)
    assert calls == [3, 1]
    assert not np.allclose(demos[0].meta["hand_end"], again[0].meta["hand_end"])
    assert np.allclose(demos[1].meta["hand_end"], again[1].meta["hand_end"])
    error = np.linalg.norm(kin.fk(demos[0].robot[-1], link=TIP_LINK)
                           - demos[0].meta["handover_target"])
    assert error <= 0.01

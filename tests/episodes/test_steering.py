"""Policies for any arm (issue 23 items 2-3): retargeted plans, task-space models, outcomes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from sandbox.core import IProMP
from sandbox.data.synthetic import make_dataset
from sandbox.episodes.policies import IProMPPolicy, RecordedRobotPolicy, fit_family_model
from sandbox.episodes.scenarios import run_scenario
from sandbox.episodes.steering import meeting_points, reach_report
from sandbox.robot import Q_HOME, TIP_LINK, BaxterKinematics
from sandbox.robot.arms import ROBOTS, arm_spec
from sandbox.robot.retarget import IK_TOL, Retargeter


@pytest.fixture(scope="module")
def task_space():
    """A model of the diverging demos whose robot part is Baxter's fingertip (m)."""
    kin = BaxterKinematics()
    demos = [replace(d, robot=kin.fk(d.robot, link=TIP_LINK), robot_names=("x", "y", "z"),
                     robot_space="task")
             for d in make_dataset("diverging", 8, np.random.default_rng(0))]
    return IProMP(n_basis=15).fit(demos), demos


def _drive(policy, demo, dof: int):
    """Feed ``demo``'s hand at 50 Hz to ``policy``, the arm tracking its targets exactly."""
    q = np.array(arm_spec(policy.robot).q_home)
    for t in np.arange(0.0, demo.times[-1] - demo.times[0], 0.02):
        hand = np.array([np.interp(demo.times[0] + t, demo.times, c) for c in demo.human.T])
        obs = {"time": np.array([t]), "hand": hand, "q": q, "object": np.full(3, 5.0)}
        action = policy(obs)
        assert action.shape == (dof + 1,)
        q = action[:dof]
    return q


def test_a_task_space_model_meets_at_the_same_point_with_every_arm(task_space):
    model, demos = task_space
    ends = {}
    for name in ROBOTS:
        policy = IProMPPolicy(model, robot=name)
        q = _drive(policy, demos[3], arm_spec(name).dof)
        goal = policy.predictor.command(policy._last_time + policy.dt)[0]
        assert goal.shape == (3,) and not policy.retargeted and not policy.unreachable
        ends[name] = Retargeter(name).tip(q)
        assert np.linalg.norm(ends[name] - goal) <= IK_TOL
    spread = max(np.linalg.norm(a - b) for a in ends.values() for b in ends.values())
    assert spread <= 2 * IK_TOL


def test_a_baxter_joint_model_drives_another_arm_retargeted():
    model = fit_family_model("diverging")
    policy = IProMPPolicy(model, robot="ur5")
    assert policy.retargeted and policy.dof == 6
    np.testing.assert_array_equal(policy.max_velocity, Retargeter("ur5").max_velocity)
    fraction, note = reach_report(model, "ur5")
    assert fraction >= 0.95 and "retargeted" in note
    assert reach_report(model, "baxter") == (1.0, None)


@pytest.mark.parametrize("name", ROBOTS)
def test_every_arm_reaches_the_models_meeting_points(name):
    """The bases are placed so: at least 95 % (the warning's threshold), all in fact."""
    points = meeting_points(fit_family_model("diverging"), np.random.default_rng(0))
    assert points.shape == (5 * 21, 3)
    assert reach_report(fit_family_model("diverging"), name)[0] == 1.0


def test_a_meeting_point_out_of_reach_ends_unreachable_not_in_a_crash():
    """Baxter's arm stretched out to the left (0.9, 1.1, 0.3 m): beyond the UR5's reach."""
    times = np.linspace(0.0, 2.0, 21)
    robot = Q_HOME + np.linspace(0.0, 1.0, 21)[:, None] * (np.zeros(7) - Q_HOME)

    def factory(arm):
        return lambda model: RecordedRobotPolicy(times, robot, "left", arm=arm)

    far = run_scenario("diverging", factory("ur5"), n_episodes=1, robot="ur5")[0]
    assert not far.success and far.outcome == "unreachable" and far.final_distance > 0.3
    near = run_scenario("diverging", factory("baxter"), n_episodes=1)[0]
    assert near.outcome == "missed" and near.reach is None


def test_policies_refuse_an_unknown_arm_and_observations_of_another_arm():
    model = fit_family_model("diverging")
    with pytest.raises(ValueError, match="robot: expected one of baxter, panda, ur5, kinova"):
        IProMPPolicy(model, robot="iiwa")
    policy = IProMPPolicy(model, robot="kinova")
    obs = {"time": np.array([0.0]), "hand": np.array([1.0, 0.2, 0.1]), "q": Q_HOME,
           "object": np.zeros(3)}
    with pytest.raises(ValueError, match=r"obs\['q'\]"):
        policy(obs)
    with pytest.raises(ValueError, match="rng"):
        meeting_points(model, 0)


def test_scenario_files_name_the_arm(tmp_path):
    from sandbox.episodes.scenario_files import load_scenario

    path = tmp_path / "s.yaml"
    path.write_text("human: {task: left}\npolicy: {type: dynamic, dow_t: 0.2}\nrobot: panda\n")
    assert load_scenario(path).robot == "panda"
    assert load_scenario(path, robot="kinova").robot == "kinova"       # play --robot wins
    path.write_text("human: {task: left}\npolicy: {type: dynamic, dow_t: 0.2}\nrobot: iiwa\n")
    with pytest.raises(ValueError, match=r"robot: expected one of \['baxter', 'panda'"):
        load_scenario(path)
    path.write_text("human: {task: left}\npolicy: {type: dynamic, dow_t: 0.2}\n")
    assert load_scenario(path).robot == "baxter"

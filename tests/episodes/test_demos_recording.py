"""Teleop that records demonstrations: the CSV writer, the robot's paired motion, the
recorder, ``play --record-demos``, and record -> fit -> play through a pseudo-terminal."""

from __future__ import annotations

import doctest
import json
import re

import numpy as np
import pytest

import sandbox.data.writer
from sandbox.cli import main
from sandbox.data.recorded import TrialError, load_recorded, load_trial
from sandbox.data.spec import BUILT_IN, ROBOT_COLUMNS
from sandbox.data.synthetic.base import HAND_START
from sandbox.data.synthetic.robot import kinematics, robot_meeting
from sandbox.data.writer import RECORDED_COLUMNS, next_trial_path, write_trial
from sandbox.episodes.demos_recording import (
    DemoRecorder,
    HeldRobot,
    check_task_name,
    motion_span,
    teleop_trial,
)
from sandbox.robot import GRASP_OFFSET, Q_HOME, TIP_LINK

DT = 0.02  # the environment's control step (s)
LEFT = np.array([0.72, 0.26, 0.25])  # a handover place Baxter's left arm reaches


def hand_path(end=LEFT, idle=0.5, move=1.2, total=3.0):
    """A teleop-like hand: still for ``idle`` s, straight at constant speed for ``move`` s,
    then still; times at the control rate. Returns times (T,) and hand (T, 3)."""
    t = np.arange(0.0, total + DT / 2, DT)
    s = np.clip((t - idle) / move, 0.0, 1.0)[:, None]
    return t, HAND_START + s * (np.asarray(end) - HAND_START)


# -- the writer ------------------------------------------------------------------------------


def test_the_header_is_the_recorded_sets(recorded_dir):
    first = next(recorded_dir.glob("*/*.csv"))
    assert first.read_text().splitlines()[0] == ",".join(RECORDED_COLUMNS)


def test_the_header_has_every_built_in_column():
    wanted = {c for m in BUILT_IN.values() for c in m.dims} | set(ROBOT_COLUMNS) | {"t"}
    assert wanted <= set(RECORDED_COLUMNS)
    assert len(set(RECORDED_COLUMNS)) == len(RECORDED_COLUMNS)


def test_written_columns_load_back_and_absent_ones_are_missing(tmp_path):
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 2.0, 0.01)
    hand = rng.uniform(-0.5, 1.0, (t.size, 3))
    q = Q_HOME + rng.normal(0.0, 0.1, (t.size, 7))
    cols = {**{f"human_left_hand_{a}": hand[:, i] for i, a in enumerate("xyz")},
            **{n: q[:, i] for i, n in enumerate(ROBOT_COLUMNS)}, "right_s0": -0.285}
    (tmp_path / "task").mkdir()
    path = write_trial(tmp_path / "task" / "001.csv", t, cols)
    demo = load_trial(path, preprocess="none")
    np.testing.assert_allclose(demo.times, t, atol=1e-6)
    np.testing.assert_allclose(demo.human, hand, atol=1e-6)
    np.testing.assert_allclose(demo.robot, q, atol=1e-6)
    assert demo.task == "task"
    rows = path.read_text().splitlines()
    header = rows[0].split(",")
    cells = dict(zip(header, rows[1].split(","), strict=True))
    assert cells["right_s0"] == "-0.285000" and cells["emg0"] == cells["human_head_x"] == ""
    with pytest.raises(TrialError, match="fewer than 2 valid samples of 'arm'"):
        load_trial(path, observe="hand,arm")
    with pytest.raises(TrialError, match="'emg' is constant or missing"):
        load_trial(path, observe="hand,emg")


def test_a_hand_only_set_skips_every_trial_asked_for_the_arm(tmp_path):
    t, hand = hand_path()
    for k in range(2):
        write_trial(next_trial_path(tmp_path / "left"), t,
                    {**{f"human_left_hand_{a}": hand[:, i] for i, a in enumerate("xyz")},
                     **{n: Q_HOME[i] + 0.01 * k for i, n in enumerate(ROBOT_COLUMNS)}})
    demos, skipped = load_recorded(tmp_path, observe="hand")
    assert len(demos) == 2 and not skipped
    with pytest.warns(UserWarning, match="'arm'"):
        demos, skipped = load_recorded(tmp_path, observe="hand,arm")
    assert not demos and len(skipped) == 2
    assert all("fewer than 2 valid samples of 'arm'" in why for _, why in skipped)


def test_write_trial_refuses_bad_input(tmp_path):
    t = np.arange(5) * 0.1
    with pytest.raises(ValueError, match="got \\['human_left_foot_x'\\]"):
        write_trial(tmp_path / "a.csv", t, {"human_left_foot_x": t})
    with pytest.raises(ValueError, match="t"):  # the time is the times argument
        write_trial(tmp_path / "a.csv", t, {"t": t})
    with pytest.raises(ValueError, match=r"shape \(5,\), got shape \(4,\)"):
        write_trial(tmp_path / "a.csv", t, {"left_s0": t[:4]})
    with pytest.raises(ValueError, match="strictly increasing"):
        write_trial(tmp_path / "a.csv", t[::-1], {})
    write_trial(tmp_path / "a.csv", t, {})
    with pytest.raises(ValueError, match="expected a new file"):
        write_trial(tmp_path / "a.csv", t, {})


def test_trials_are_numbered_in_order(tmp_path):
    folder = tmp_path / "up"
    assert next_trial_path(folder) == folder / "001.csv" and folder.is_dir()
    for name in ("001.csv", "009.csv", "notes.csv", "7.txt"):
        (folder / name).write_text("")
    assert next_trial_path(folder).name == "010.csv"


def test_the_writer_doctest():
    assert doctest.testmod(sandbox.data.writer).failed == 0


# -- the robot's paired motion ------------------------------------------------------------


def test_the_robot_meets_the_hand_where_it_stopped_when_it_stopped():
    t = np.arange(0.0, 3.0, DT)
    q, error = robot_meeting(t, LEFT, 0.5, 1.7)
    assert q.shape == (t.size, 7) and error < 0.01
    tip = kinematics().fk(q, link=TIP_LINK)
    assert np.linalg.norm(tip[-1] - (LEFT + GRASP_OFFSET)) < 0.01
    np.testing.assert_allclose(q[t <= 0.5], np.broadcast_to(Q_HOME, q[t <= 0.5].shape))
    np.testing.assert_allclose(q[t >= 1.7], np.broadcast_to(q[-1], q[t >= 1.7].shape))
    assert np.abs(np.diff(q[(t > 0.5) & (t < 1.7)], axis=0)).max() > 0  # moves in between


def test_the_robot_refuses_an_unreachable_point_and_bad_times():
    t = np.arange(0.0, 2.0, DT)
    with pytest.raises(ValueError, match="out of reach"):
        robot_meeting(t, [2.5, 0.0, 0.0], 0.0, 1.0)
    with pytest.raises(ValueError, match="t_on < t_off"):
        robot_meeting(t, LEFT, 1.0, 1.0)
    with pytest.raises(ValueError, match="3 finite numbers"):
        robot_meeting(t, [1.0, np.nan, 0.0], 0.0, 1.0)


# -- a teleop episode as a trial -----------------------------------------------------------


def test_motion_span():
    t, hand = hand_path(idle=0.5, move=1.2)
    first, last = motion_span(hand)
    assert t[first] == pytest.approx(0.5) and t[last] == pytest.approx(1.7)
    assert motion_span(np.zeros((10, 3))) == (0, 0)


def test_a_teleop_episode_becomes_a_trial_aligned_with_the_hand():
    t, hand = hand_path(idle=0.5, move=1.2, total=4.0)
    seen = hand + np.random.default_rng(1).normal(0.0, 0.002, hand.shape)
    times, cols, info = teleop_trial(t, hand, seen, lead_s=0.1, tail_s=0.6)
    assert times[0] == 0.0 and np.allclose(np.diff(times), DT)
    assert info["reach_time"] == pytest.approx((0.1, 1.3))  # the idle start is cut to lead_s
    assert info["duration"] == pytest.approx(1.9)  # and the end to tail_s after the stop
    np.testing.assert_allclose(info["meeting"], LEFT)
    kept = (t >= 0.4 - 1e-9) & (t <= 2.3 + 1e-9)
    np.testing.assert_allclose(cols["human_left_hand_y"], seen[kept, 1])  # as the tracker saw
    q = np.column_stack([cols[n] for n in ROBOT_COLUMNS])
    moving = np.flatnonzero(np.abs(np.diff(q, axis=0)).max(axis=1) > 1e-9)
    assert times[moving[0]] == pytest.approx(0.1) and times[moving[-1] + 1] == pytest.approx(1.3)
    wrist = kinematics().fk(q, link="left_hand_link")
    np.testing.assert_allclose(cols["baxter_left_hand_z"], wrist[:, 2])


def test_a_quick_reach_still_gets_a_robot_motion_of_min_robot_s():
    t, hand = hand_path(idle=0.0, move=0.2, total=2.0)
    times, cols, info = teleop_trial(t, hand, hand, lead_s=0.0, tail_s=0.2, min_robot_s=0.5)
    assert info["reach_time"] == pytest.approx((0.0, 0.2))
    assert times[-1] == pytest.approx(0.7)  # robot over at 0.5 s, then the tail
    q = np.column_stack([cols[n] for n in ROBOT_COLUMNS])
    assert np.abs(q[times >= 0.5] - q[-1]).max() < 1e-12 < np.abs(q[10] - q[-1]).max()


def test_an_episode_that_does_not_reach_is_refused():
    t, hand = hand_path(end=HAND_START + [0.0, 0.03, 0.0])
    with pytest.raises(ValueError, match="3.0 cm from its start"):
        teleop_trial(t, hand, hand)
    t, hand = hand_path(end=[1.4, -0.6, -0.3])
    with pytest.raises(ValueError, match="out of reach"):
        teleop_trial(t, hand, hand)


# -- the recorder --------------------------------------------------------------------------


def test_the_recorder_saves_each_episode_once(tmp_path):
    recorder, rng = DemoRecorder(tmp_path, "left"), np.random.default_rng(0)
    for episode in range(2):
        recorder.start()
        t, hand = hand_path(total=2.5 + episode)
        seen = hand + rng.normal(0.0, 0.002, hand.shape)  # a still, noiseless hand is "frozen"
        for k in range(t.size):
            recorder.add(t[k], hand[k], seen[k])
            recorder.add(t[k], hand[k] + 1.0, seen[k] + 1.0)  # the same time again: ignored
        line = recorder.finish()
        assert f"saved demo {episode + 1} of 'left'" in line
        assert recorder.finish() is None  # nothing new to save
    assert [p.name for p in recorder.saved] == ["001.csv", "002.csv"]
    demos, _ = load_recorded(tmp_path)
    assert [d.task for d in demos] == ["left", "left"]
    np.testing.assert_allclose(demos[0].human[-1], LEFT, atol=0.01)


def test_the_recorder_says_why_an_episode_is_not_saved(tmp_path):
    recorder = DemoRecorder(tmp_path, "up")
    recorder.start()
    for k in range(50):
        recorder.add(k * DT, HAND_START, HAND_START)
    assert "not saved as a demo of 'up': the hand stopped 0.0 cm from its start" in \
        recorder.finish()
    assert recorder.saved == [] and not (tmp_path / "up").exists()


@pytest.mark.parametrize("name", ["", "../up", "a b", ".hidden", "x" * 65, 3])
def test_task_names_must_be_folder_names(name):
    with pytest.raises(ValueError, match="--task: expected a name"):
        check_task_name(name)


def test_the_held_robot_feeds_the_predictor_and_stays_home():
    class Policy:
        task, calls = "left", []

        def __call__(self, obs):
            self.calls.append(obs)
            return np.ones(8)

    policy = Policy()
    held = HeldRobot(policy)
    action = held({"time": [0.0]})
    np.testing.assert_array_equal(action, np.append(Q_HOME, -1.0))
    assert policy.calls == [{"time": [0.0]}] and held.task == "left"


def test_the_right_arm_is_the_environments():
    from sandbox.envs.robot import Q_RIGHT as ENV_Q_RIGHT
    from sandbox.episodes.demos_recording import Q_RIGHT

    np.testing.assert_array_equal(Q_RIGHT, ENV_Q_RIGHT)


@pytest.mark.parametrize("args, match", [
    (["--task", "left"], "--task: expected it with --record-demos"),
    (["--record-demos", "DIR"], "--record-demos: expected --task NAME"),
    (["--record-demos", "DIR", "--task", "a/b"], "--task: expected a name"),
    (["--record-demos", "DIR", "--task", "up", "--scenario", "waypoints"],
     "expected the keyboard teleop"),
])
def test_play_record_options_are_checked(args, match, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["play", *args]) == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "DIR").exists()


# -- record -> fit -> play, through a pseudo-terminal ---------------------------------------

#: Key script per task: the keys, the axis and the coordinates (m) at which each of three
#: demos halts the hand (x), as the status lines show it, and how an episode ends: "n" (the
#: last one "q"), or "limit" (a 3 s time limit; then q saves nothing more).
DEMO_SCRIPTS = {"left": ("wa", 1, (0.18, 0.22, 0.26), "n"),
                "up": ("wr", 2, (0.45, 0.50, 0.55), "limit")}


def _record(root, task, cwd):
    from tests.test_play import Terminal

    keys, axis, stops, end = DEMO_SCRIPTS[task]
    term = Terminal(["--record-demos", str(root), "--task", task, "--demos", "2",
                     "--time-limit", "3" if end == "limit" else "10"], cwd)
    try:
        term.wait_for(lambda s: "press space" in s, timeout=120, what="the first episode")
        assert "the robot holds still while you record" in term.text
        for i, stop in enumerate(stops):
            mark = len(term.text)
            term.type(keys + " ")  # directions first: the hand moves as the clock starts
            term.wait_for(lambda s, m=mark, a=axis, v=stop: any(
                h[a] > v for _, h, _, _ in term.statuses(m)), what=f"the hand past {stop}")
            term.type("x")
            if end == "limit":
                term.wait_for(lambda s, m=mark: "no handover by" in s[m:], what="the limit")
            else:
                term.drain(0.5)
                term.type("q" if i == len(stops) - 1 else "n")
            term.wait_for(lambda s, n=i + 1: f"saved demo {n} of '{task}'" in s,
                          what=f"demo {i + 1} saved")
            if i < len(stops) - 1:
                if end == "limit":
                    term.type("n")
                term.wait_for(lambda s, n=i + 2: f"episode {n}:" in s, what="the next episode")
        if end == "limit":
            term.type("q")
        assert term.proc.wait(timeout=30) == 0
        term.wait_for(lambda s: "3 demo(s) saved" in s, timeout=5, what="the goodbye")
        return term.text
    finally:
        term.close()


def _scenario(path, task, end):
    path.write_text(json.dumps({
        "name": f"to {task}", "family": "diverging", "seed": 0, "time_limit": 4.0,
        "human": {"task": task, "waypoints": [
            {"t": 0.0, "position": HAND_START.tolist()},
            {"t": 0.1, "position": HAND_START.tolist()},
            {"t": 1.6, "position": end}]},
        "policy": {"type": "dynamic", "dow_t": 0.2}}))
    return path


@pytest.mark.slow
def test_record_demos_fit_and_play_recognises_them(tmp_path, capsys):
    root = tmp_path / "demos"
    for task in DEMO_SCRIPTS:
        text = _record(root, task, tmp_path)
        stopped = [float(m) for m in re.findall(
            r"hand stopped at \(([-+\d.]+),([-+\d.]+),([-+\d.]+)\)", text)[0]]
        assert stopped[DEMO_SCRIPTS[task][1]] > DEMO_SCRIPTS[task][2][0]
    assert sorted(p.relative_to(root).as_posix() for p in root.rglob("*.csv")) == [
        f"{task}/{n:03d}.csv" for task in ("left", "up") for n in (1, 2, 3)]
    assert main(["fit", "--data", str(root), "--out", str(tmp_path / "model.npz")]) == 0
    assert "left                   3 demos" in capsys.readouterr().out
    for task, end in (("left", [0.72, 0.26, 0.25]), ("up", [0.78, -0.12, 0.55])):
        path = _scenario(tmp_path / f"{task}.json", task, end)
        assert main(["play", "--scenario", str(path), "--model", str(tmp_path / "model.npz"),
                     "--out", str(tmp_path / f"{task}.html"),
                     "--summary", str(tmp_path / f"{task}.json.summary.json")]) == 0
        summary = json.loads((tmp_path / f"{task}.json.summary.json").read_text())
        assert summary["final_task"] == task, summary["recognised"]
        assert summary["success"], summary  # the robot met the hand
        assert summary["handover_time_s"] < 2.5  # soon after the hand arrived (1.6 s)


def test_the_readme_workflow_commands_parse():
    import shlex

    from sandbox.cli import build_parser
    from tests.test_readme import _section

    section = _section("tutorials/own-demonstrations.md", "Record new tasks by teleop")
    lines = [line.split("#")[0] for line in re.findall(r"```text\n(.*?)```", section, re.S)[0]
             .splitlines() if line.startswith("python -m sandbox ")]
    assert [shlex.split(line)[3] for line in lines] == ["play", "play", "fit", "play"]
    for line in lines:
        args = build_parser().parse_args(shlex.split(line)[3:])
        assert args.command in ("play", "fit")
    recording = build_parser().parse_args(shlex.split(lines[0])[3:])
    assert (recording.record_demos, recording.task) == ("mydemos", "left")

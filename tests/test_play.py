"""``python -m sandbox play``: keyboard teleop through a pseudo-terminal, scenario files."""

from __future__ import annotations

import base64
import json
import os
import re
import select
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import umsgpack

from sandbox.cli import main
from sandbox.data.synthetic.base import HAND_START
from sandbox.episodes.keyboard import Keyboard, TeleopState, split_keys, status_line
from sandbox.episodes.scenario_files import load_scenario
from tests.viz.test_server import _servers_watching, _wait_gone

_XYZ = r"\(([-+\d.]+),([-+\d.]+),([-+\d.]+)\)"
STATUS = re.compile(rf"t=\s*([\d.]+)s hand={_XYZ} seen={_XYZ} m task=(\w+) p\[([^\]]+)\]")
AIM = re.compile(rf"gripper-hand=([\d.]+)m meet={_XYZ}")


# -- keys ----------------------------------------------------------------------------------


def test_direction_keys_set_and_halt_axes():
    state = TeleopState(speed=0.2)
    assert state.apply("w") == "move" and state.apply("r") == "move"
    np.testing.assert_allclose(state.velocity, [-0.2, 0.0, 0.2])
    state.apply("s")  # opposite of the x motion: halts x only
    np.testing.assert_allclose(state.velocity, [0.0, 0.0, 0.2])
    state.apply("a")
    state.apply("x")
    np.testing.assert_allclose(state.velocity, 0.0)


def test_speed_clock_and_commands():
    state = TeleopState(speed=0.2)
    state.apply("+")
    assert state.speed == pytest.approx(0.3)
    for _ in range(20):
        state.apply("+")
    assert state.speed == pytest.approx(0.6)  # capped
    assert state.apply(" ") == "clock" and state.running
    assert state.apply(" ") == "clock" and not state.running
    assert [state.apply(k) for k in "nqh?z"] == ["reset", "quit", "help", "help", None]


def test_slow_motion_key_and_reset_stops_the_clock():
    from sandbox.episodes.keyboard import SLOW_RATE

    state = TeleopState(running=True)
    assert state.rate == 1.0
    assert state.apply("c") == "slow" and state.slow and state.rate == SLOW_RATE < 1.0
    assert state.apply("c") == "slow" and not state.slow and state.rate == 1.0
    np.testing.assert_allclose(state.velocity, 0.0)  # the hand's own speed is not touched
    assert state.apply("n") == "reset" and not state.running  # the next episode waits


def test_escape_sequences_are_not_keys():
    assert split_keys("w\x1b[Aa\x1bOBq\x1b") == ["w", "a", "q"]


def test_keyboard_reads_a_pipe_until_it_closes():
    read, write = os.pipe()
    with Keyboard(read) as keyboard:  # not a terminal: the mode is left alone
        os.write(write, b"wa ")
        assert keyboard.read(1.0) == ["w", "a", " "]
        assert keyboard.read(0.0) == []
        os.close(write)
        assert keyboard.read(1.0) == [] and keyboard.closed
    os.close(read)


@pytest.fixture(scope="module")
def fitted():
    from sandbox.core import IProMP
    from sandbox.data.synthetic import diverging_demos

    demos = diverging_demos(6, np.random.default_rng(0), directions=("left", "right"))
    return IProMP(n_basis=10).fit(demos[1:]), demos[0]


def _predictor(fitted, familiar):
    """A real DynamicPredictor fed a demo; ``familiar`` set by a test double subclass."""
    from sandbox.core import DynamicPredictor

    class Double(DynamicPredictor):
        pass

    Double.familiar = familiar
    model, demo = fitted
    predictor = Double(model, dow_t=0.25)
    for t, y in zip(demo.times, demo.select("hand").human):
        predictor.observe(t, y)
    return predictor


def test_status_line_aims_distance_meeting_point_and_unsure(fitted):
    from sandbox.episodes.keyboard import UNSURE, meeting_point
    from sandbox.robot import BaxterKinematics

    kin, demo = BaxterKinematics(), fitted[1]
    for familiar in (None, True, False):
        predictor = _predictor(fitted, familiar)
        meet = meeting_point(predictor, kin)
        hand = np.array([0.9, 0.1, 0.2])
        line = status_line(1.0, hand, hand, predictor, gripper=hand + [0.0, 0.3, 0.4],
                           meeting=meet)
        assert STATUS.search(line)  # the first fields as before
        assert "gripper-hand=0.500m" in line  # a 3-4-5 triangle
        shown = re.search(rf"meet={_XYZ}", line)
        np.testing.assert_allclose([float(v) for v in shown.groups()], meet, atol=5e-4)
        assert (UNSURE in line) == (familiar is False)
    # where the whole demo's plan ends: near where the demonstrated gripper went
    end = kin.fk(demo.robot[-1], link="left_gripper")
    assert np.linalg.norm(meet - end) < 0.1


def test_status_line_has_the_posterior():
    class Predictor:
        task_posterior = {"left": 0.25, "right": 0.75}
        task, duration = "right", 2.5

    line = status_line(1.234, [1.1, -0.12, 0.25], [1.0, -0.1, 0.2], Predictor())
    match = STATUS.search(line)
    assert match and match.group(8) == "right" and "right=0.75" in match.group(9)
    assert float(match.group(6)) == pytest.approx(-0.1)  # seen y


# -- teleop through a pseudo-terminal ------------------------------------------------------


class Terminal:
    """``python -m sandbox play`` on a pseudo-terminal: type keys, read lines."""

    def __init__(self, args, cwd: Path) -> None:
        self.master, slave = os.openpty()
        self.proc = subprocess.Popen([sys.executable, "-m", "sandbox", "play", *args],
                                     stdin=slave, stdout=slave, stderr=slave, cwd=cwd,
                                     env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        os.close(slave)
        self.text = ""

    def _pump(self, timeout: float) -> None:
        ready, _, _ = select.select([self.master], [], [], timeout)
        if ready:
            try:
                self.text += os.read(self.master, 65536).decode("utf-8", "replace")
            except OSError:  # the child closed the terminal
                time.sleep(timeout)

    def wait_for(self, predicate, timeout: float = 60.0, what: str = ""):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            found = predicate(self.text)
            if found:
                return found
            self._pump(0.1)
        raise AssertionError(f"timed out waiting for {what}; output:\n{self.text[-3000:]}")

    def drain(self, seconds: float) -> None:
        """Read whatever comes during ``seconds``."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self._pump(0.05)

    def type(self, keys: str) -> None:
        os.write(self.master, keys.encode())

    def statuses(self, after: int = 0) -> list[tuple[float, np.ndarray, np.ndarray, dict]]:
        """(time, true hand, hand the policy saw, posterior) of each status line."""
        out = []
        for m in STATUS.finditer(self.text, after):
            probs = dict((k, float(v)) for k, v in (p.split("=") for p in m.group(9).split()))
            out.append((float(m.group(1)), np.array([float(m.group(i)) for i in (2, 3, 4)]),
                        np.array([float(m.group(i)) for i in (5, 6, 7)]), probs))
        return out

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        os.close(self.master)


def test_keys_move_the_hand_and_the_posterior_follows(tmp_path):
    term = Terminal(["--time-limit", "30"], tmp_path)
    try:
        url = term.wait_for(lambda s: re.search(r"meshcat viewer: (http://127\.0\.0\.1:\d+)", s),
                            timeout=240.0, what="the viewer's URL")   # fits first: slow under load
        assert url
        term.wait_for(lambda s: "press space" in s and "q  quit" in s, what="the help")
        assert "observes hand and re-predicts every 0.2 s" in term.text
        term.type("h")          # the help says where each task's hand ends
        term.wait_for(lambda s: "each task's hand ends" in s and "straight" in s,
                      what="the meeting points")
        servers = _servers_watching(term.proc.pid)
        assert len(servers) == 1
        term.drain(0.6)
        assert term.statuses() == []  # the clock waits for space
        term.type(" ")
        term.wait_for(lambda s: len(term.statuses()) >= 3, what="updates at the start")
        start = term.statuses()
        np.testing.assert_allclose(start[-1][1], HAND_START, atol=1e-3)  # not moving yet
        np.testing.assert_allclose(start[-1][2], HAND_START, atol=0.01)  # seen through noise
        mark = len(term.text)
        term.type("w")  # toward Baxter at 0.2 m/s
        term.wait_for(lambda s: "> w: hand velocity (-0.20" in s, what="the key's echo")
        term.wait_for(lambda s: any(h[0] < HAND_START[0] - 0.1 for _, h, _, _ in
                                    term.statuses(mark)), what="the hand to move in -x")
        term.type("a")  # and to Baxter's left
        term.wait_for(lambda s: any(h[1] > HAND_START[1] + 0.15 for _, h, _, _ in
                                    term.statuses(mark)), what="the hand to move in +y")
        moved = term.statuses(mark)
        seen = moved[-1][2]  # the tracker saw the hand where the keys took it
        np.testing.assert_allclose(seen, moved[-1][1], atol=0.03)
        assert seen[0] < HAND_START[0] - 0.1 and seen[1] > HAND_START[1] + 0.1
        changes = [max(abs(p[k] - start[0][3][k]) for k in p) for _, _, _, p in moved]
        assert max(changes) > 0.2, "the task posterior did not change"
        times = [t for t, _, _, _ in moved]
        assert times == sorted(times)
        aim = AIM.findall(term.text)  # the gripper-to-hand distance, the meeting point
        assert aim and all(0.0 <= float(d) < 2.0 and -2 < float(y) < 2 for d, _, y, _ in aim)
        term.type("c")
        term.wait_for(lambda s: "> slow motion on: the clock runs at x0.25" in s, what="slow")
        mark = len(term.text)
        term.type("n")  # a new episode: the hand back at the start, the clock stopped
        term.wait_for(lambda s: "episode 2" in s[mark:] and "press space" in s[mark:],
                      what="the reset")
        assert "slow motion is still on (c: off)" in term.text[mark:]   # a reminder (issue 27)
        term.drain(0.8)
        assert term.statuses(mark) == []  # the clock waits for space again
        term.type(" ")
        term.wait_for(lambda s: term.statuses(mark), what="an update after the reset")
        t, hand, _, _ = term.statuses(mark)[0]
        assert t < 1.0 and np.allclose(hand, HAND_START, atol=0.05)
        term.type("q")
        assert term.proc.wait(timeout=30) == 0
        term.wait_for(lambda s: "bye (2 episode(s))" in s, timeout=5, what="the goodbye")
        assert all(_wait_gone(pid) for pid in servers), "the meshcat server outlived play"
    finally:
        term.close()


# -- scenario files ------------------------------------------------------------------------

WAYPOINTS = {
    "name": "small reach", "seed": 2, "time_limit": 3.0,
    "human": {"waypoints": [{"t": 0.0, "position": [1.10, -0.12, 0.25]},
                            {"t": 1.4, "position": [0.80, 0.18, 0.22]}]},
    "policy": {"type": "dynamic", "dow_t": 0.25},
}
YAML = """\
name: static on an intent switch
family: diverging
seed: 0
time_limit: 2.0
human: {task: up, switch_to: right, switch_phase: 0.5}
policy: {type: static, ratio: 0.3}
model: {demos: 10, seed: 1}
"""


def _run(tmp_path, path, capsys):
    html, summary = tmp_path / "replay.html", tmp_path / "out" / "summary.json"
    assert main(["play", "--scenario", str(path), "--out", str(html),
                 "--summary", str(summary)]) == 0
    printed = capsys.readouterr().out
    assert html.stat().st_size > 1e6 and "replay:" in printed
    return json.loads(summary.read_text()), printed


def test_json_scenario_runs_to_completion(tmp_path, capsys):
    path = tmp_path / "reach.json"
    path.write_text(json.dumps(WAYPOINTS))
    summary, printed = _run(tmp_path, path, capsys)
    assert summary["scenario"] == "small reach" and summary["human"] == "waypoints"
    assert isinstance(summary["success"], bool)
    assert summary["final_distance_m"] >= 0 and summary["steps"] >= 1
    assert summary["success"] == (summary["handover_time_s"] is not None)
    assert summary["n_updates"] == len(summary["updates"]) >= 3
    assert summary["updates"][0]["time"] == pytest.approx(0.25, abs=0.03)  # dow_t from the file
    # one clock: the first recognition is the first update's, none before it
    assert summary["recognised"][0]["time"] == summary["updates"][0]["time"]
    assert printed.count("  t=") == summary["n_updates"]  # each update printed as it came


def test_yaml_scenario_with_the_static_policy(tmp_path, capsys):
    path = tmp_path / "switch.yaml"
    path.write_text(YAML)
    summary, _ = _run(tmp_path, path, capsys)
    assert summary["policy"] == "static" and summary["n_updates"] <= 1
    assert summary["intent_switch"]["from"] == "up" and summary["intent_switch"]["to"] == "right"
    assert summary["end_time_s"] <= 2.0 + 1e-9  # the file's time limit


def test_observe_key_and_option_choose_the_modalities(tmp_path, capsys):
    from sandbox.episodes.scenario_runner import build_model, make_policy

    path = tmp_path / "arm.yaml"
    path.write_text(YAML + "observe: hand,arm\n")
    scenario = load_scenario(path)
    assert scenario.observe == ("hand", "arm")
    assert load_scenario(path, observe="hand").observe == ("hand",)
    model = build_model(scenario)
    assert [m.name for m in model.modalities] == ["hand", "arm"]
    assert make_policy(scenario, model).observe == ("hand", "arm")
    path.write_text(YAML)
    html, out = tmp_path / "r.html", tmp_path / "s.json"
    assert main(["play", "--scenario", str(path), "--observe", "hand,arm", "--out", str(html),
                 "--summary", str(out)]) == 0
    assert "observing hand,arm" in capsys.readouterr().out
    assert json.loads(out.read_text())["observe"] == ["hand", "arm"]


def test_shipped_examples_are_valid():
    for name in ("intent_switch", "waypoints"):
        scenario = load_scenario(name)
        assert scenario.path.parent.name == "scenario_examples"


def test_recorded_scenario_holds_the_trial_out(recorded_dir, tmp_path, capsys):
    path = tmp_path / "recorded.json"
    path.write_text(json.dumps({"family": "objects", "time_limit": 1.0, "human": {
        "recorded": str(recorded_dir), "task": "pencil_box", "trial": 0},
        "policy": {"type": "dynamic"}}))
    scenario = load_scenario(path)
    assert scenario.human["task"] == "pencil_box" and scenario.human["trial"].endswith(".csv")
    summary, _ = _run(tmp_path, path, capsys)
    assert summary["task"] == "pencil_box" and summary["object"] == "box"
    assert "pencil_box" in summary["model_tasks"]
    blobs = re.findall(r'^"([A-Za-z0-9+/=]+)"', (tmp_path / "replay.html").read_text(),
                       flags=re.M)
    animated = {a["path"] for a in umsgpack.unpackb(base64.b64decode(blobs[-1]))["animations"]}
    assert any(p.startswith("/meshcat/bodies/tracked_arm/elbow") for p in animated)  # the arm


BAD = [
    ("bad.json", '{"human": {"task": "up"}, "policy": {"type": "dynamic"},\n "humn": 1}',
     "top level: expected keys among"),
    ("bad.json", '{"policy": {"type": "dynamic"}}', "human: expected this key"),
    ("bad.json", '{"human": {"task": "up"},\n "policy": {"type": "dynamic",}}',
     "invalid JSON at line 2"),
    ("bad.yaml", "human: {task: up\npolicy: dynamic\n", "invalid YAML at line"),
    ("bad.yaml", "- a list\n- not a mapping\n", "top level: expected a mapping"),
    ("bad.yaml", "human: {task: sideways}\npolicy: {type: dynamic}\n", "human.task"),
    ("bad.yaml", "human: {task: up}\npolicy: {type: greedy}\n", "policy.type"),
    ("bad.yaml", "human: {task: up}\npolicy: {type: static, dow_t: 0.2}\n", "policy (static)"),
    ("bad.yaml", "human: {task: up}\npolicy: {type: dynamic, dow_t: -1}\n", "policy.dow_t"),
    ("bad.yaml", "human: {task: up, switch_to: up}\npolicy: {}\n", "human.switch_to"),
    ("bad.yaml", "human:\n  waypoints: [{t: 0, position: [1, 0, 0]}, {t: 0, position: [1, 0, 0]}]"
                 "\npolicy: {}\n", "waypoints[1].t: expected a time after"),
    ("bad.yaml", "human:\n  waypoints: [{t: 0, position: [1, 0]}, {t: 1, position: [1, 0, 0]}]"
                 "\npolicy: {}\n", "waypoints[0].position"),
    ("bad.yaml", "human:\n  waypoints: [{t: 0, position: [1, 0, 0]}]\npolicy: {}\n",
     "at least 2 waypoints"),
    ("bad.yaml", "human:\n  waypoints: [{t: 0, position: [1, 0, 0]}, {t: 1, position: [1, 0, 0]}]"
                 "\n  tracker: {noise: 1}\npolicy: {}\n", "human.tracker"),
    ("bad.yaml", "human: {recorded: no/such/folder}\npolicy: {}\n", "human.recorded"),
    ("bad.yaml", "human: {task: up}\npolicy: {}\nspeed: 9\n", "speed"),
    ("bad.yaml", "human: {task: up}\npolicy: {}\nmodel: {file: missing.npz}\n", "model.file"),
    ("bad.txt", "{}", "expected a .json, .yaml or .yml file"),
    ("bad.yaml", "human: {task: up}\npolicy: {}\nobserve: [hand, emg]\n", "EMG is not simulated"),
    ("bad.yaml", "human: {task: up}\npolicy: {}\nobserve: [hand, leg]\n",
     "observe: expected distinct modalities"),
]


@pytest.mark.parametrize("name, text, match", BAD)
def test_bad_scenario_files_are_clear_errors(name, text, match, tmp_path, capsys):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError, match=re.escape(match)) as error:
        load_scenario(path)
    assert str(path) in str(error.value)  # the message names the file
    assert main(["play", "--scenario", str(path)]) == 2
    assert match in capsys.readouterr().err
    assert not list(tmp_path.glob("*.html"))


def test_missing_scenario_and_bad_options(tmp_path, capsys):
    assert main(["play", "--scenario", str(tmp_path / "nothing.json")]) == 2
    assert "intent_switch" in capsys.readouterr().err  # lists the shipped examples
    path = tmp_path / "opts.json"
    path.write_text(json.dumps({**WAYPOINTS, "policy": {"options": {"colour": 1}}}))
    assert main(["play", "--scenario", str(path), "--out", str(tmp_path / "r.html")]) == 2
    assert "policy.options" in capsys.readouterr().err
    assert main(["play", "--dow", "0"]) == 2
    assert "--dow" in capsys.readouterr().err

"""``python -m sandbox episodes``: policies side by side in the same seeded episodes."""

from __future__ import annotations

import json

import pytest

from sandbox.cli import main
from sandbox.episodes.scenarios import run_scenario, summarize


def test_policies_run_the_same_episodes_and_match_run_scenario(tmp_path, capsys):
    out = tmp_path / "episodes.json"
    assert main(["episodes", "--episodes", "2", "--seed", "3", "--policies", "dynamic,static",
                 "--json", str(out)]) == 0
    result = json.loads(out.read_text())
    assert list(result) == ["dynamic", "static"]
    for name, entry in result.items():
        assert [e["seed"] for e in entry["episodes"]] == [3, 4]
        expected = summarize(run_scenario("diverging", name, n_episodes=2, seed=3))
        summary = entry["summary"]
        assert {k: summary[k] for k in expected} == pytest.approx(expected, nan_ok=True)
        lo, hi = summary["success_rate_ci"]
        assert 0.0 <= lo <= summary["success_rate"] <= hi <= 1.0
    table = capsys.readouterr().out
    assert "| dynamic |" in table and "| static |" in table
    # what the table is over and how to read it (issue 27)
    assert "2 episodes per policy, seeds 3 to 4" in table
    assert "the mean over the successful episodes only" in table
    assert "recorded_robot is no predictor" not in table


def test_recorded_robot_beside_the_dynamic_policy(recorded_dir, tmp_path, capsys):
    out = tmp_path / "recorded.json"
    assert main(["episodes", "--scenario", "recorded", "--data", str(recorded_dir),
                 "--policies", "recorded_robot,dynamic", "--episodes", "1",
                 "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "1 episodes per policy, each replaying one recorded trial" in printed
    assert "recorded_robot is no predictor" in printed
    result = json.loads(out.read_text())
    trials = [entry["episodes"][0]["options"]["trial"] for entry in result.values()]
    assert trials[0] == trials[1]            # the same held-out trial for both


@pytest.mark.parametrize("argv, match", [
    (["--policies", "dynamic,greedy"], "--policies"),
    (["--policies", "dynamic,dynamic"], "--policies"),
    (["--policies", "recorded_robot"], "scenario='recorded'"),
    (["--scenario", "recorded"], "data"),
])
def test_bad_arguments_are_clear_errors(argv, match, capsys, tmp_path):
    assert main(["episodes", "--episodes", "1", *argv]) == 2
    assert match in capsys.readouterr().err


def test_json_pointing_at_a_folder_is_refused_before_any_episode(tmp_path, capsys):
    assert main(["episodes", "--episodes", "1", "--json", str(tmp_path)]) == 2
    assert "--json" in capsys.readouterr().err


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    """ROOT/<session>/<task>/<trial>.csv: the same synthetic:diverging trials twice (2 per
    task), the second session's tracker 4 cm off."""
    from tests.data.folders import write_synthetic_set

    root = tmp_path_factory.mktemp("sessions")
    for name, shift in (("monday", 0.0), ("tuesday", 0.04)):
        write_synthetic_set(root / name, "diverging", n_per_task=2, shift=shift)
    return root


def test_cross_session_replays_record_the_mode(sessions, tmp_path, capsys):
    out = tmp_path / "cross.json"
    monday, tuesday = sessions / "monday", sessions / "tuesday"
    assert main(["episodes", "--scenario", "recorded", "--data", str(monday), "--test",
                 str(tuesday), "--policies", "recorded_robot", "--episodes", "1", "--seed", "2",
                 "--json", str(out)]) == 0
    entry = json.loads(out.read_text())["recorded_robot"]
    assert entry["config"] == {"scenario": "recorded", "mode": "cross-session",
                               "observe": ["hand"], "train": str(monday),
                               "test": str(tuesday), "n_train": 10}
    (episode,) = entry["episodes"]
    from sandbox.episodes.replays import plan_replays

    (expected,) = plan_replays(monday, 1, 2, test=tuesday)
    assert episode["options"] == expected.options
    assert episode["replay"] == expected.provenance
    printed = capsys.readouterr().out
    assert f"cross-session: one model fitted on {monday} (10 trials)" in printed
    assert "| recorded_robot |" in printed and "by session" not in printed


def test_a_folder_of_sessions_is_replayed_leave_one_session_out(sessions, tmp_path, capsys):
    out = tmp_path / "loso.json"
    assert main(["episodes", "--scenario", "recorded", "--data", str(sessions),
                 "--policies", "recorded_robot", "--episodes", "2", "--seed", "5",
                 "--json", str(out)]) == 0
    entry = json.loads(out.read_text())["recorded_robot"]
    assert entry["config"]["mode"] == "leave-one-session-out"
    assert entry["config"]["sessions"] == ["monday", "tuesday"]
    drawn = [e["replay"]["session"] for e in entry["episodes"]]
    assert sorted(entry["per_session"]) == sorted(set(drawn))
    for session, summary in entry["per_session"].items():
        assert summary["n_episodes"] == drawn.count(session)
    for e in entry["episodes"]:
        assert e["replay"]["train"] == ({"monday", "tuesday"} - {e["replay"]["session"]}).pop()
    printed = capsys.readouterr().out
    assert "leave-one-session-out over 2 sessions: monday, tuesday" in printed
    assert "by session:" in printed and f"| recorded_robot | {drawn[0]} |" in printed


@pytest.mark.parametrize("case, match", [
    ("sessions", "--test: expected one set"),
    ("synthetic", "--test: expected with --scenario recorded"),
    ("missing", "--test: expected a folder <root>/<task>/<trial>.csv"),
    ("tasks", "has tasks ['right', 'straight', 'up'] that"),
])
def test_replays_that_cannot_run_exit_2_with_one_line(sessions, tmp_path, capsys, case, match):
    import shutil

    argv = ["--scenario", "recorded", "--policies", "recorded_robot", "--data",
            str(sessions / "monday"), "--test", str(sessions)]
    if case == "missing":
        argv[-1] = str(tmp_path / "nowhere")
    elif case == "synthetic":
        argv = ["--test", str(sessions / "monday")]
    elif case == "tasks":
        for task in ("down", "left"):
            shutil.copytree(sessions / "monday" / task, tmp_path / "two" / task)
        argv[-3:] = [str(tmp_path / "two"), "--test", str(sessions / "monday")]
    out = tmp_path / "never.json"
    assert main(["episodes", "--episodes", "1", *argv, "--json", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert match in err and "\n" not in err and not out.exists()


def test_recorded_halves_replayed_across_sessions(recorded_dir, tmp_path):
    """The recorded set split by recording time (links, no copies), with EMG: the late half's
    trials replayed with a model of the early half, in its meeting geometry."""
    from sandbox.data.geometry import learn_geometry
    from sandbox.data.recorded import load_recorded

    for task in ("screw_driver", "pencil_box"):
        for i, path in enumerate(sorted((recorded_dir / task).glob("*.csv"))[:8]):
            link = tmp_path / ("early" if i < 4 else "late") / task / path.name
            link.parent.mkdir(parents=True, exist_ok=True)
            link.symlink_to(path)
    out = tmp_path / "halves.json"
    assert main(["episodes", "--scenario", "recorded", "--data", str(tmp_path / "early"),
                 "--test", str(tmp_path / "late"), "--policies", "recorded_robot",
                 "--observe", "hand,emg", "--episodes", "2", "--json", str(out)]) == 0
    entry = json.loads(out.read_text())["recorded_robot"]
    assert entry["config"]["observe"] == ["hand", "emg"]
    early = learn_geometry(load_recorded(tmp_path / "early", observe=("hand", "emg"))[0])
    for e in entry["episodes"]:
        assert (tmp_path / "late" / e["task"] / e["options"]["trial"]).is_file()
        assert e["options"]["grasp_offset"][e["task"]] == pytest.approx(
            early.offsets()[e["task"]], abs=1e-12)

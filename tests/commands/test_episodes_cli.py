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


def test_recorded_robot_beside_the_dynamic_policy(recorded_dir, tmp_path):
    out = tmp_path / "recorded.json"
    assert main(["episodes", "--scenario", "recorded", "--data", str(recorded_dir),
                 "--policies", "recorded_robot,dynamic", "--episodes", "1",
                 "--json", str(out)]) == 0
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

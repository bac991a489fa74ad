"""``--session S`` of ``fit`` and ``evaluate``: a synthetic set's recording session, no folders."""

from __future__ import annotations

import json

import pytest

from sandbox.cli import main


def test_fit_accepts_a_session_of_a_synthetic_set(tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert main(["fit", "--data", "synthetic:objects", "--session", "3", "--n-per-task", "3",
                 "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["session"] == 3 and out.is_file()


@pytest.mark.parametrize("command", [["fit", "--out", "m.npz"], ["evaluate", "--out", "r.json"]])
def test_a_session_with_a_folder_is_one_error_line(command, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "set" / "a").mkdir(parents=True)
    assert main([*command, "--data", str(tmp_path / "set"), "--session", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: session: only for synthetic:NAME data") and "\n" not in err
    assert not (tmp_path / command[2]).exists()


@pytest.mark.parametrize("command", [["fit", "--out", "m.npz"], ["evaluate", "--out", "r.json"]])
@pytest.mark.parametrize("value", ["-1", "x", "1.5"])
def test_a_bad_session_is_refused_by_argparse(command, value, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main([*command, "--data", "synthetic:objects", "--session", value]) == 2
    assert "argument --session: expected a non-negative integer" in capsys.readouterr().err


QUICK = ["--n-per-task", "3", "--windows", "0.5", "--ratios", "0.5", "--workers", "1",
         "--no-progress"]


def test_evaluate_across_two_synthetic_sessions_says_which(tmp_path):
    out = tmp_path / "r.json"
    assert main(["evaluate", "--data", "synthetic:objects", "--session", "1", "--test",
                 "synthetic:objects", "--test-session", "2", *QUICK, "--out", str(out)]) == 0
    config = json.loads(out.read_text())["config"]
    assert (config["mode"], config["session"], config["test_session"]) == ("cross-session", 1, 2)


def test_test_session_needs_a_synthetic_test_set(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "set" / "a").mkdir(parents=True)
    for extra, message in ((["--test-session", "2"], "error: --test-session: expected with --test"),
                           (["--test", str(tmp_path / "set"), "--test-session", "2"],
                            "session: only for synthetic:NAME data")):
        assert main(["evaluate", "--data", "synthetic:objects", *extra, *QUICK,
                     "--out", "r.json"]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and "\n" not in err
    assert not (tmp_path / "r.json").exists()

"""``evaluate --tail KIND [--tail-in-training]``: emulated motion tails on the test streams."""

from __future__ import annotations

import json

import pytest

from sandbox.cli import main

QUICK = ["--data", "synthetic:two_task", "--n-per-task", "3", "--windows", "0.5", "--ratios",
         "0.5", "--workers", "1", "--no-progress"]


def test_a_tail_is_said_in_the_report(tmp_path):
    out = tmp_path / "r.json"
    assert main(["evaluate", *QUICK, "--tail", "freeze", "--tail-in-training",
                 "--out", str(out)]) == 0
    config = json.loads(out.read_text())["config"]
    assert (config["tail"], config["tail_in_training"]) == ("freeze", True)


@pytest.mark.parametrize(("extra", "message"), [
    (["--tail-in-training"], "error: --tail-in-training: expected with --tail KIND"),
    (["--tail", "hold", "--test", "synthetic:two_task"], "error: --tail: expected the "
                                                         "leave-one-out of one set"),
])
def test_a_tail_outside_a_leave_one_out_is_one_error_line(extra, message, tmp_path,
                                                          monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["evaluate", *QUICK, *extra, "--out", "r.json"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(message) and "\n" not in err
    assert not (tmp_path / "r.json").exists()


def test_an_unknown_tail_is_refused_by_argparse(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["evaluate", *QUICK, "--tail", "wobble", "--out", "r.json"]) == 2
    assert "argument --tail: invalid choice" in capsys.readouterr().err

"""``python -m sandbox compare``: one-line errors, the files it writes, Ctrl-C."""

from __future__ import annotations

import json

import pytest

from sandbox.cli import main
from tests.commands.test_exits_cli import _interrupt


@pytest.mark.parametrize("methods, message", [
    ("bip,foo", "--methods: expected distinct names among dynamic, static, bip, ebip, dtw, "
                "nearest, got bip,foo (unknown: foo)"),
    ("bip,bip", "--methods: expected distinct names among dynamic, static, bip, ebip, dtw, "
                "nearest, got bip,bip"),
])
def test_a_bad_method_is_one_line_naming_the_valid_ones(methods, message, tmp_path, capsys):
    assert main(["compare", "--data", "synthetic:two_task", "--methods", methods,
                 "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"error: {message}"
    assert not (tmp_path / "c").exists()


def test_an_unknown_modality_is_one_line_naming_the_valid_ones(tmp_path, capsys):
    assert main(["compare", "--data", "synthetic:two_task", "--observe", "gaze",
                 "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gaze" in err[0] and "hand" in err[0]


def test_one_task_cannot_measure_recognition(tmp_path, capsys):
    assert main(["compare", "--data", "synthetic:two_task", "--tasks", "left",
                 "--n-per-task", "3", "--methods", "nearest", "--out", str(tmp_path / "c"),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --data: expected at least two tasks") and "--holdout" in err
    assert "\n" not in err


def test_compare_writes_one_row_per_method_and_resumes(tmp_path, capsys):
    argv = ["compare", "--data", "synthetic:two_task", "--n-per-task", "3", "--methods",
            "nearest,dtw", "--out", str(tmp_path), "--workers", "1", "--no-progress"]
    assert main(argv) == 0
    out = json.loads((tmp_path / "compare.json").read_text())
    assert list(out["rows"]) == ["nearest", "dtw"] and out["n_trials"] == 6
    assert (tmp_path / "recognition.png").stat().st_size > 0
    before = (tmp_path / "methods" / "dtw.json").stat().st_mtime_ns
    assert main(argv) == 0
    assert (tmp_path / "methods" / "dtw.json").stat().st_mtime_ns == before
    capsys.readouterr()
    (tmp_path / "other.txt").write_text("x")
    assert main(argv) == 2
    assert "other.txt" in capsys.readouterr().err


def test_ctrl_c_in_compare_is_130_with_no_partial_file(tmp_path):
    status, err = _interrupt(["compare", "--data", "synthetic:two_task", "--n-per-task", "10",
                              "--methods", "bip,ebip", "--workers", "2",
                              "--out", str(tmp_path)], b"trials:", "stderr")
    assert status == 130 and "Traceback" not in err and "interrupted" in err
    assert not (tmp_path / "compare.json").exists()
    assert not list(tmp_path.rglob("*.tmp"))

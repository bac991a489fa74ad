"""Folders of sessions (``<root>/<session>/<task>/<trial>.csv``) told apart from one set."""

from __future__ import annotations

from pathlib import Path

import pytest

from sandbox.data.sessions import check_sessions, find_sessions


def touch(root: Path, *names: str) -> Path:
    for name in names:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text("t\n")
    return root


def test_a_set_has_no_sessions(tmp_path):
    root = touch(tmp_path, "up/001.csv", "down/001.csv")
    assert find_sessions(root) == []


def test_sessions_are_the_subfolders_whose_subfolders_hold_trials_sorted(tmp_path):
    root = touch(tmp_path, "b/up/001.csv", "a/up/001.csv", "a/down/002.csv", "c/down/1.csv")
    (tmp_path / "empty" / "nothing").mkdir(parents=True)      # ignored, as empty tasks are
    (tmp_path / "notes.txt").write_text("not a folder")
    assert find_sessions(root) == [root / "a", root / "b", root / "c"]
    assert check_sessions(str(root)) == [root / "a", root / "b", root / "c"]


@pytest.mark.parametrize("names", [
    ("up/001.csv", "monday/up/001.csv"),              # a task folder beside a session
    ("monday/001.csv", "monday/up/001.csv", "tuesday/up/001.csv"),  # both in one folder
])
def test_a_folder_mixing_tasks_and_sessions_is_one_error_naming_both(tmp_path, names):
    root = touch(tmp_path, *names)
    with pytest.raises(ValueError, match="got both") as info:
        find_sessions(root, "--data")
    message = str(info.value)
    assert message.startswith("--data: ") and "\n" not in message and "monday" in message


def test_one_session_is_nothing_to_leave_out(tmp_path):
    root = touch(tmp_path, "only/up/001.csv", "only/down/001.csv")
    assert find_sessions(root) == [root / "only"]
    with pytest.raises(ValueError, match=r"at least 2 sessions .* got 1 \(only\)"):
        check_sessions(root)
    with pytest.raises(ValueError, match="got none"):
        check_sessions(touch(tmp_path / "set", "up/001.csv"))


@pytest.mark.parametrize("root", ["no/such/folder", 3])
def test_not_a_folder_is_an_error(tmp_path, root):
    with pytest.raises(ValueError, match="expected a folder"):
        find_sessions(tmp_path / root if isinstance(root, str) else root)

"""``evaluate --data A --test B`` (cross-session) and leave-one-session-out of a folder of
sessions (issue 21, item 3)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main
from tests.commands.test_observe_cli import write_set
from tests.data.folders import write_synthetic_set

SMALL = ["--data", "synthetic:two_task", "--n-per-task", "3"]
#: A quick evaluation: one window, one ratio, in this process.
QUICK = ["--windows", "0.2", "--ratios", "0.5", "--workers", "1", "--no-progress"]
#: The sessions of the folder of sessions: the last one 3 cm off in the tracker's frame.
SHIFTS = {"monday": 0.0, "tuesday": 0.0, "wednesday": 0.03}


def evaluate(tmp_path: Path, *argv: str, name: str = "r.json") -> dict:
    out = tmp_path / name
    assert main(["evaluate", *QUICK, *argv, "--out", str(out), "--force"]) == 0
    return json.loads(out.read_text())


def close(a, b) -> bool:
    """``a == b`` with numbers equal to 1e-9 (a model saved and loaded again, or fitted in
    another order, may differ in the last bits)."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(close(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(close, a, b))
    if isinstance(a, float):
        return b == pytest.approx(a, rel=1e-9, abs=1e-12, nan_ok=True)
    return a == b


@pytest.fixture(scope="module")
def sessions(tmp_path_factory) -> Path:
    """ROOT/<session>/<task>/<trial>.csv: three sessions of synthetic:two_task, 3 per task."""
    root = tmp_path_factory.mktemp("sessions")
    for seed, (name, shift) in enumerate(SHIFTS.items()):
        write_synthetic_set(root / name, seed=seed, shift=shift)
    return root


@pytest.fixture(scope="module")
def loso(sessions, tmp_path_factory) -> dict:
    return evaluate(tmp_path_factory.mktemp("loso"), "--data", str(sessions),
                    "--markdown", str(sessions.parent / "loso.md"))


def test_test_on_the_training_set_predicts_as_its_fitted_model(tmp_path):
    """``--data A --test A`` gives the per-trial predictions of ``--model`` fitted on A."""
    model = tmp_path / "model.npz"
    assert main(["fit", *SMALL, "--out", str(model)]) == 0
    cross = evaluate(tmp_path, *SMALL, "--test", "synthetic:two_task", name="cross.json")
    test_only = evaluate(tmp_path, *SMALL, "--model", str(model), name="model.json")
    assert close(cross["per_trial"], test_only["per_trial"])
    assert close(cross["dynamic"], test_only["dynamic"])
    assert close(cross["static"], test_only["static"])
    config = cross["config"]
    assert config["mode"] == "cross-session"
    assert config["train"] == config["test"] == "synthetic:two_task"
    assert (config["n_train"], config["n_test"]) == (6, 6)


def test_signals_are_normalised_with_the_training_sessions_only(tmp_path):
    """A test session whose grip signal has another gain: still predicted as by ``fit`` on
    the training session (whose signal scale the model keeps)."""
    spec = tmp_path / "spec.yaml"
    spec.write_text("time: stamp\nrobot: [j0, j1, j2, j3, j4, j5, j6]\nobserve: [wrist]\n"
                    "modalities:\n  wrist: {columns: [wx, wy, wz], kind: position}\n"
                    "  grip: {columns: [g0, g1], kind: signal, units: raw}\n")
    train = write_set(tmp_path / "a", n_per_task=3)
    test = write_set(tmp_path / "b", n_per_task=3)
    for path in test.rglob("*.csv"):            # the second session's sensor: 3x the gain
        lines = path.read_text().splitlines()
        rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
        rows[:, 4:6] *= 3.0
        path.write_text(lines[0] + "\n" + "\n".join(",".join(f"{v:.6f}" for v in r)
                                                    for r in rows) + "\n")
    common = ["--spec", str(spec), "--observe", "wrist,grip"]
    model = tmp_path / "m.npz"
    assert main(["fit", "--data", str(train), *common, "--out", str(model)]) == 0
    cross = evaluate(tmp_path, "--data", str(train), "--test", str(test), *common,
                     name="cross.json")
    test_only = evaluate(tmp_path, "--data", str(test), "--model", str(model), *common,
                         name="model.json")
    assert close(cross["per_trial"], test_only["per_trial"])


def test_leave_one_session_out_reports_every_trial_once_with_its_session(sessions, loso):
    config = loso["config"]
    assert config["mode"] == "leave-one-session-out"
    assert config["sessions"] == list(SHIFTS)
    assert config["session_trials"] == {name: 6 for name in SHIFTS}
    files = sorted(str(p) for p in sessions.rglob("*.csv"))
    assert sorted(r["source"] for r in loso["per_trial"]) == files
    for row in loso["per_trial"]:
        assert Path(row["source"]).relative_to(sessions).parts[0] == row["session"]
    assert sum(loso["n_trials"].values()) == len(files) == 18
    assert set(loso["per_session"]) == set(SHIFTS)
    markdown = (sessions.parent / "loso.md").read_text()
    assert "leave-one-session-out over 3 sessions" in markdown and "By session" in markdown


@pytest.mark.parametrize("left_out", list(SHIFTS))
def test_per_session_figures_are_those_of_the_others_tested_on_it(sessions, loso, left_out,
                                                                  tmp_path):
    others = tmp_path / "others"
    for name in SHIFTS:
        if name != left_out:
            shutil.copytree(sessions / name, others / name)
    cross = evaluate(tmp_path, "--data", str(others), "--test", str(sessions / left_out))
    assert cross["config"]["train"] == str(others) and cross["config"]["n_train"] == 12
    figures = loso["per_session"][left_out]
    assert figures["n_trials"] == cross["n_trials"]
    for section in ("static", "dynamic"):
        for key, entry in figures[section].items():
            assert close(entry, {m: cross[section][key]["mean"][m] for m in entry})
    mine = [r for r in loso["per_trial"] if r["session"] == left_out]
    assert close([{**r, "source": Path(r["source"]).name} for r in cross["per_trial"]], [
        {k: Path(v).name if k == "source" else v for k, v in r.items() if k != "session"}
        for r in mine])


def mixed(tmp_path: Path) -> Path:
    root = write_synthetic_set(tmp_path / "mixed" / "monday", n_per_task=2)
    (tmp_path / "mixed" / "left").mkdir()
    shutil.copy(next((root / "left").glob("*.csv")), tmp_path / "mixed" / "left")
    return tmp_path / "mixed"


@pytest.mark.parametrize(("argv", "words"), [
    (lambda d: ["--data", str(d / "right-only"), "--test", "synthetic:two_task"],
     "--test: synthetic:two_task has tasks ['left'] that"),
    (lambda d: ["--data", "synthetic:two_task", "--test", "synthetic:two_task", "--model",
                str(d / "m.npz")], "--test: expected either --test"),
    (lambda d: ["--data", str(mixed(d))], "got both in"),
    (lambda d: ["--data", str(d / "sessions")], "expected at least 2 sessions"),
    (lambda d: ["--data", str(d / "sessions"), "--model", str(d / "m.npz")],
     "--model: expected --data to be one set"),
    (lambda d: ["--data", "synthetic:two_task", "--test", str(d / "sessions")],
     "--test: expected one set"),
])
def test_what_cannot_run_is_one_line_and_writes_nothing(tmp_path, capsys, argv, words):
    write_synthetic_set(tmp_path / "right-only", n_per_task=2)
    shutil.rmtree(tmp_path / "right-only" / "left")
    write_synthetic_set(tmp_path / "sessions" / "only", n_per_task=2)
    (tmp_path / "m.npz").write_text("not read")
    out, markdown = tmp_path / "r.json", tmp_path / "r.md"
    status = main(["evaluate", "--n-per-task", "2", *QUICK, *argv(tmp_path), "--out", str(out),
                   "--markdown", str(markdown)])
    err = capsys.readouterr().err
    assert status == 2 and words in err, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists() and not markdown.exists()


def test_help_names_the_options(capsys):
    with pytest.raises(SystemExit):
        main(["evaluate", "--help"])
    text = " ".join(capsys.readouterr().out.split()).replace("- ", "-")   # unwrapped
    assert "--test DIR|synthetic:NAME" in text and "leave-one-session-out" in text
    assert "--test-seed" in text


def test_a_test_seed_needs_a_test_set(tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["evaluate", *SMALL, *QUICK, "--test-seed", "1", "--out", str(out)]) == 2
    assert "--test-seed: expected with --test" in capsys.readouterr().err
    assert not out.exists()


def test_recorded_halves_left_out_in_turn(recorded_dir, tmp_path):
    """The recorded set split by recording time into two sessions (links, no copies), with
    EMG: every trial predicted once, by the other half."""
    tasks = ["screw_driver", "pencil_box"]
    for task in tasks:
        files = sorted((recorded_dir / task).glob("*.csv"))[:8]
        for i, path in enumerate(files):
            link = tmp_path / "halves" / ("early" if i < 4 else "late") / task / path.name
            link.parent.mkdir(parents=True, exist_ok=True)
            link.symlink_to(path)
    report = evaluate(tmp_path, "--data", str(tmp_path / "halves"), "--tasks", ",".join(tasks),
                      "--observe", "hand,emg")
    assert report["config"]["sessions"] == ["early", "late"]
    assert report["config"]["observe"] == ["hand", "emg"]
    rows = report["per_trial"]
    names = [Path(r["source"]).name for r in rows]          # usable ones, each once
    assert len(set(names)) == len(names) == sum(report["n_trials"].values()) >= 12
    assert set(names) <= {p.name for p in (tmp_path / "halves").rglob("*.csv")}
    assert {r["session"] for r in rows} == {"early", "late"}
    assert set(report["per_session"]) == {"early", "late"}

"""Tests of ``python -m sandbox data ...`` and ``fit``, through sandbox.cli.main."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main
from sandbox.data.recorded import HUMAN_COLUMNS, ROBOT_COLUMNS


def write_trial(path: Path, n: int = 60, seed: int = 0, end_z: float = 0.2) -> Path:
    """A 30 Hz hand on 90 Hz rows (each frame sent 3 times), a smooth robot whose
    fingertip ends 2 cm above where the hand ends (a handover: ``fit`` learns where)."""
    from sandbox.robot import TIP_LINK, BaxterKinematics

    rng = np.random.default_rng(seed)
    t = np.arange(n) / 90.0 * (1 + 0.1 * seed)
    s = np.clip(t / t[-1], 0, 1)
    s = s**3 * (10 - 15 * s + 6 * s**2)
    robot = 0.1 * np.arange(7) + s[:, None] * (0.2 + 0.5 * end_z)
    start = np.array([1.1, -0.1, 0.25])
    end = BaxterKinematics().fk(robot[-1], link=TIP_LINK) - [0.0, 0.0, 0.02]
    hand = start + s[:, None] * (end - start)
    hand = hand + rng.normal(0, 1e-3, hand.shape)
    hand = hand[(np.arange(n) // 3) * 3]  # sample-and-hold at a third of the row rate
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [",".join(["t", *HUMAN_COLUMNS, *ROBOT_COLUMNS])]
    lines += [",".join(f"{v:.6f}" for v in row) for row in np.column_stack([t, hand, robot])]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    root = tmp_path / "set"
    for task, end_z in (("low", 0.05), ("high", 0.35)):
        for i in range(4):
            write_trial(root / task / f"trial{i}.csv", seed=i, end_z=end_z)
    (root / "low" / "broken.csv").write_text("t,human_left_hand_x\n")
    return root


def test_summary_text(folder, capsys):
    assert main(["data", "summary", "--data", str(folder), "--synthetic", "none"]) == 0
    out = capsys.readouterr().out
    assert "8 trials in 2 tasks (1 skipped)" in out
    assert "low" in out and "high" in out
    assert "broken.csv: missing column 'human_left_hand_y'" in out
    assert "rows repeating the previous time stamp" in out
    assert "Realism" not in out


def test_summary_json(folder, capsys):
    assert main(["data", "summary", "--data", str(folder), "--json", "--synthetic", "none"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert {t: r["trials"] for t, r in result["tasks"].items()} == {"high": 4, "low": 4}
    assert result["all"]["rows_per_s"] == pytest.approx(60 * 8 / sum(
        59 / 90 * (1 + 0.1 * i) for i in range(4)) / 2)
    # every frame is sent 3 times: 2 of 3 rows are re-sent frames, 1 of 3 rows a new one
    assert result["glitches"]["stale_rows"]["fraction_of_rows"] == pytest.approx(2 / 3, abs=0.01)
    assert result["all"]["frames_per_s"] == pytest.approx(result["all"]["rows_per_s"] / 3, 0.02)
    assert result["skipped"][0]["file"].endswith("broken.csv")
    assert result["realism"] is None


def test_summary_task_subset_and_realism(folder, capsys):
    args = ["data", "summary", "--data", str(folder), "--tasks", "high", "--json",
            "--synthetic", "two_task"]
    assert main(args) == 0
    result = json.loads(capsys.readouterr().out)
    assert list(result["tasks"]) == ["high"]
    assert set(result["realism"]["table"]) >= {"duration", "peak_speed"}


def test_check_filter(folder, capsys):
    assert main(["data", "check-filter", "--data", str(folder), "--json",
                 "--accel-std", "4"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["trials"] == 8 and result["config"]["accel_std"] == 4
    assert result["hidden_frames"] > 0
    assert 0 < result["smooth_error_mm"]["median"] < 20
    assert main(["data", "check-filter", "--data", str(folder)]) == 0
    assert "RTS smoother" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, match",
    [
        (["data", "summary", "--data", "no/such/dir"], "expected a folder"),
        (["data", "summary", "--data", "{folder}", "--tasks", "mid"], "unknown ['mid']"),
        (["data", "summary", "--data", "{folder}", "--synthetic", "zzz"], "--synthetic"),
        (["data", "check-filter", "--data", "{folder}", "--noise-std", "-1"], "noise_std"),
    ],
)
def test_bad_input_exits_2_with_a_message(folder, capsys, argv, match):
    argv = [a.replace("{folder}", str(folder)) for a in argv]
    assert main(argv) == 2
    assert match in capsys.readouterr().err


def test_summary_of_the_recorded_set(recorded_dir, capsys):
    assert main(["data", "summary", "--data", str(recorded_dir), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert {t: r["trials"] for t, r in result["tasks"].items()} == {
        "pencil_box": 42, "measurement_tape": 47, "gummed_paper": 40, "screw_driver": 45}
    assert result["skipped"] == []
    assert 0.35 < result["glitches"]["repeated_timestamps"]["fraction_of_rows"] < 0.45
    assert 90 < result["all"]["rows_per_s"] < 110
    assert 25 < result["modalities"]["hand"]["samples_per_s"] < 31


def test_summary_of_the_recorded_set_with_every_modality(recorded_dir, capsys):
    assert main(["data", "summary", "--data", str(recorded_dir), "--observe", "hand,arm,emg",
                 "--tasks", "pencil_box", "--synthetic", "none"]) == 0
    out = capsys.readouterr().out
    rates = dict(part.rsplit(" ", 1) for part in
                 out.split("by modality: ")[1].splitlines()[0].split(", "))
    assert set(rates) == {"hand", "arm", "emg"}
    assert 20 < float(rates["emg"]) <= 30.5 and 25 < float(rates["arm"]) < 31


# --- fit ----------------------------------------------------------------------------------


def test_fit_folder_saves_a_loadable_model(folder, tmp_path, capsys):
    from sandbox.core import IProMP

    out = tmp_path / "model.npz"
    argv = ["fit", "--data", str(folder), "--out", str(out), "--n-basis", "9", "--json"]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["demos"] == 8 and set(summary["tasks"]) == {"low", "high"}
    assert any("broken.csv" in w for w in summary["skipped"])
    model = IProMP.load(out)
    assert set(model.tasks) == {"low", "high"} and model.basis.n_basis == 9
    assert model.human_names == HUMAN_COLUMNS and model.robot_names == ROBOT_COLUMNS


def test_fit_synthetic_with_task_subset(tmp_path, capsys):
    from sandbox.core import IProMP

    out = tmp_path / "syn.npz"
    argv = ["fit", "--data", "synthetic:two_task", "--out", str(out), "--tasks", "left,right",
            "--n-per-task", "4", "--n-basis", "7", "--seed", "2"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "Fitted 2 task models (N=7) on 8 demos" in text and f"Saved {out}" in text
    assert IProMP.load(out).tasks == ("left", "right")


def test_fit_refuses_to_overwrite_without_force(folder, tmp_path, capsys):
    out = tmp_path / "model.npz"
    out.write_text("keep me")
    assert main(["fit", "--data", str(folder), "--out", str(out), "--n-basis", "7"]) == 2
    assert "--force" in capsys.readouterr().err and out.read_text() == "keep me"
    assert main(["fit", "--data", str(folder), "--out", str(out), "--n-basis", "7",
                 "--force"]) == 0


@pytest.mark.parametrize(
    "argv, match",
    [
        (["fit", "--data", "synthetic:nope", "--out", "{tmp}/m.npz"], "synthetic:two_task"),
        (["fit", "--data", "{folder}", "--out", "{tmp}/m.npz", "--tasks", "x"], "unknown ['x']"),
    ],
)
def test_fit_bad_input_exits_2(folder, tmp_path, capsys, argv, match):
    argv = [a.replace("{folder}", str(folder)).replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    assert match in capsys.readouterr().err

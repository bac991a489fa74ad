"""``--observe`` and ``--spec`` on the data-reading commands."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main


def write_set(root: Path, n_per_task: int = 4) -> Path:
    """Two tasks whose wrists move alike but whose grip signal differs, in own columns."""
    for k, task in enumerate(("soft", "firm")):
        for i in range(n_per_task):
            rng = np.random.default_rng(10 * k + i)
            t = np.arange(90) / 45.0 * (1 + 0.05 * i)
            s = t / t[-1]
            s = s**3 * (10 - 15 * s + 6 * s**2)
            wrist = np.array([1.1, -0.1, 0.25]) + s[:, None] * [-0.3, 0.3, 0.0]
            wrist += rng.normal(0, 1e-3, wrist.shape)
            grip = (100 + 150 * k) * (1 + 0.5 * s[:, None]) * [1.0, 0.6]
            grip = grip * (1 + 0.05 * rng.standard_normal(grip.shape))
            joints = 0.1 * np.arange(7) + s[:, None] * 0.3
            path = root / task / f"t{i}.csv"
            path.parent.mkdir(parents=True, exist_ok=True)
            header = ["stamp", "wx", "wy", "wz", "g0", "g1", *[f"j{j}" for j in range(7)]]
            rows = np.column_stack([t, wrist, grip, joints])
            path.write_text(",".join(header) + "\n"
                            + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows) + "\n")
    return root


@pytest.fixture
def spec(tmp_path: Path) -> Path:
    path = tmp_path / "spec.yaml"
    path.write_text("time: stamp\nrobot: [j0, j1, j2, j3, j4, j5, j6]\nobserve: [wrist]\n"
                    "modalities:\n  wrist: {columns: [wx, wy, wz], kind: position}\n"
                    "  grip: {columns: [g0, g1], kind: signal, units: raw}\n")
    return path


def test_fit_and_summary_with_a_spec_and_two_modalities(tmp_path, spec, capsys):
    from sandbox.core import IProMP

    data = write_set(tmp_path / "set")
    out = tmp_path / "m.npz"
    assert main(["fit", "--data", str(data), "--spec", str(spec), "--observe", "wrist,grip",
                 "--n-basis", "9", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["observe"] == ["wrist", "grip"] and len(summary["signal_scale"]["grip"]) == 2
    model = IProMP.load(out)
    assert model.modality_names == ("wrist", "grip") and model.n_human == 5
    assert main(["fit", "--data", str(data), "--spec", str(spec), "--n-basis", "9",
                 "--out", str(tmp_path / "w.npz")]) == 0
    assert "observe=wrist," in capsys.readouterr().out          # the spec's default
    assert main(["data", "summary", "--data", str(data), "--spec", str(spec), "--json",
                 "--observe", "grip,wrist"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["observe"] == ["grip", "wrist"] and result["all"]["trials"] == 8


def test_evaluate_observes_the_chosen_modalities(tmp_path, spec, capsys):
    data = write_set(tmp_path / "set")
    out = tmp_path / "report.json"
    assert main(["evaluate", "--data", str(data), "--spec", str(spec), "--observe", "grip",
                 "--windows", "0.5", "--ratios", "0.5", "--workers", "1", "--no-progress",
                 "--out", str(out)]) == 0
    report = json.loads(out.read_text())
    assert report["config"]["observe"] == ["grip"]
    assert report["dynamic"]["0.5"]["mean"]["recognition"] == 1.0
    curve = report["recognition_over_time_ci"]["0.5"]
    assert len(curve["mean"]) == 10 and curve["decay_ci"][0] <= curve["decay"]


@pytest.mark.parametrize("argv, match", [
    (["fit", "--data", "{data}", "--out", "{tmp}/m.npz", "--observe", "grip"],
     "expected names among ['hand', 'arm', 'emg'], got ['grip']"),
    (["fit", "--data", "{data}", "--out", "{tmp}/m.npz", "--spec", "{spec}", "--observe",
      "wrist,arm"], "(missing column 'human_left_elbow_x' in 4 files; see --observe/--spec)"),
    (["fit", "--data", "{data}", "--out", "{tmp}/m.npz", "--spec", "{spec}", "--observe",
      "eeg"], "expected names among"),
    (["fit", "--data", "synthetic:two_task", "--out", "{tmp}/m.npz", "--observe", "hand,emg"],
     "synthetic sets carry the hand only"),
    (["evaluate", "--data", "{data}", "--out", "{tmp}/r.json", "--spec", "{tmp}/none.yaml"],
     "existing YAML or JSON"),
    (["tune", "--data", "{data}", "--observe", "hand,hand"], "repeat"),
])
def test_bad_observation_options_exit_2(tmp_path, spec, capsys, argv, match):
    data = write_set(tmp_path / "set", n_per_task=2)
    argv = [a.replace("{data}", str(data)).replace("{tmp}", str(tmp_path))
            .replace("{spec}", str(spec)) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert match in err


def test_missing_column_error_names_file_and_option(tmp_path, spec, capsys):
    """The error is one line counting the reasons (issue 14); --verbose names each file
    and the spec key to set."""
    data = write_set(tmp_path / "set", n_per_task=2)
    assert main(["fit", "--data", str(data), "--out", str(tmp_path / "m.npz")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no usable demonstration" in err
    assert "missing column 't' in 4 files; see --observe/--spec" in err
    assert main(["fit", "--data", str(data), "--out", str(tmp_path / "m.npz"), "--verbose"]) == 2
    err = capsys.readouterr().err
    assert "t0.csv: missing column 't'" in err and "--spec FILE, key 'time'" in err

"""A motion-capture layout through one spec file, no conversion script (issue 28, targets).

The generated set of :mod:`tests.data.mocap_fixture` (one folder per trial, one CSV per
body segment, no time column at 120 Hz, millimetres, a Z-up world frame of its own, a label
file, 7.5 s windows with a pick-up and a retreat) goes through ``data summary``, ``fit`` and
``evaluate`` with :data:`~tests.data.mocap_fixture.SPEC`; the same data converted by hand
to the built-in layout gives the same metrics to the printed digits.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main
from sandbox.data.recorded import load_recorded
from sandbox.data.spec import DataSpec

from .mocap_fixture import RATE_HZ, ROBOT, SPEC, TRANSLATION, YAW_DEG, write_mocap_set

QUICK = ["--windows", "0.2", "--ratios", "0.5", "--workers", "1", "--no-progress", "--no-cache"]
DOCS = Path(__file__).resolve().parents[2] / "docs" / "tutorials" / "own-recordings.md"


@pytest.fixture(scope="module")
def mocap(tmp_path_factory):
    root = tmp_path_factory.mktemp("mocap")
    truth = write_mocap_set(root / "mocap")
    (root / "mocap.yaml").write_text(SPEC)
    return root / "mocap", root / "mocap.yaml", truth


def _loaded(mocap):
    data, spec, _ = mocap
    demos, skipped = load_recorded(data, spec=DataSpec.load(spec), preprocess="none")
    assert not skipped
    return demos


def test_the_docs_page_reads_the_set_with_this_spec():
    assert SPEC in DOCS.read_text()


def test_the_segments_are_the_reaches(mocap):
    truth = mocap[2]
    demos = _loaded(mocap)
    assert len(demos) == 24 and sorted({d.task for d in demos}) == ["box", "glasses_case",
                                                                      "tape"]
    for demo in demos:
        real, found = truth[Path(demo.source).name], demo.meta["report"]["segment"]
        assert demo.task == real["task"]
        assert abs(found["start_s"] - real["reach_start_s"]) < 0.35   # not the pick-up at 0.5 s
        assert found["end_s"] < real["reach_end_s"] + 0.4              # not the retreat
        assert np.linalg.norm(demo.human[-1] - real["meeting_m"]) < 0.03   # at the meeting
        assert found["closest_approach_m"] < 0.05
        np.testing.assert_allclose(np.diff(demo.times), 1 / 60, atol=1e-9)   # resample_hz
    hands = np.array([d.human[-1] for d in demos])
    assert np.all((hands[:, 0] > 0.5) & (hands[:, 0] < 1.1))   # metres, in front of Baxter


def test_summary_fit_and_evaluate_take_it_through(mocap, tmp_path, capsys):
    data, spec, _ = mocap
    assert main(["data", "summary", "--data", str(data), "--spec", str(spec), "--no-progress",
                 "--synthetic", "none"]) == 0
    out = capsys.readouterr().out
    assert f"Dataset {data}: 24 trials in 3 tasks (0 skipped)" in out
    block = out[out.index("frame:\n"):]
    translation = [float(v) for v in re.search(r"translation: \[(.*)\]", block)[1].split(",")]
    yaw = float(re.search(r"yaw: (\S+)", block)[1])
    assert abs(yaw - YAW_DEG) <= 3 and np.linalg.norm(translation - TRANSLATION) < 0.15
    assert main(["fit", "--data", str(data), "--spec", str(spec), "--out",
                 str(tmp_path / "m.npz"), "--no-cache"]) == 0
    out = capsys.readouterr().out
    assert "Fitted 3 task models" in out and "on 24 demos" in out
    assert re.search(r"hand observation noise \(mm\): \d+\.\d", out)          # metres -> mm
    assert main(["evaluate", "--data", str(data), "--spec", str(spec), *QUICK,
                 "--out", str(tmp_path / "r.json")]) == 0
    assert "24 trials" in capsys.readouterr().out
    assert main(["data", "check-filter", "--data", str(data), "--spec", str(spec)]) == 0
    smoothed = re.search(r"RTS smoother +error median (\S+) mm", capsys.readouterr().out)
    assert 0.5 < float(smoothed[1]) < 5               # 1 mm of jitter, read in millimetres


def _by_hand(mocap, out: Path) -> Path:
    """The conversion script a user no longer writes: time, metres, frame, cut, thin, regroup."""
    data = mocap[0]
    bounds = {Path(d.source).name: d.meta["report"]["segment"] for d in _loaded(mocap)}
    with open(data / "labels.csv", newline="") as fh:
        task = {row["trial"]: row["object"] for row in csv.DictReader(fh)}
    c, s = np.cos(np.radians(YAW_DEG)), np.sin(np.radians(YAW_DEG))
    rotation = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    for name, label in task.items():
        hand = np.loadtxt(data / name / "giver_RHand_pose.csv", delimiter=",", skiprows=1)
        robot = np.loadtxt(data / name / "baxter_left_arm.csv", delimiter=",", skiprows=1)
        base = (hand[:, :3] / 1000.0) @ rotation.T + TRANSLATION
        first, last = (round(bounds[name][k] * RATE_HZ) for k in ("start_s", "end_s"))
        rows = np.arange(first, last + 1, 2)                              # 120 -> 60 Hz
        (out / label).mkdir(parents=True, exist_ok=True)
        with open(out / label / f"{name}.csv", "w", newline="") as fh:   # full precision
            table = csv.writer(fh)
            table.writerow(["t", *(f"human_left_hand_{a}" for a in "xyz"), *ROBOT])
            table.writerows(map(list, np.column_stack([(rows - first) / RATE_HZ, base[rows],
                                                       robot[rows]]).tolist()))
    return out


def test_the_same_data_converted_by_hand_gives_the_same_metrics(mocap, tmp_path, capsys):
    data, spec, _ = mocap
    converted = _by_hand(mocap, tmp_path / "converted")
    tables = []
    for args in (["--data", str(data), "--spec", str(spec)], ["--data", str(converted)]):
        assert main(["evaluate", *args, *QUICK, "--out", str(tmp_path / f"{len(tables)}.json")
                     ]) == 0
        tables.append(capsys.readouterr().out.split("\n", 1)[1])
    assert "e_p (m)" in tables[0] and tables[0] == tables[1]


def test_each_skipped_trial_is_one_line_and_nothing_usable_is_one_error(mocap, tmp_path,
                                                                         capsys):
    data, _, _ = mocap
    spec = tmp_path / "spec.yaml"
    spec.write_text(SPEC.replace("rate_hz: 120", "time: giver.t"))
    assert main(["data", "summary", "--data", str(data), "--spec", str(spec),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == ("skipped 24 trials: missing column 't' in files.giver; name the time "
                      "column in a spec (--spec FILE, key 'time'), or give rate_hz for files "
                      "without one")
    assert err[1].startswith("error: no usable trial in") and len(err) == 2
    assert main(["data", "summary", "--data", str(data), "--spec", str(spec), "--verbose",
                 "--no-progress"]) == 2
    assert len(capsys.readouterr().err.splitlines()) == 25                    # one per file


def test_a_set_already_in_baxters_frame_is_suggested_about_the_identity(tmp_path):
    from sandbox.data.spec_frame import suggest_for

    from .folders import write_synthetic_set

    root = write_synthetic_set(tmp_path / "set", "objects", n_per_task=4)
    demos, _ = load_recorded(root, preprocess="causal")
    frame = suggest_for(demos, DataSpec())
    assert abs(frame.rotation["yaw"]) <= 10 and np.linalg.norm(frame.translation) < 0.15

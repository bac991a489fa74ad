"""Tests of sandbox.data.recorded: the per-trial CSV loader and its preprocessing."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from sandbox.data.recorded import (
    HUMAN_COLUMNS,
    ROBOT_COLUMNS,
    Columns,
    SkippedTrialWarning,
    TrialError,
    find_trials,
    load_recorded,
    load_trial,
    preprocess_demonstration,
)

HEADER = ["t", *HUMAN_COLUMNS, "emg0", *ROBOT_COLUMNS]


def trial_rows(n_frames: int = 40, seed: int = 0) -> list[list[float]]:
    """Rows like the recordings: a 30 Hz hand re-sent in bursts, a smooth robot."""
    rng = np.random.default_rng(seed)
    rows, t = [], 0.0
    frames = [np.array([1.1 - 0.01 * k, -0.1 + 0.008 * k, 0.25]) for k in range(n_frames)]
    for k, hand in enumerate(frames):
        for repeat in range(3):  # the new frame, then twice the same or the previous one
            shown = frames[k - 1] if (repeat == 2 and k > 0) else hand
            robot = 0.1 * np.arange(7) + 0.01 * t
            rows.append([round(t, 4), *shown, float(rng.integers(100, 900)), *robot])
            t += 0.0 if repeat == 0 else 0.011
    return rows


def write_csv(path: Path, header: list[str], rows: list[list]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [",".join(header)] + [",".join(str(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def good_file(tmp_path: Path) -> Path:
    return write_csv(tmp_path / "data" / "reach" / "trial1.csv", HEADER, trial_rows())


def test_good_trial_loads_with_collapsed_timestamps(good_file):
    rows = np.array(trial_rows())
    demo = load_trial(good_file, preprocess="none")
    assert demo.task == "reach" and demo.source == str(good_file)
    assert demo.human_names == HUMAN_COLUMNS and demo.robot_names == ROBOT_COLUMNS
    times = np.unique(rows[:, 0])
    np.testing.assert_array_equal(demo.times, times)
    assert demo.duration == pytest.approx(rows[-1, 0] - rows[0, 0])  # the recorded span
    last = [np.flatnonzero(rows[:, 0] == ti)[-1] for ti in times]
    np.testing.assert_array_equal(demo.human, rows[last, 1:4])  # raw: untouched
    np.testing.assert_array_equal(demo.robot, rows[last, 5:])
    report = demo.meta["report"]
    assert report["rows"] == len(rows)
    assert report["repeated_timestamps"] == len(rows) - times.size
    assert report["new_frames"] == 40 and report["stale_rows"] == 80
    assert report["zero_rows"] == 0 and report["rows_dropped"] == {}


@pytest.mark.parametrize("preprocess", ["causal", "smooth"])
def test_filtered_trial_marks_rows_without_a_new_frame(good_file, preprocess):
    demo = load_trial(good_file, preprocess=preprocess)
    measured = demo.meta["human_measured"]
    assert measured.sum() == 40  # one new frame per burst time stamp
    assert np.isfinite(demo.human[measured]).all()
    if preprocess == "causal":
        assert np.isnan(demo.human[~measured]).all()  # marked, not invented
    else:
        assert np.isfinite(demo.human).all()  # smoothing fills the short gaps
    truth = np.array([[1.1 - 0.01 * k, -0.1 + 0.008 * k, 0.25] for k in range(40)])
    # (the causal filter starts with zero velocity: skip its first frames)
    np.testing.assert_allclose(demo.human[measured][3:], truth[3:], atol=2e-3)


def test_causal_preprocessing_uses_no_later_rows(tmp_path):
    rows = trial_rows()
    full = load_trial(write_csv(tmp_path / "a" / "full.csv", HEADER, rows), preprocess="causal")
    cut = load_trial(write_csv(tmp_path / "a" / "cut.csv", HEADER, rows[:70]),
                     preprocess="causal")
    n = cut.n_steps
    np.testing.assert_array_equal(cut.human, full.human[:n])


def test_zero_and_missing_values_are_marked_and_reported(tmp_path):
    rows = trial_rows()
    rows[31][1:4] = [0.0, 0.0, 0.0]  # (rows 31 and 47 are the last of their time stamp)
    rows[47][2] = ""  # a missing human value
    rows[60][6] = ""  # a missing robot value: the row is dropped
    path = write_csv(tmp_path / "d" / "t.csv", HEADER, rows)
    demo = load_trial(path, preprocess="causal")
    report = demo.meta["report"]
    assert report["zero_rows"] == 1 and report["missing_rows"] == 1
    assert report["rows_dropped"] == {"robot value missing": 1}
    assert np.isfinite(demo.robot).all()
    raw = load_trial(path, preprocess="none")
    assert np.isnan(raw.human).any() and (raw.human == 0).all(axis=1).any()


def test_smooth_sets_aside_a_short_excursion(tmp_path):
    rows = trial_rows(60)
    for row in rows:  # frames 30 and 31 (wherever they are sent) jump 8 cm up
        if round((1.1 - row[1]) / 0.01) in (30, 31):
            row[3] += 0.08
    demo = load_trial(write_csv(tmp_path / "e" / "t.csv", HEADER, rows), preprocess="smooth")
    assert demo.meta["report"]["excursions"] == 2
    truth_z = 0.25
    assert np.abs(demo.human[:, 2] - truth_z).max() < 0.01  # the smoothed track stays put
    raw = load_trial(write_csv(tmp_path / "e" / "t.csv", HEADER, rows), preprocess="none")
    assert raw.meta["report"]["excursions"] == 2 and raw.human[:, 2].max() > 0.32


def test_smooth_leaves_long_gaps_unfilled(tmp_path):
    rows = trial_rows(60)
    for row in rows[60:120]:  # the hand is lost for 20 frames (about 0.44 s)
        row[1:4] = [0.0, 0.0, 0.0]
    demo = load_trial(write_csv(tmp_path / "g" / "t.csv", HEADER, rows), preprocess="smooth",
                      max_fill_s=0.25)
    lost = (demo.times > rows[58][0] + 0.05) & (demo.times < rows[120][0] - 0.05)
    assert lost.any() and np.isnan(demo.human[lost]).all()
    assert demo.meta["report"]["unfilled_samples"] >= lost.sum()
    assert np.isfinite(demo.human[demo.times < rows[55][0]]).all()


def test_frozen_skeleton_is_reported(tmp_path):
    rows = trial_rows(60)
    for row in rows[60:120]:
        row[1:4] = rows[59][1:4]  # the same frame for about 0.44 s
    demo = load_trial(write_csv(tmp_path / "f" / "t.csv", HEADER, rows), preprocess="causal")
    report = demo.meta["report"]
    assert report["frozen_segments"] == 1 and report["frozen_s"] > 0.4


def test_user_columns_and_garbled_header_spacing(tmp_path):
    header = ["\ufefft", " hx ", "hy", "\"hz\"", "emg0", *ROBOT_COLUMNS]
    path = write_csv(tmp_path / "c" / "t.csv", header, trial_rows())
    demo = load_trial(path, columns=Columns(human=("hx", "hy", "hz"), robot=ROBOT_COLUMNS[:2]))
    assert demo.human_names == ("hx", "hy", "hz") and demo.robot.shape[1] == 2


BAD_FILES = {
    "empty.csv": ("", "empty file"),
    "header_only.csv": (",".join(HEADER) + "\n", "no data rows"),
    "one_row.csv": (None, "only 1 usable time stamp"),
    "missing_column.csv": (None, "missing column 'left_w2'"),
    "garbled.csv": (None, "missing column 'human_left_hand_y' \\(did you mean 'human_left_hnad_y'"),
    "duplicate.csv": (None, "column 'left_s0' appears 2 times"),
    "text_row.csv": (None, "row 5: non-numeric value 'oops' in column 'left_e0'"),
    "same_time.csv": (None, "only 1 usable time stamp"),
    "ragged.csv": (None, "row 3 has 5 fields"),
    "upper.csv": (None, "missing column 't' \\(did you mean 'T'\\?\\)"),
    "no_hand.csv": (None, "fewer than 2 valid samples of 'hand' \\(0 rows missing, 30 rows"),
}


def make_bad(folder: Path, name: str) -> Path:
    path = folder / name
    content, _ = BAD_FILES[name]
    rows = trial_rows(10)
    if content is not None:
        folder.mkdir(parents=True, exist_ok=True)
        path.write_text(content)
        return path
    if name == "one_row.csv":
        return write_csv(path, HEADER, rows[:1])
    if name == "missing_column.csv":
        return write_csv(path, HEADER[:-1], [r[:-1] for r in rows])
    if name == "garbled.csv":
        return write_csv(path, [h.replace("hand_y", "hnad_y") for h in HEADER], rows)
    if name == "duplicate.csv":
        return write_csv(path, [*HEADER, "left_s0"], [[*r, 0.0] for r in rows])
    if name == "text_row.csv":
        rows[3][HEADER.index("left_e0")] = "oops"
        return write_csv(path, HEADER, rows)
    if name == "upper.csv":
        return write_csv(path, ["T", *HEADER[1:]], rows)
    if name == "no_hand.csv":
        return write_csv(path, HEADER, [[r[0], 0.0, 0.0, 0.0, *r[4:]] for r in rows])
    if name == "same_time.csv":
        return write_csv(path, HEADER, [[0.5, *r[1:]] for r in rows])
    rows[1] = rows[1][:5]  # ragged
    return write_csv(path, HEADER, rows)


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_bad_file_asked_for_directly_raises_a_clear_error(tmp_path, name):
    path = make_bad(tmp_path / "bad", name)
    with pytest.raises(ValueError, match=BAD_FILES[name][1]) as info:
        load_trial(path)
    assert str(path) in str(info.value)


def test_bad_trials_are_skipped_with_warnings_and_reasons(tmp_path):
    root = tmp_path / "set"
    write_csv(root / "reach" / "good1.csv", HEADER, trial_rows(seed=1))
    write_csv(root / "wave" / "good2.csv", HEADER, trial_rows(seed=2))
    for name in BAD_FILES:
        make_bad(root / "reach", name)
    with pytest.warns(SkippedTrialWarning) as caught:
        demos, skipped = load_recorded(root)
    assert [d.source for d in demos] == [str(root / "reach" / "good1.csv"),
                                        str(root / "wave" / "good2.csv")]
    assert len(skipped) == len(BAD_FILES) == len(caught)
    for file, reason in skipped:
        assert reason and str(root) not in reason
        assert BAD_FILES[Path(file).name][1].split(" \\(")[0] in reason


def test_task_subset_and_unknown_task(tmp_path):
    root = tmp_path / "set"
    write_csv(root / "reach" / "a.csv", HEADER, trial_rows())
    write_csv(root / "wave" / "b.csv", HEADER, trial_rows())
    demos, _ = load_recorded(root, tasks=["wave"], preprocess="none")
    assert [d.task for d in demos] == ["wave"]
    with pytest.raises(ValueError, match=r"expected some of \['reach', 'wave'\]"):
        load_recorded(root, tasks=["jump"])


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda p: load_recorded(p / "nowhere"), "expected a folder"),
        (lambda p: load_recorded(p), "no <task>/<trial>.csv"),
        (lambda p: load_recorded(p, preprocess="magic"), "preprocess"),
        (lambda p: Columns(human=("a", "a", "b")), "more than once"),
        (lambda p: Columns(robot=()), "robot columns"),
        (lambda p: load_trial(p / "missing.csv"), "no such file"),
    ],
)
def test_bad_arguments_are_refused(tmp_path, call, match):
    with pytest.raises(ValueError, match=match):
        call(tmp_path)


def test_preprocess_demonstration_applies_the_loader_pipeline(good_file):
    raw = load_trial(good_file, preprocess="none")
    assert preprocess_demonstration(raw, "none") is raw
    causal = preprocess_demonstration(raw, "causal")
    np.testing.assert_array_equal(causal.times, raw.times)
    np.testing.assert_array_equal(causal.robot, raw.robot)
    report = causal.meta["report"]
    assert report["preprocess"] == "causal" and report["rows"] == raw.meta["report"]["rows"]
    assert np.isnan(causal.human[~causal.meta["human_measured"]]).all()
    with pytest.raises(ValueError, match="preprocess"):
        preprocess_demonstration(raw, "fancy")
    with pytest.raises(ValueError, match="max_fill_s"):
        preprocess_demonstration(raw, "smooth", max_fill_s=-1.0)


def test_trial_error_is_a_value_error():
    assert issubclass(TrialError, ValueError)


# --- the recorded handovers ------------------------------------------------------------


@pytest.fixture(scope="module")
def recorded(recorded_dir):
    with warnings.catch_warnings():
        warnings.simplefilter("error", SkippedTrialWarning)
        return load_recorded(recorded_dir, preprocess="causal")


def test_all_174_recorded_trials_load(recorded, recorded_dir):
    demos, skipped = recorded
    assert skipped == []
    counts = {t: sum(d.task == t for d in demos) for t in {d.task for d in demos}}
    assert counts == {"pencil_box": 42, "measurement_tape": 47, "gummed_paper": 40,
                      "screw_driver": 45}
    assert len(find_trials(recorded_dir)) == 174


def test_recorded_durations_are_the_recorded_span(recorded):
    demos, _ = recorded
    for demo in demos[::17]:
        t = np.loadtxt(demo.source, delimiter=",", skiprows=1, usecols=0)
        assert demo.duration == pytest.approx(t[-1] - t[0])
    durations = np.array([d.duration for d in demos])
    assert 1.6 < durations.min() and durations.max() < 4.1


def test_recorded_glitch_report_matches_the_data_description(recorded):
    demos, _ = recorded
    reports = [d.meta["report"] for d in demos]
    rows = sum(r["rows"] for r in reports)
    repeated = sum(r["repeated_timestamps"] for r in reports) / rows
    assert 0.35 < repeated < 0.45  # "about 40 % of rows share their timestamp"
    frames_per_s = sum(r["new_frames"] for r in reports) / sum(r["duration_s"] for r in reports)
    assert 25 < frames_per_s < 45  # a ~30 Hz tracker under ~100 Hz rows
    for demo in demos:
        measured = demo.meta["human_measured"]
        assert np.isfinite(demo.human[measured]).all()
        assert np.isnan(demo.human[~measured]).all()
        assert np.isfinite(demo.robot).all()

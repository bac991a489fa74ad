"""Regression and property tests of the loader's limits (issue 13: findings 1, 2, 7, 9; item 5).

Corrupted data sets are built in ``tmp_path`` from a few real trial files of
the recorded set (skipped without it, a failure under ``SANDBOX_REQUIRE_DATA=1``).
"""

from __future__ import annotations

import csv
import os
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sandbox.data import limits, load_dataset, resample_uniform
from sandbox.data.recorded import (
    Columns,
    SkippedTrialWarning,
    TrialError,
    load_recorded,
    load_trial,
)
from sandbox.data.spec import DataSpec, resolve
from tests.data.test_recorded import HEADER, trial_rows, write_csv

#: The shortest trial of each of two tasks (fast to load).
TRIALS = ("pencil_box/2018-03-29-17-12-20.csv", "gummed_paper/2018-03-29-17-13-27.csv")


def _table(path: Path) -> tuple[list[str], list[list[str]]]:
    rows = list(csv.reader(path.read_text().splitlines()))
    return rows[0], rows[1:]


def _write(path: Path, header: list[str], rows: list[list[str]]) -> Path:
    path.write_text("\n".join(",".join(r) for r in [header, *rows]) + "\n")
    return path


@pytest.fixture
def dataset(tmp_path: Path, recorded_dir: Path) -> Path:
    """Two real trials in ``tmp_path/data/<task>/<trial>.csv``."""
    root = tmp_path / "data"
    for name in TRIALS:
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(recorded_dir / name, root / name)
    return root


def _corrupt(root: Path, name: str, cell: str, column: str = "t", row: int = -1) -> Path:
    path = root / name
    header, rows = _table(path)
    rows[row][header.index(column)] = cell
    return _write(path, header, rows)


def _load(root: Path, **kw) -> tuple[list, dict[str, str]]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SkippedTrialWarning)
        demos, skipped = load_recorded(root, preprocess="causal", **kw)
    return demos, {Path(f).name: reason for f, reason in skipped}


# -- finding 1: durations and time units -------------------------------------------------------


def test_a_last_timestamp_of_1e6_s_skips_the_trial(dataset):
    """issue 13 finding 1: one CSV whose last timestamp is 1e6 s made `data summary` grow past
    5 GB; the trial is now skipped, naming the 60 s limit."""
    _corrupt(dataset, TRIALS[0], "1000000.0")
    demos, skipped = _load(dataset)
    assert len(demos) == 1
    reason = skipped[Path(TRIALS[0]).name]
    assert "at most 60 s" in reason and "1e+06 s" in reason


@pytest.mark.parametrize(("factor", "unit"), [(1e3, "milliseconds"), (1e9, "nanoseconds")])
def test_a_trial_in_another_time_unit_is_skipped_with_the_unit_it_looks_like(dataset, factor,
                                                                            unit):
    """issue 13 finding 1: a trial stamped in milliseconds or nanoseconds made `evaluate` die
    with MemoryError; it is skipped and the reason says which unit the times look like."""
    path = dataset / TRIALS[1]
    header, rows = _table(path)
    for row in rows:
        row[0] = repr(float(row[0]) * factor)
    _write(path, header, rows)
    demos, skipped = _load(dataset)
    assert len(demos) == 1
    assert f"looks like {unit}" in skipped[path.name]


def test_max_duration_can_be_raised(dataset):
    """issue 13 finding 1: the duration limit names the option that raises it."""
    path = dataset / TRIALS[0]
    header, rows = _table(path)
    for row in rows:
        row[0] = repr(float(row[0]) * 30.0)  # about 50 s sampled at 3 Hz: slow, but seconds
    _write(path, header, rows)
    demo = load_trial(path, preprocess="none", max_duration=100.0)
    assert demo.duration > 40.0
    with pytest.raises(ValueError, match="max_duration"):
        load_trial(path, preprocess="none", max_duration=10.0)
    with pytest.raises(ValueError, match="max_duration"):
        load_recorded(dataset, max_duration=float("nan"))


def test_data_summary_lists_the_long_trial_as_skipped(dataset, capsys):
    """issue 13 finding 1: `data summary` on a set with a 1e6 s trial finishes and lists it."""
    from sandbox.cli import main

    _corrupt(dataset, TRIALS[0], "1000000.0")
    assert main(["data", "summary", "--data", str(dataset), "--synthetic", "none"]) == 0
    out = capsys.readouterr().out
    assert "1 trials in 1 tasks (1 skipped)" in out and "at most 60 s" in out


def test_check_filter_leaves_out_a_trial_with_implausible_times(dataset, capsys):
    """issue 13 finding 1: `data check-filter` used a 1e6 s trial silently; it leaves it out."""
    from sandbox.cli import main

    _corrupt(dataset, TRIALS[0], "1000000.0")
    assert main(["data", "check-filter", "--data", str(dataset), "--json"]) == 0
    assert '"trials": 1,' in capsys.readouterr().out


# -- finding 2: one huge field --------------------------------------------------------------


def test_a_field_over_128_kib_skips_the_trial(dataset):
    """issue 13 finding 2: a 128 KiB field (a stray quote) raised `_csv.Error` out of `data
    summary` and `evaluate`; the trial is now skipped with the reason."""
    path = dataset / TRIALS[0]
    text = path.read_text().splitlines()
    text[5] = text[5].replace(",", ',"', 1) + "x" * (200 * 1024)
    path.write_text("\n".join(text) + "\n")
    demos, skipped = _load(dataset)
    assert len(demos) == 1
    assert "stray quote" in skipped[path.name]


def test_the_field_limit_holds_when_csv_allows_more(dataset):
    """issue 13 finding 2: MAX_FIELD_BYTES is checked by the loader itself, whatever the
    process-wide `csv.field_size_limit` is."""
    path = _corrupt(dataset, TRIALS[0], "1" * (limits.MAX_FIELD_BYTES + 1), column="emg0")
    old = csv.field_size_limit(2**30)
    try:
        with pytest.raises(TrialError, match="MAX_FIELD_BYTES"):
            load_trial(path)
    finally:
        csv.field_size_limit(old)


@pytest.mark.parametrize(("limit", "value", "words"), [
    ("MAX_ROWS_PER_FILE", 50, "data rows"),
    ("MAX_LINE_BYTES", 200, "longer than 200"),
    ("MAX_FILE_BYTES", 1000, "expected at most 1000"),
])
def test_file_row_and_line_limits_skip_the_trial(dataset, monkeypatch, limit, value, words):
    """issue 13 item 1: rows per file, bytes per line and per file are bounded; the reason
    names the limit."""
    import sandbox.data.trialfile as trialfile

    monkeypatch.setattr(trialfile, limit, value)
    demos, skipped = _load(dataset)
    assert not demos
    for reason in skipped.values():
        assert words in reason and limit in reason


# -- finding 7: robot values --------------------------------------------------------------


def test_a_robot_joint_far_outside_its_urdf_limits_skips_the_trial(dataset):
    """issue 13 finding 7: one `left_s0 = 1e6` rad cell moved the evaluated e_p from 0.074 m
    to 0.757 m; the trial is now skipped, naming the column and the URDF limits."""
    _corrupt(dataset, TRIALS[0], "1000000", column="left_s0", row=10)
    demos, skipped = _load(dataset)
    assert len(demos) == 1
    reason = skipped[Path(TRIALS[0]).name]
    assert "'left_s0' = 1e+06 rad" in reason and "URDF limits [-1.70168, 1.70168]" in reason


def test_the_joint_limit_tolerance(dataset):
    """issue 13 finding 7: a joint within JOINT_LIMIT_TOL_RAD past its limit loads (the
    recordings reach 0.011 rad past left_w1's), one beyond it does not."""
    upper = 2.094  # left_w1 (URDF)
    path = _corrupt(dataset, TRIALS[0], repr(upper + 0.9 * limits.JOINT_LIMIT_TOL_RAD),
                    column="left_w1", row=3)
    load_trial(path, preprocess="none")
    _corrupt(dataset, TRIALS[0], repr(upper + 1.1 * limits.JOINT_LIMIT_TOL_RAD),
             column="left_w1", row=3)
    with pytest.raises(TrialError, match="left_w1"):
        load_trial(path, preprocess="none")


def test_other_robot_and_human_values_are_bounded(dataset):
    """issue 13 finding 7: columns that are not Baxter joints, and human values, are bounded
    by MAX_ABS_VALUE."""
    path = _corrupt(dataset, TRIALS[0], "3e7", column="human_left_hand_y", row=4)
    with pytest.raises(TrialError, match="'human_left_hand_y' = 3e\\+07.*MAX_ABS_VALUE"):
        load_trial(path)
    header, rows = _table(path)
    header[header.index("left_s0")] = "joint_a"
    rows[4][header.index("human_left_hand_y")] = "0.1"
    rows[6][header.index("joint_a")] = "-2e6"
    _write(path, header, rows)
    columns = Columns(robot=("joint_a", "left_s1"))
    with pytest.raises(TrialError, match="'joint_a' = -2e\\+06"):
        load_trial(path, columns=columns)


# -- item 5: every per-file error is a skipped trial ------------------------------------------


def test_an_unexpected_error_in_one_file_skips_only_that_file(dataset, monkeypatch):
    """issue 13 item 5: any per-file error is a skipped trial with a reason, never an
    exception out of load_recorded."""
    import sandbox.data.recorded as recorded

    real, calls = recorded.preprocess_human, []

    def flaky(*args, **kw):
        calls.append(1)
        if len(calls) == 1:  # the first trial only
            raise ZeroDivisionError("boom")
        return real(*args, **kw)

    monkeypatch.setattr(recorded, "preprocess_human", flaky)
    demos, skipped = _load(dataset)
    assert len(demos) == 1
    assert list(skipped.values()) == ["unexpected ZeroDivisionError: boom"]


def test_a_folder_named_like_a_trial_is_skipped(dataset):
    """issue 13 item 5: a `<task>/<name>.csv` that is not a readable file is a skipped trial."""
    (dataset / "pencil_box" / "z.csv").mkdir()
    demos, skipped = _load(dataset)
    assert len(demos) == 2 and "not a regular file" in skipped["z.csv"]


def test_evaluate_exits_non_zero_when_no_trial_is_usable(dataset, tmp_path, capsys):
    """issue 13 item 5: `evaluate` on a set whose every trial is skipped is an error (2)."""
    from sandbox.cli import main

    for name in TRIALS:
        _corrupt(dataset, name, "1e6")
    out = tmp_path / "report.json"
    assert main(["evaluate", "--data", str(dataset), "--out", str(out), "--workers", "1",
                 "--no-progress"]) == 2
    assert "no usable trial" in capsys.readouterr().err
    assert not out.exists()


# -- finding 9: Columns ------------------------------------------------------------------


@pytest.mark.parametrize("kwargs", [{"human": "abc"}, {"robot": "left_s0"}, {"human": 3},
                                    {"time": ""}, {"time": 1}, {"human": None}])
def test_columns_refuses_what_its_docstring_does_not_accept(kwargs):
    """issue 13 finding 9: `Columns(human='abc')` became three one-letter columns."""
    with pytest.raises(ValueError, match="expected"):
        Columns(**kwargs)


# -- property: mutated CSV contents ---------------------------------------------------------

CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(["", '"', "nan", "-inf", "1e308", "-1e400", "1e6", "1,2", "\r", "\n",
                     '"a\nb"', "\x00", "\ufeff", "0x10", "1_000", " 3 ", "∞"]),
    st.text(max_size=12),
)


@st.composite
def mutations(draw):
    """A list of 1-4 edits: set a cell, drop or repeat a row, scale the times, cut the text."""
    edit = st.one_of(
        st.tuples(st.just("cell"), st.integers(0, 400), st.integers(0, 60), CELLS),
        st.tuples(st.just("drop"), st.integers(0, 400)),
        st.tuples(st.just("repeat"), st.integers(0, 400)),
        st.tuples(st.just("scale"), st.sampled_from([-1.0, 0.0, 1e-6, 1e3, 1e9, 1e300])),
        st.tuples(st.just("cut"), st.floats(0.0, 1.0)),
    )
    return draw(st.lists(edit, min_size=1, max_size=4))


def _mutate(header: list[str], rows: list[list[str]], edits) -> str:
    rows = [list(r) for r in rows]
    cut = None
    for kind, *args in edits:
        if kind == "cell":
            r, c, text = args
            rows[r % len(rows)][c % len(header)] = text
        elif kind == "drop" and len(rows) > 1:
            rows.pop(args[0] % len(rows))
        elif kind == "repeat":
            rows.insert(args[0] % len(rows), rows[args[0] % len(rows)])
        elif kind == "scale":
            for row in rows:
                try:
                    row[0] = repr(float(row[0]) * args[0])
                except ValueError:
                    pass
        elif kind == "cut":
            cut = args[0]
    text = "\n".join(",".join(r) for r in [header, *rows]) + "\n"
    return text if cut is None else text[: int(cut * len(text))]


@pytest.fixture(scope="module")
def source_table(recorded_dir: Path) -> tuple[list[str], list[list[str]]]:
    return _table(recorded_dir / TRIALS[0])


#: Examples per property test; raise ``SANDBOX_FUZZ_EXAMPLES`` for a longer campaign.
EXAMPLES = int(os.environ.get("SANDBOX_FUZZ_EXAMPLES", "80"))


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(edits=mutations(), preprocess=st.sampled_from(["none", "causal", "smooth"]),
       observe=st.sampled_from(["hand", "hand,arm,emg"]))
def test_mutated_trials_load_or_are_refused_with_a_value_error(source_table, edits, preprocess,
                                                               observe):
    """issue 13 item 9: whatever is done to a trial's text, the loader either returns a
    demonstration with finite times and robot values (the human is NaN only where missing,
    never infinite) or raises ValueError, never another exception."""
    text = _mutate(*source_table, edits)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "reach" / "trial.csv"
        path.parent.mkdir()
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            try:
                demo = load_trial(path, preprocess=preprocess, observe=observe)
            except ValueError as error:
                assert str(error)
                return
    assert np.isfinite(demo.times).all() and (np.diff(demo.times) > 0).all()
    assert demo.duration <= limits.MAX_DURATION_S
    assert np.isfinite(demo.robot).all()
    assert not np.isinf(demo.human).any()
    assert np.abs(np.nan_to_num(demo.human)).max() <= limits.MAX_ABS_VALUE


def test_synthetic_rows_still_load_without_the_recorded_set(tmp_path):
    """issue 13: the limits leave a well-formed trial untouched (needs no shared data)."""
    path = write_csv(tmp_path / "reach" / "t.csv", HEADER, trial_rows())
    demo = load_trial(path, preprocess="none")
    assert demo.times.size == 40 * 2 and demo.robot.shape == (80, 7)


# -- finding 9: types of the data package's public entries ----------------------------------


@pytest.mark.parametrize("call", [
    lambda: load_recorded(None), lambda: load_recorded(3), lambda: load_trial(None),
    lambda: load_recorded(".", tasks=3), lambda: load_recorded(".", tasks=[[1]]),
    lambda: load_dataset("synthetic:two_task", seed="a"),
    lambda: load_dataset("synthetic:two_task", seed=-1),
    lambda: load_dataset("synthetic:two_task", n_per_task=float("inf")),
    lambda: load_dataset("synthetic:two_task", n_per_task="3"),
    lambda: load_dataset("synthetic:two_task", tasks="left"),
    lambda: load_dataset("synthetic:two_task", spec=3),
    lambda: load_dataset("synthetic:two_task", observe=3),
    lambda: DataSpec(modalities=3), lambda: DataSpec(modalities=[1]), lambda: DataSpec(observe=3),
    lambda: DataSpec().observed(3), lambda: DataSpec.load(None), lambda: resolve(3),
    lambda: DataSpec.from_dict({"modalities": {"a": {"columns": ["x"], "units": [1]}}}),
])
def test_public_entries_raise_value_error_for_wrong_types(call):
    """issue 13 finding 9: the data package's entries raised TypeError/OverflowError for
    inputs their docstrings do not accept; they raise ValueError."""
    with pytest.raises(ValueError, match="expected"):
        call()


def test_synthetic_sets_and_resampling_are_bounded():
    """issue 13 item 1: `n_per_task=10**9` generated until memory ran out and
    `resample_uniform(demo, 1e9)` allocated gigabytes; both are refused with the limit."""
    with pytest.raises(ValueError, match=r"n_per_task: expected an integer in \[1, 10000\]"):
        load_dataset("synthetic:two_task", n_per_task=10**9)
    demo = load_dataset("synthetic:two_task", n_per_task=2, preprocess="none")[0]
    with pytest.raises(ValueError, match="MAX_RATE_HZ"):
        resample_uniform(demo, 1e9)
    long = demo.replace(times=demo.times * 200.0 / demo.duration)  # 200 s: 10 kHz is too many
    with pytest.raises(ValueError, match="MAX_GRID_SAMPLES"):
        resample_uniform(long, limits.MAX_RATE_HZ)
    assert resample_uniform(demo, 50.0).meta["resampled_hz"] == 50.0

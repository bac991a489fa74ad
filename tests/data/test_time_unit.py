"""Time columns in other units than seconds (issue 26, item 5).

A set stamped in milliseconds was skipped with a terse reason; only
``--verbose`` said "looks like milliseconds: divide by 1000". The one-line
summary now names the unit and the fix, and a spec's ``time_unit`` (or
``--time-unit``) reads such a set as it is.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from sandbox.cli import main
from sandbox.data.datasets import load_dataset
from sandbox.data.spec import TIME_UNITS, DataSpec, resolve

from .folders import write_synthetic_set


def _rescaled(src: Path, dst: Path, factor: float) -> Path:
    """A copy of the CSV set ``src`` whose time column ``t`` is multiplied by ``factor``."""
    for file in sorted(src.rglob("*.csv")):
        with open(file, newline="") as fh:
            rows = list(csv.reader(fh))
        col = rows[0].index("t")
        for row in rows[1:]:
            row[col] = repr(float(row[col]) * factor)
        out = dst / file.relative_to(src)
        out.parent.mkdir(parents=True, exist_ok=True)
        with open(out, "w", newline="") as fh:
            csv.writer(fh).writerows(rows)
    return dst


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    root = tmp_path_factory.mktemp("sets")
    seconds = write_synthetic_set(root / "s", n_per_task=3)
    return seconds, _rescaled(seconds, root / "ms", 1e3), _rescaled(seconds, root / "us", 1e6)


def test_the_spec_key_and_its_checks(tmp_path):
    assert DataSpec().time_unit == "s" and DataSpec().time_scale == 1.0
    spec = DataSpec.from_dict({"time_unit": "ms"})
    assert spec.time_scale == 1e-3 and DataSpec.from_dict(spec.to_dict()) == spec
    assert resolve(None, time_unit="us").time_scale == 1e-6
    assert set(TIME_UNITS) == {"s", "ms", "us", "ns"}
    path = tmp_path / "spec.yaml"
    path.write_text("time_unit: hours\n")
    with pytest.raises(ValueError, match=r"spec .*spec\.yaml: time_unit: expected one of "
                                         r"\['s', 'ms', 'us', 'ns'\], got 'hours'"):
        DataSpec.load(path)
    with pytest.raises(ValueError, match="time_unit"):
        DataSpec(time_unit=1e-3)


@pytest.mark.parametrize(("index", "unit"), [(1, "ms"), (2, "us")])
def test_a_set_in_another_unit_loads_as_the_one_in_seconds(sets, index, unit):
    seconds = load_dataset(str(sets[0]), cache=False)
    scaled = load_dataset(str(sets[index]), spec=DataSpec(time_unit=unit), cache=False)
    assert [d.task for d in scaled] == [d.task for d in seconds]
    for a, b in zip(seconds, scaled):
        np.testing.assert_allclose(b.times, a.times, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(b.human, a.human, rtol=1e-9, atol=1e-12)


def test_the_one_line_error_names_the_unit_and_the_fix(sets, tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert main(["fit", "--data", str(sets[1]), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and not out.exists()
    assert ("time column 't' looks like milliseconds (--time-unit ms, or time_unit: ms in a "
            "spec) in 6 files") in err


def test_the_option_and_the_spec_read_it(sets, tmp_path, capsys):
    quick = ["--windows", "0.2", "--ratios", "0.5", "--workers", "1", "--no-progress"]
    assert main(["evaluate", "--data", str(sets[1]), "--time-unit", "ms", *quick,
                 "--out", str(tmp_path / "a.json")]) == 0
    spec = tmp_path / "spec.json"
    spec.write_text('{"time_unit": "us"}')
    assert main(["evaluate", "--data", str(sets[2]), "--spec", str(spec), *quick,
                 "--out", str(tmp_path / "b.json")]) == 0
    capsys.readouterr()
    assert main(["fit", "--data", str(sets[1]), "--time-unit", "hours",
                 "--out", str(tmp_path / "c.npz")]) == 2
    assert "argument --time-unit: invalid choice: 'hours'" in capsys.readouterr().err
    assert not (tmp_path / "c.npz").exists()

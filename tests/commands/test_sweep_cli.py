"""``python -m sandbox sweep``: a run, its re-run, and bad input refused before any work."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sandbox.cli import main

#: Quick folds: few candidates, one kept sample in four, a 1 s window.
GRID = ("n_basis: [15]\nobserve: [hand, 'hand,arm']\nn_candidates: [10]\nsubsample: [4]\n"
        "dow_t: [1.0]\n")
DATA = ["--data", "synthetic:two_task", "--n-per-task", "3"]


def _grid(tmp_path: Path, text: str = GRID) -> str:
    path = tmp_path / "grid.yaml"
    path.write_text(text)
    return str(path)


@pytest.fixture
def no_loading(monkeypatch):
    """Fail the test if any trial is loaded: bad input must be refused before that."""
    import sandbox.eval.datasets

    def load_pair(*args, **kwargs):
        raise AssertionError("trials were loaded")

    monkeypatch.setattr(sandbox.eval.datasets, "load_pair", load_pair)


@pytest.mark.slow
def test_a_sweep_ranks_its_configurations_and_a_rerun_skips_them(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["sweep", *DATA, "--grid", _grid(tmp_path), "--out", str(out), "--workers", "1"]
    assert main(args) == 0
    printed = capsys.readouterr()
    assert "2 configurations ranked, 0 failed" in printed.out
    summary = json.loads((out / "summary.json").read_text())
    assert [e["observe"] for e in summary["ranked"]] in (["hand", "hand,arm"],
                                                          ["hand,arm", "hand"])
    assert "| 1 |" in (out / "summary.md").read_text() and (out / "summary.png").is_file()
    assert len(list((out / "results").glob("*.json"))) == 2
    assert main(args) == 0
    assert "2 of 2 configurations already done" in capsys.readouterr().err


@pytest.mark.parametrize("grid, extra, message", [
    ("n_basis: [15]\nspeed: [1, 2]\n", [], "speed: unknown option; expected one of"),
    ("n_basis: []\n", [], "n_basis: expected a non-empty list of values, got []"),
    (GRID, ["--workers", "0"], "--workers: expected a positive integer <= 256, got '0'"),
    (GRID, ["--scheduler-timeout", "0"], "--scheduler-timeout: expected a finite number in (0"),
])
def test_bad_input_is_refused_before_any_work(tmp_path, capsys, no_loading, grid, extra,
                                              message):
    out = tmp_path / "out"
    assert main(["sweep", *DATA, "--grid", _grid(tmp_path, grid), "--out", str(out),
                 *extra]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_an_unreachable_scheduler_is_refused_naming_its_address(tmp_path, capsys, no_loading):
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    assert main(["sweep", *DATA, "--grid", _grid(tmp_path), "--out", str(out),
                 "--scheduler", "tcp://127.0.0.1:9", "--scheduler-timeout", "1"]) == 2
    err = capsys.readouterr().err
    assert "no Dask scheduler answered at 'tcp://127.0.0.1:9' within 1 s" in err
    assert not out.exists()


def test_an_out_folder_of_another_sweep_is_refused_unless_forced(tmp_path, capsys, no_loading,
                                                                 monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.json").write_text(json.dumps({"fingerprint": "another grid"}))
    args = ["sweep", *DATA, "--grid", _grid(tmp_path), "--out", str(out)]
    assert main(args) == 2
    assert "another sweep's results; use --force" in capsys.readouterr().err
    import sandbox.eval.sweep

    monkeypatch.setattr(sandbox.eval.sweep, "open_executor", lambda *a: _Stop())
    with pytest.raises(_Stopped):      # --force: past the check, on to the executor
        main([*args, "--force", "--debug"])


class _Stopped(Exception):
    pass


class _Stop:
    def __enter__(self):
        raise _Stopped

    def __exit__(self, *exc):
        return False


def test_tune_takes_the_same_executor_options(capsys, no_loading):
    assert main(["tune", "--data", "synthetic:two_task", "--workers", "0"]) == 2
    assert "--workers: expected a positive integer <= 256, got '0'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["tune", "--help"])
    assert "--scheduler ADDRESS|local" in capsys.readouterr().out

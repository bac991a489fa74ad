"""Regression tests of the command line's input checks (issue 13: finding 8, item 6)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from sandbox.cli import build_parser, main
from sandbox.commands import _types

REPO = Path(__file__).resolve().parents[2]
EVAL = ["evaluate", "--data", "synthetic:two_task", "--no-progress"]

BAD_NUMBERS = [
    ([*EVAL, "--ratios", "nan"], "--ratios"),
    ([*EVAL, "--ratios", "0.3,inf"], "--ratios"),
    ([*EVAL, "--ratios", "1.5"], "--ratios"),
    ([*EVAL, "--ratios", ","], "--ratios"),
    ([*EVAL, "--windows", "-1"], "--windows"),
    ([*EVAL, "--windows", "0"], "--windows"),
    ([*EVAL, "--windows", "1e9"], "--windows"),
    ([*EVAL, "--workers", "0"], "--workers"),
    ([*EVAL, "--workers", "-3"], "--workers"),
    ([*EVAL, "--workers", "2.5"], "--workers"),
    ([*EVAL, "--seed", "-1"], "--seed"),
    ([*EVAL, "--n-per-task", "0"], "--n-per-task"),
    (["fit", "--data", "synthetic:two_task", "--n-basis", "200000"], "--n-basis"),
    (["fit", "--data", "synthetic:two_task", "--n-basis", "1"], "--n-basis"),
    (["fit", "--data", "synthetic:two_task", "--regularizer", "nan"], "--regularizer"),
    (["fit", "--data", "synthetic:two_task", "--regularizer", "-1"], "--regularizer"),
    (["tune", "--data", "synthetic:two_task", "--window", "inf"], "--window"),
    (["tune", "--data", "synthetic:two_task", "--workers", "0"], "--workers"),
    (["bench", "--repeats", "nan"], "--repeats"),
    (["play", "--dow", "nan"], "--dow"),
    (["play", "--time-limit", "inf"], "--time-limit"),
    (["play", "--demos", "1"], "--demos"),
    (["demo", "--switch", "nan"], "--switch"),
    (["demo", "--ratio", "0"], "--ratio"),
    (["demo", "--seed", "1e3"], "--seed"),
    (["data", "check-filter", "--data", ".", "--gate-prob", "2"], "--gate-prob"),
    (["data", "check-filter", "--data", ".", "--accel-std", "nan"], "--accel-std"),
    (["results", "--workers", "-1"], "--workers"),
]


@pytest.mark.parametrize(("argv", "option"), BAD_NUMBERS)
def test_numeric_options_refuse_nan_inf_and_out_of_range(argv, option, tmp_path, capsys):
    """issue 13 finding 8: `evaluate --ratios nan` exited 0 with NaN in the report,
    `--workers 0`/`-3` became 1, `fit --n-basis 200000` gave a traceback; every numeric
    option is now checked by argparse, naming the option, before any work."""
    out = tmp_path / "out.json"
    needs_out = argv[0] in ("evaluate", "fit")
    assert main([*argv, *(["--out", str(out)] if needs_out else [])]) == 2
    err = capsys.readouterr().err
    assert f"argument {option}: expected" in err and "Traceback" not in err
    assert not out.exists()


def test_n_basis_range_is_documented_and_bounds_the_option(capsys):
    """issue 13 finding 8: `fit --n-basis` takes 2 .. the core's MAX_N_BASIS, its help says so."""
    from sandbox.core.limits import MAX_N_BASIS

    assert _types.MAX_N_BASIS == MAX_N_BASIS
    assert _types.N_BASIS(str(MAX_N_BASIS)) == MAX_N_BASIS and _types.N_BASIS("2") == 2
    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    assert f"2 to {MAX_N_BASIS}" in " ".join(capsys.readouterr().out.split())


def test_window_limit_matches_the_core_duration_limit():
    """issue 13 item 1: the CLI's longest window is the core's MAX_DURATION_S."""
    from sandbox.core.limits import MAX_DURATION_S

    assert _types.MAX_WINDOW_S == MAX_DURATION_S


def test_valid_defaults_parse_as_before():
    """issue 13 item 6: valid use is unchanged (the defaults go through the same types)."""
    args = build_parser().parse_args(["evaluate", "--data", "d", "--out", "r.json"])
    assert args.windows == (1.0, 0.5, 0.2, 0.1)
    assert args.ratios == tuple(k / 10 for k in range(1, 10))
    assert (args.workers, args.seed, args.n_per_task, args.debug) == (2, 0, None, False)


@pytest.mark.parametrize("make", [
    lambda d: [*EVAL, "--out", str(d)],
    lambda d: [*EVAL, "--out", str(d / "r.json"), "--markdown", str(d)],
    lambda d: [*EVAL, "--out", str(d / "r.json"), "--markdown", str(d / "file.txt" / "r.md")],
    lambda d: [*EVAL, "--out", str(d / "file.txt" / "no" / "r.json")],
    lambda d: [*EVAL, "--out", str(d / "r.json"), "--plots", str(d / "file.txt" / "figs")],
    lambda d: ["fit", "--data", "synthetic:two_task", "--out", str(d)],
    lambda d: ["fit", "--data", "synthetic:two_task", "--out", str(d / "file.txt" / "m.npz")],
    lambda d: ["tune", "--data", "synthetic:two_task", "--json", str(d)],
    lambda d: ["plot", "r.json", "--out", str(d / "file.txt")],
    lambda d: ["results", "--figures", str(d / "file.txt")],
    lambda d: ["play", "--scenario", "waypoints", "--summary", str(d)],
    lambda d: ["play", "--scenario", "waypoints", "--out", str(d / "file.txt" / "r.html")],
    lambda d: ["demo", "--out", str(d / "file.txt" / "demo.html")],
])
def test_output_paths_are_checked_before_any_work(make, tmp_path, capsys):
    """issue 13 finding 8: `--markdown` or `fit --out` pointing at a folder gave a traceback
    after the work was done; an output path that cannot be written is refused at once."""
    (tmp_path / "file.txt").write_text("x")
    argv = make(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "error: argument --" in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


def _raising(error: BaseException):
    def run(args) -> int:
        raise error

    return run


@pytest.mark.parametrize(("error", "status", "words"), [
    (ValueError("bad value"), 2, "error: bad value"),
    (FileNotFoundError(2, "No such file or directory", "x.csv"), 1,
     "error: [Errno 2] No such file or directory: 'x.csv'"),
    (PermissionError(13, "Permission denied", "out.json"), 1, "Permission denied"),
    (RuntimeError("oops"), 1, "error: unexpected RuntimeError: oops (run with --debug"),
    (KeyboardInterrupt(), 130, "error: interrupted"),
])
def test_no_traceback_reaches_the_user(monkeypatch, capsys, error, status, words):
    """issue 13 item 6: an error ends a command with one line on stderr and a status."""
    import sandbox.commands.plot as plot

    monkeypatch.setattr(plot, "run", _raising(error))
    assert main(["plot", "r.json", "--out", "figs"]) == status
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and err.count("\n") == 1


@pytest.mark.parametrize("argv", [["--debug", "plot", "r.json", "--out", "figs"],
                                  ["plot", "r.json", "--out", "figs", "--debug"]])
def test_debug_shows_the_traceback(monkeypatch, argv):
    """issue 13 item 6: `--debug` (before or after the command) lets the exception through."""
    import sandbox.commands.plot as plot

    monkeypatch.setattr(plot, "run", _raising(FileNotFoundError(2, "gone", "r.json")))
    with pytest.raises(FileNotFoundError):
        main(argv)


def test_the_installed_entry_point_prints_no_traceback(tmp_path):
    """issue 13 finding 8: `python -m sandbox evaluate --ratios nan` fails cleanly (status 2)."""
    out = subprocess.run(
        [sys.executable, "-m", "sandbox", "evaluate", "--data", "synthetic:two_task", "--out",
         str(tmp_path / "r.json"), "--ratios", "nan"],
        capture_output=True, text=True, cwd=REPO, timeout=60,
        env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 2
    assert "argument --ratios" in out.stderr and "Traceback" not in out.stderr

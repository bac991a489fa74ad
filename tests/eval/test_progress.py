"""Progress on stderr: drawn on a terminal only, never on stdout, off with enabled=False."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
from pathlib import Path

from sandbox.bench.evaluate import read_terminal
from sandbox.eval import progress

REPO = Path(__file__).resolve().parents[2]
SCRIPT = ("from sandbox.eval.progress import bar, status\n"
          "status('loading the set', {enabled})\n"
          "with bar(3, 'trials', {enabled}) as b:\n"
          "    [b.update() for _ in range(3)]\n"
          "print('result')\n")


def _run(enabled: bool, terminal: bool) -> tuple[str, str]:
    """stdout and stderr of SCRIPT, stderr a pseudo-terminal or a pipe."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    cmd = [sys.executable, "-c", SCRIPT.format(enabled=enabled)]
    if not terminal:
        done = subprocess.run(cmd, capture_output=True, env=env, timeout=120, check=True)
        return done.stdout.decode(), done.stderr.decode()
    master, slave = pty.openpty()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=slave, env=env)
    os.close(slave)
    err = read_terminal(master, proc, timeout=120)
    out = proc.communicate(timeout=120)[0]
    os.close(master)
    return out.decode(), err.decode(errors="replace")


def test_drawn_on_a_terminal_with_a_size_even_if_it_says_zero():
    out, err = _run(True, terminal=True)
    assert out == "result\n"
    assert "loading the set" in err and "trials: 100%" in err and "3/3" in err


def test_nothing_on_a_pipe_or_when_disabled():
    assert _run(True, terminal=False) == ("result\n", "")
    out, err = _run(False, terminal=True)
    assert out == "result\n" and "trials" not in err and "loading" not in err


def test_shown_needs_both(monkeypatch, capsys):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert progress.shown(True) and not progress.shown(False)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False, raising=False)
    assert not progress.shown(True)
    progress.status("hidden", True)
    assert capsys.readouterr().err == ""


TUNE = ("from sandbox.eval.datasets import load_pair\n"
        "from sandbox.eval.loocv import EvalConfig\n"
        "from sandbox.eval.tune import tune\n"
        "train, test, _ = load_pair('synthetic:two_task', n_per_task=4, seed=0)\n"
        "best, rows = tune(train, test, grid={{'noise_floor': [0.01, 0.02], "
        "'likelihood': ['joint', 'marginal']}}, workers=1, progress={enabled})\n"
        "print('rows', len(rows))\n")


def test_tune_counts_its_trials_on_a_terminal():
    """Issue 27: tune showed nothing for a minute; now a bar of k of N trials with an ETA.

    2 values of noise_floor, then 2 of likelihood of which 'joint' (the current choice)
    is not re-run: 3 runs of 8 trials; the bar's total shrinks from 32 to 24.
    """
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-c", TUNE.format(enabled=True)],
                            stdout=subprocess.PIPE, stderr=slave, env=env)
    os.close(slave)
    err = read_terminal(master, proc, timeout=600).decode(errors="replace")
    out = proc.communicate(timeout=600)[0].decode()
    os.close(master)
    assert proc.returncode == 0, err
    assert "tune (4 runs)" in err and "24/24" in err
    assert out.count("noise_floor") == 2 and out.rstrip().endswith("rows 3")
    assert "tune (" not in out                    # the bar never goes to stdout

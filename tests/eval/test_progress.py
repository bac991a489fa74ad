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

"""``bench`` shows signs of life: a bar of its stages on a terminal's stderr, JSON on stdout."""

from __future__ import annotations

import json
import os
import pty
import subprocess
import sys
from argparse import Namespace
from pathlib import Path

import pytest

from sandbox.bench.evaluate import read_terminal
from sandbox.commands.bench import _stages

REPO = Path(__file__).resolve().parents[2]


def test_stages_follow_the_skip_options():
    names = lambda **kw: [n for n, _ in _stages(Namespace(repeats=1, seed=0, **kw))]  # noqa: E731
    core = ["predictor update", "many tasks and demos"]
    assert names(skip_env=True, skip_vector=False) == core
    assert names(skip_env=False, skip_vector=True) == [*core, "environments"]
    assert names(skip_env=False, skip_vector=False) == [
        *core, "environments", "vector environments"]
    assert names(skip_env=True, skip_vector=False, methods=True) == [*core, "methods"]


@pytest.mark.slow
def test_json_bench_draws_its_bar_on_stderr_only():
    """Issue 27: ``bench --json`` was silent for a minute."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "sandbox", "bench", "--skip-env",
                             "--repeats", "1", "--json"], stdout=subprocess.PIPE, stderr=slave,
                            env=env, cwd=REPO)
    os.close(slave)
    err = read_terminal(master, proc, timeout=900).decode(errors="replace")
    out = proc.communicate(timeout=900)[0].decode()
    os.close(master)
    assert proc.returncode == 0, err
    assert "bench" in err and "2/2" in err and "predictor update" in err
    result = json.loads(out)                     # stdout is the JSON alone
    assert result["update_ms"] > 0
    assert set(result["roofline"]["stages"]) == {"phase", "recognition", "conditioning",
                                                 "blending"}
    assert result["update_20_tasks_ms"] > 0 and set(result["update_demos_ms"]) == {
        "10", "20", "40", "80", "160"}

"""Importing the PyBullet modules prints nothing (issue 27: a stray 'pybullet build time' line)."""

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_no_build_time_line_on_stderr():
    code = "import sandbox.robot.bullet, sandbox.viz.bodies; import envs.pybullet; print('ok')"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=REPO, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "ok\n" and "pybullet build time" not in done.stderr


def test_pybullet_errors_still_show():
    """The silenced descriptor is restored before Python reports anything."""
    code = ("import sandbox.robot.pybullet_quiet as q, sys\n"
            "print('after', file=sys.stderr)\n"
            "q.pybullet.getNumBodies(physicsClientId=999)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=REPO, timeout=300)
    assert done.returncode != 0
    assert "after" in done.stderr and "error" in done.stderr.lower()

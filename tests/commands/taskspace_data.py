"""A synthetic recorded set whose robot part is in task space (issue 28 item 2), for tests.

Two tasks (``left``, ``right``) of handovers at 100 Hz: the human hand reaches
from a common start to a task's meeting point with a bell-shaped speed profile
(minimum jerk) plus tracker jitter; the robot part is the receiving hand's
x, y, z (m), reaching from its own start to 3 cm beside the meeting point.
Written in the built-in per-trial layout ``<root>/<task>/<trial>.csv`` with a
spec file that declares ``robot: {columns: [rx, ry, rz], space: task}``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HAND_START = np.array([0.9, 0.4, 0.0])
ROBOT_START = np.array([0.6, 0.6, 0.2])
GOALS = {"left": np.array([0.75, 0.55, 0.15]), "right": np.array([0.75, 0.25, 0.05])}
#: The robot part stops this far (m) from the hand: the object is between them.
BESIDE = np.array([0.0, 0.03, 0.0])
SPEC = "time: t\nrobot: {columns: [rx, ry, rz], space: task}\nobserve: [hand]\n" \
       "modalities:\n  hand: {columns: [hx, hy, hz], kind: position, units: m}\n"


def min_jerk(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk progress (0 -> 1) at normalised times ``s`` in [0, 1]."""
    s = np.clip(s, 0.0, 1.0)
    return 10 * s**3 - 15 * s**4 + 6 * s**5


def trial(task: str, rng: np.random.Generator, jitter: float = 0.001) -> np.ndarray:
    """Rows (t, hx, hy, hz, rx, ry, rz) of one handover: motion, then a 0.4 s hold."""
    duration = rng.uniform(1.6, 2.2)
    t = np.arange(0.0, duration + 0.4, 0.01)
    goal = GOALS[task] + rng.normal(0.0, 0.01, 3)
    p = min_jerk(t / duration)[:, None]
    hand = HAND_START + p * (goal - HAND_START) + rng.normal(0.0, jitter, (t.size, 3))
    robot = ROBOT_START + p * (goal + BESIDE - ROBOT_START)
    return np.column_stack([t, hand, robot])


def write_set(root: Path, n_per_task: int = 4, seed: int = 0) -> Path:
    """Write the set under ``root`` and its spec as ``root / "spec.yaml"``; returns the spec."""
    rng = np.random.default_rng(seed)
    for task in GOALS:
        (root / "data" / task).mkdir(parents=True, exist_ok=True)
        for i in range(n_per_task):
            np.savetxt(root / "data" / task / f"{i:03d}.csv", trial(task, rng), delimiter=",",
                       header="t,hx,hy,hz,rx,ry,rz", comments="", fmt="%.6f")
    spec = root / "spec.yaml"
    spec.write_text(SPEC)
    return spec

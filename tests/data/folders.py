"""Small folders in the shared CSV layout, written from synthetic trials (test helper)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sandbox.data.datasets import load_dataset
from sandbox.data.writer import next_trial_path, write_trial


def write_synthetic_set(root: Path, name: str = "two_task", *, n_per_task: int = 3,
                        seed: int = 0, shift: float = 0.0) -> Path:
    """``root/<task>/<NNN>.csv`` of the raw trials (tracker artefacts included) of
    ``synthetic:name`` with ``seed``; ``shift`` (m) is added to the hand's x, y and z
    columns (another tracker calibration). Returns ``root``."""
    demos = load_dataset(f"synthetic:{name}", seed=seed, n_per_task=n_per_task,
                         preprocess="none")
    for demo in demos:
        columns = {n: demo.human[:, j] + shift for j, n in enumerate(demo.human_names)}
        columns.update({n: demo.robot[:, j] for j, n in enumerate(demo.robot_names)})
        write_trial(next_trial_path(root / demo.task), np.asarray(demo.times), columns)
    return root

"""Synthetic paired human/robot handover demonstrations (seeded), the default data.

Submodules: :mod:`~sandbox.data.synthetic.base` (constants), ``two_task`` (the
minimal generator), ``human`` (clean reaches), ``tracker`` (sensor artefacts),
``realism`` (synthetic vs recorded statistics).
"""

from sandbox.data.synthetic.base import (
    HAND_START,
    HUMAN_NAMES,
    Q_HOME,
    ROBOT_NAMES,
    minimum_jerk,
)
from sandbox.data.synthetic.realism import compare_realism, realism_stats
from sandbox.data.synthetic.registry import DATASETS, make_dataset
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.data.synthetic.two_task import two_task_demos

__all__ = [
    "DATASETS",
    "HAND_START",
    "HUMAN_NAMES",
    "Q_HOME",
    "ROBOT_NAMES",
    "TrackerModel",
    "compare_realism",
    "make_dataset",
    "minimum_jerk",
    "realism_stats",
    "two_task_demos",
]

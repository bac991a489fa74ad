"""Synthetic paired human/robot handover demonstrations (seeded), the default data.

Datasets by name: :func:`make_dataset` (``"two_task"``, ``"diverging"``,
``"objects"``), observing the hand (default) or the hand and the arm
(``observe="hand,arm"``). Submodules: ``base`` (constants), ``two_task`` (the
minimal generator), ``human`` (clean reaches), ``arm`` (the human's elbow and
shoulder), ``two_link`` (the arm's inverse kinematics), ``tracker`` (sensor
artefacts), ``observe`` (which modalities a demonstration carries), ``tasks``
(task geometry and random draws), ``robot`` (the paired Baxter arm motion),
``generator`` (assembly), ``families`` (objects and diverging tasks),
``intent`` (a change of task mid-motion, with its ground truth), ``realism``
(synthetic vs recorded statistics), ``session`` (a recording session drawn
from a seed: the tracker's calibration, where the fingertip meets the hand,
the tempo, the motion's tail; ``make_dataset(..., session=S)``) and ``tails``
(what the hand does after the handover in a session). Baxter's own facts (home pose, tip link,
grasp offset) come from :mod:`sandbox.robot`.

Examples
--------
>>> import numpy as np
>>> from sandbox.data.synthetic import make_dataset, intent_switch_demo, TrackerModel
>>> demos = make_dataset("objects", 2, np.random.default_rng(0))
>>> [d.task for d in demos]
['box', 'box', 'glasses_case', 'glasses_case', 'tape', 'tape']
>>> clean = make_dataset("diverging", 1, np.random.default_rng(0), tracker=TrackerModel.clean())
>>> demo, truth = intent_switch_demo("left", "right", 0.6, np.random.default_rng(0))
>>> demo.task, truth.task_at([0.0, demo.duration]).tolist()
('right', ['left', 'right'])
>>> arm = make_dataset("objects", 1, np.random.default_rng(0), observe="hand,arm")
>>> arm[0].human.shape[1], [m.name for m in arm[0].modalities], arm[0].meta["clean_arm"].shape[1]
(9, ['hand', 'arm'], 6)
>>> from sandbox.data.synthetic import draw_session
>>> linger = draw_session(3, tail="linger")
>>> lab = make_dataset("objects", 1, np.random.default_rng(0), session=linger)
>>> lab[0].meta["session"]["tail"], lab[0].meta["tracked_clean"].shape == lab[0].human.shape
('linger', True)
"""

from sandbox.data.synthetic.arm import ArmModel, arm_positions
from sandbox.data.synthetic.base import (
    HAND_START,
    HUMAN_NAMES,
    ROBOT_NAMES,
    minimum_jerk,
)
from sandbox.data.synthetic.families import OBJECTS, diverging_demos, objects_demos
from sandbox.data.synthetic.intent import IntentSwitch, intent_switch_demo
from sandbox.data.synthetic.realism import (
    arm_realism_stats,
    compare_arm_realism,
    compare_realism,
    realism_stats,
)
from sandbox.data.synthetic.registry import DATASETS, make_dataset
from sandbox.data.synthetic.session import TAILS, Session, draw_session
from sandbox.data.synthetic.tasks import TaskSpec, Variability
from sandbox.data.synthetic.tracker import TrackerModel
from sandbox.data.synthetic.two_task import two_task_demos

__all__ = [
    "ArmModel",
    "DATASETS",
    "HAND_START",
    "HUMAN_NAMES",
    "IntentSwitch",
    "OBJECTS",
    "ROBOT_NAMES",
    "Session",
    "TAILS",
    "TaskSpec",
    "TrackerModel",
    "Variability",
    "arm_positions",
    "arm_realism_stats",
    "compare_arm_realism",
    "compare_realism",
    "diverging_demos",
    "draw_session",
    "make_dataset",
    "intent_switch_demo",
    "minimum_jerk",
    "objects_demos",
    "realism_stats",
    "two_task_demos",
]

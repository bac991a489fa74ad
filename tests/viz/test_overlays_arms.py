"""Overlays of any arm (issue 23): a task-space plan drawn as it is, another arm's fingertip."""

from __future__ import annotations

import meshcat
import numpy as np
import pytest

from sandbox.robot import Q_HOME, TIP_LINK, BaxterKinematics
from sandbox.viz.overlays import OverlayStyle, PredictionOverlay
from sandbox.viz.scene import Scene


@pytest.fixture
def overlay():
    vis = meshcat.Visualizer(window=Scene(fps=10))
    return PredictionOverlay(vis["overlays"], rng=np.random.default_rng(0), tasks=("a", "b"),
                             style=OverlayStyle(n_samples=5, max_steps=4))


def test_a_task_space_plan_is_drawn_at_its_positions(overlay):
    means = np.stack([np.linspace(0.6, 0.8, 6), np.full(6, 0.2), np.full(6, 0.1)], axis=1)
    covs = np.repeat(1e-6 * np.eye(3)[None], 6, axis=0)
    path, samples = overlay.gripper_paths(means, covs)
    np.testing.assert_array_equal(path, means[[0, 2, 3, 5]])
    assert samples.shape == (5, 4, 3) and np.abs(samples - path).max() < 0.01


def test_a_joint_space_plan_is_drawn_at_baxters_fingertip(overlay):
    means = np.repeat(Q_HOME[None], 3, axis=0)
    path, _ = overlay.gripper_paths(means, np.repeat(1e-8 * np.eye(7)[None], 3, axis=0))
    np.testing.assert_allclose(path[0], BaxterKinematics().fk(Q_HOME, link=TIP_LINK))
    with pytest.raises(ValueError, match="covs"):
        overlay.gripper_paths(means, np.zeros((3, 3, 3)))

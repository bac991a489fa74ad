"""Environments shared by the tests of :mod:`sandbox.envs` (loading Baxter takes ~1.3 s)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import sandbox.envs  # noqa: F401  (registers the environments)


@pytest.fixture(scope="session")
def diverging_env():
    """``sandbox/BaxterHandoverDiverging-v1`` through ``gym.make`` (tests reset it themselves)."""
    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    yield env
    env.close()


@pytest.fixture(scope="session")
def objects_env():
    """``sandbox/BaxterHandover-v1`` through ``gym.make``, with ``render_mode="rgb_array"``."""
    env = gym.make("sandbox/BaxterHandover-v1", render_mode="rgb_array")
    yield env
    env.close()

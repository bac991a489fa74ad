"""Environments shared by the tests of :mod:`sandbox.envs` (loading Baxter takes ~1.3 s)."""

from __future__ import annotations

import gymnasium as gym
import pytest

import sandbox.envs  # noqa: F401  (registers the environments)


@pytest.fixture(scope="session")
def diverging_env():
    """``sandbox/BaxterHandoverDiverging-v0`` through ``gym.make`` (tests reset it themselves)."""
    env = gym.make("sandbox/BaxterHandoverDiverging-v0")
    yield env
    env.close()


@pytest.fixture(scope="session")
def objects_env():
    """``sandbox/BaxterHandover-v0`` through ``gym.make``, with ``render_mode="rgb_array"``."""
    env = gym.make("sandbox/BaxterHandover-v0", render_mode="rgb_array")
    yield env
    env.close()

"""Fixtures shared by the tests of :mod:`sandbox.episodes`."""

from __future__ import annotations

import gymnasium as gym
import pytest

import sandbox.envs  # noqa: F401  (registers the environments)


@pytest.fixture(scope="module")
def env():
    """``sandbox/BaxterHandoverDiverging-v1`` through ``gym.make``, one per test module."""
    env = gym.make("sandbox/BaxterHandoverDiverging-v1")
    yield env
    env.close()

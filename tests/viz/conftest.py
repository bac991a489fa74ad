"""Fixtures of the viewer tests: a PyBullet Baxter (loaded once per module)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def baxter():
    """A Baxter in its own DIRECT client, arm at the recorded home configuration."""
    from sandbox.robot import q_home
    from sandbox.robot.bullet import connect, load_baxter, reset_arm

    client = connect()
    robot = load_baxter(client)
    reset_arm(robot, q_home())
    yield robot
    client.disconnect()

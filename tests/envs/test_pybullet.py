"""The simulation wrapper: named bodies, save/restore, constraints, independence, close."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox import urdf
from sandbox.envs.pybullet import Simulation


@pytest.fixture()
def sim():
    sim = Simulation(physics_hz=240.0)
    sim.load_urdf("floor", urdf.path("floor"), (0, 0, 0), fixed=True)
    sim.load_urdf("box", urdf.path("box"), (0, 0, 0.5))
    yield sim
    sim.close()


def test_a_dropped_box_lands_on_the_floor(sim):
    for _ in range(480):
        sim.step_physics()
    position, _ = sim.pose("box")
    assert position[2] == pytest.approx(0.045 / 2, abs=0.002)  # half the box's height


def test_restore_returns_to_the_saved_state(sim):
    sim.save()
    for _ in range(100):
        sim.step_physics()
    moved, _ = sim.pose("box")
    sim.restore()
    np.testing.assert_allclose(sim.pose("box")[0], (0, 0, 0.5))
    for _ in range(100):
        sim.step_physics()
    np.testing.assert_array_equal(sim.pose("box")[0], moved)  # deterministic


def test_restore_before_save_is_refused(sim):
    with pytest.raises(RuntimeError, match="save"):
        sim.restore()


def test_attach_keeps_the_relative_pose(sim):
    sim.load_urdf("tape", urdf.path("tape"), (0.3, 0.0, 0.5))
    sim.set_pose("box", (0.0, 0.0, 1.0))
    sim.load_urdf("anchor", urdf.path("human_hand"), (0.0, 0.0, 1.0), fixed=True)
    sim.disable_collisions("anchor", "box")
    sim.disable_collisions("anchor", "tape")
    cid = sim.attach("anchor", -1, "tape")
    for _ in range(240):
        sim.step_physics()
    np.testing.assert_allclose(sim.pose("tape")[0], (0.3, 0.0, 0.5), atol=0.01)  # held
    sim.detach(cid)
    for _ in range(240):
        sim.step_physics()
    assert sim.pose("tape")[0][2] < 0.1  # fell


def test_set_pose_at_rest_zeroes_the_velocity(sim):
    for _ in range(50):
        sim.step_physics()
    sim.set_pose("box", (0, 0, 0.5), at_rest=True)
    assert np.allclose(sim.client.getBaseVelocity(sim.bodies["box"])[0], 0.0)


def test_advance_carries_a_moving_body_as_set_pose_at_rest_then_a_step(sim):
    """advance() relies on PyBullet's teleport zeroing the base velocity (it makes no
    resetBaseVelocity call): the same state, bit for bit, as set_pose(at_rest=True)."""
    box, spin = sim.bodies["box"], ([1.0, -2.0, 3.0], [4.0, 5.0, -6.0])
    sim.save()
    sim.client.resetBaseVelocity(box, *spin)
    sim.advance(2, "box", [[0.1, 0.2, 0.5], [0.1, 0.3, 0.5]])
    carried = sim.client.getBasePositionAndOrientation(box), sim.client.getBaseVelocity(box)
    sim.restore()
    sim.client.resetBaseVelocity(box, *spin)
    for position in ([0.1, 0.2, 0.5], [0.1, 0.3, 0.5]):
        sim.set_pose("box", position, at_rest=True)
        sim.step_physics()
    assert carried == (sim.client.getBasePositionAndOrientation(box),
                       sim.client.getBaseVelocity(box))
    assert carried[1][0][2] != 0.0                 # a step under gravity after the teleport


def test_names_are_unique_and_simulations_independent(sim):
    with pytest.raises(ValueError, match="exists already"):
        sim.load_urdf("box", urdf.path("box"), (0, 0, 0))
    other = Simulation()
    try:
        other.load_urdf("box", urdf.path("box"), (5, 5, 5))
        assert other.client._client != sim.client._client
        np.testing.assert_allclose(sim.pose("box")[0], (0, 0, 0.5))
    finally:
        other.close()


def test_render_and_close_twice(sim):
    image = sim.render(width=64, height=48)
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    sim.close()
    sim.close()


def test_bad_rate_is_refused():
    with pytest.raises(ValueError, match="physics_hz"):
        Simulation(physics_hz=0)

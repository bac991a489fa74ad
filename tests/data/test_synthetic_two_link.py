"""Two-link inverse kinematics of the arm: known answers and properties."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.data.synthetic.two_link import elbow_positions, swivel_angle

A, B = 0.32, 0.25  # upper arm and forearm (m)


def _random_reachable(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Shoulders and wrists at distances strictly between |a - b| and a + b."""
    shoulder = rng.uniform(-0.5, 0.5, (n, 3))
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    d = rng.uniform(abs(A - B) + 0.01, A + B - 0.01, n)
    return shoulder, shoulder + d[:, None] * direction


def test_elbow_is_at_the_segment_lengths_and_respects_the_swivel():
    rng = np.random.default_rng(0)
    shoulder, wrist = _random_reachable(rng, 500)
    swivel = rng.uniform(-3.0, 3.0, 500)
    elbow = elbow_positions(shoulder, wrist, A, B, swivel)
    assert np.allclose(np.linalg.norm(elbow - shoulder, axis=1), A, atol=1e-12)
    assert np.allclose(np.linalg.norm(elbow - wrist, axis=1), B, atol=1e-12)
    assert np.allclose(swivel_angle(shoulder, elbow, wrist), swivel, atol=1e-9)


def test_known_elbow_of_a_forward_arm():
    # the arm points forward (-x) from the shoulder; a = b, the wrist at a * sqrt(2)
    d = A * np.sqrt(2.0)
    shoulder, wrist = np.zeros(3), np.array([-d, 0.0, 0.0])
    down = elbow_positions(shoulder, wrist, A, A, 0.0)
    out = elbow_positions(shoulder, wrist, A, A, np.pi / 2)
    assert np.allclose(down, [[-d / 2, 0.0, -d / 2]])  # swivel 0: straight below the axis
    assert np.allclose(out, [[-d / 2, d / 2, 0.0]])  # +90 deg: outward (+y)
    # a body whose outward is -y faces +x (forward = up x outward): the mirror image
    mirror = elbow_positions(shoulder, -wrist, A, A, np.pi / 2, outward=(0.0, -1.0, 0.0))
    assert np.allclose(mirror, [[d / 2, -d / 2, 0.0]])


def test_zero_swivel_is_the_lowest_point_of_the_elbow_circle():
    shoulder, wrist = np.array([1.3, 0.0, 0.34]), np.array([0.95, 0.15, 0.2])
    phis = np.linspace(-np.pi, np.pi, 721)
    circle = elbow_positions(shoulder, wrist, A, B, phis)
    assert np.argmin(circle[:, 2]) == np.argmin(np.abs(phis))
    assert np.all(circle[phis > 0.01, 1] > circle[np.abs(phis) < 1e-9, 1])  # > 0 is outward


@pytest.mark.parametrize("distance", [A + B, A + B + 1e-6, 0.7, 3.0])
def test_out_of_reach_gives_a_straight_arm_pointing_at_the_hand(distance):
    shoulder = np.array([1.3, 0.0, 0.34])
    direction = np.array([-0.8, 0.5, -0.2]) / np.linalg.norm([-0.8, 0.5, -0.2])
    wrist = shoulder + distance * direction
    for swivel in (0.0, 1.2):
        elbow = elbow_positions(shoulder, wrist, A, B, swivel)[0]
        assert np.allclose(elbow, shoulder + A * direction, atol=1e-6)


def test_too_close_gives_a_folded_arm_on_the_line():
    shoulder = np.zeros(3)
    wrist = np.array([-0.03, 0.02, 0.0])  # closer than a - b = 0.07
    elbow = elbow_positions(shoulder, wrist, A, B, 0.7)[0]
    assert np.linalg.norm(elbow) == pytest.approx(A)
    assert np.allclose(elbow, A * wrist / np.linalg.norm(wrist))
    at_shoulder = elbow_positions(shoulder, shoulder, A, B, 0.7)[0]
    assert np.allclose(at_shoulder, [0.0, 0.0, -A])  # no direction: straight down


def test_vertical_arm_bends_backward_at_zero_swivel():
    shoulder, wrist = np.zeros(3), np.array([0.0, 0.0, -0.4])
    elbow = elbow_positions(shoulder, wrist, A, B, 0.0)[0]
    assert np.isfinite(elbow).all() and elbow[0] > 0.1  # backward is +x (away from the robot)
    assert np.linalg.norm(elbow) == pytest.approx(A)


def test_shapes_broadcast_and_inputs_are_not_changed():
    shoulder = np.array([1.3, 0.0, 0.34])
    wrists = np.array([[1.0, 0.1, 0.2], [0.9, 0.2, 0.25]])
    before = wrists.copy()
    elbow = elbow_positions(shoulder, wrists, A, B, np.array([0.3, 0.5]))
    assert elbow.shape == (2, 3) and np.array_equal(wrists, before)
    assert swivel_angle(shoulder, elbow, wrists).shape == (2,)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"upper_arm": 0.0}, "upper_arm"),
        ({"forearm": -0.2}, "forearm"),
        ({"hand": np.zeros((4, 2))}, "hand"),
        ({"outward": (0.0, 2.0, 0.0)}, "outward"),
        ({"outward": (0.0, 0.0, 1.0)}, "outward"),
    ],
)
def test_bad_inputs_are_refused(kwargs, match):
    args = {"shoulder": np.zeros(3), "hand": np.array([-0.3, 0.0, 0.0]), "upper_arm": A,
            "forearm": B, "swivel": 0.0}
    outward = kwargs.pop("outward", (0.0, 1.0, 0.0))
    with pytest.raises(ValueError, match=match):
        elbow_positions(**{**args, **kwargs}, outward=outward)

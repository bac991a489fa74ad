"""Overlay geometry: sampling statistics, tube cross-sections, polyline tubes, colours."""

from __future__ import annotations

import numpy as np
import pytest

from sandbox.viz.geometry import (
    PALETTE,
    cross_section_radii,
    cross_sections,
    polyline_tube,
    sample_joint_paths,
    sample_paths,
    task_colors,
    tube,
)


def _line(n=30):
    return np.stack([np.linspace(0, 1, n), np.zeros(n), np.zeros(n)], axis=1)


def test_joint_samples_have_the_requested_moments():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(7, 7))
    cov = 0.01 * (a @ a.T + np.eye(7))
    means = np.tile(np.linspace(-1, 1, 7), (3, 1))
    samples = sample_joint_paths(means, np.stack([cov, 2 * cov, 0 * cov]), 20000, rng)
    assert samples.shape == (20000, 3, 7)
    np.testing.assert_allclose(samples.mean(0), means, atol=0.01)
    np.testing.assert_allclose(np.cov(samples[:, 0].T), cov, atol=0.004)
    np.testing.assert_allclose(np.cov(samples[:, 1].T), 2 * cov, atol=0.008)
    np.testing.assert_allclose(samples[:, 2], np.broadcast_to(means[2], (20000, 7)), atol=1e-12)


def test_sampling_is_reproducible_and_leaves_inputs_alone():
    means, covs = np.zeros((4, 7)), np.tile(0.01 * np.eye(7), (4, 1, 1))
    before = covs.copy()
    a = sample_joint_paths(means, covs, 5, np.random.default_rng(3))
    b = sample_joint_paths(means, covs, 5, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(covs, before)


def test_nearly_singular_covariances_are_accepted():
    v = np.ones((7, 1)) / np.sqrt(7)
    cov = v @ v.T - 1e-12 * np.eye(7)  # rank one, a hair indefinite
    samples = sample_joint_paths(np.zeros((1, 7)), cov[None], 100, np.random.default_rng(0))
    assert np.all(np.isfinite(samples))


def test_sample_paths_applies_forward_kinematics():
    fk = lambda q: q[..., :3] * 2.0  # noqa: E731
    out = sample_paths(fk, np.ones((5, 7)), np.zeros((5, 7, 7)), 3, np.random.default_rng(0))
    np.testing.assert_allclose(out, 2.0)
    assert out.shape == (3, 5, 3)


@pytest.mark.parametrize(
    "means, covs, n, rng, match",
    [
        (np.zeros((3, 7)), np.zeros((3, 6, 6)), 2, np.random.default_rng(0), "covs"),
        (np.zeros((3, 7)), np.zeros((3, 7, 7)), 0, np.random.default_rng(0), "n_samples"),
        (np.zeros((3, 7)), np.zeros((3, 7, 7)), 2, 0, "rng"),
        (np.full((3, 7), np.nan), np.zeros((3, 7, 7)), 2, np.random.default_rng(0), "means"),
    ],
)
def test_sampling_errors(means, covs, n, rng, match):
    with pytest.raises(ValueError, match=match):
        sample_joint_paths(means, covs, n, rng)


def test_isotropic_spread_gives_a_round_tube_of_n_sigma():
    rng = np.random.default_rng(1)
    samples = _line() + rng.normal(0, 0.01, (5000, 30, 3))
    radii = cross_section_radii(samples, n_sigma=2.0)
    np.testing.assert_allclose(radii, 0.02, rtol=0.08)


def test_spread_along_the_path_does_not_widen_the_tube():
    rng = np.random.default_rng(2)
    noise = np.zeros((3000, 30, 3))
    noise[..., 0] = rng.normal(0, 0.05, (3000, 30))  # along x, the path's direction
    noise[..., 2] = rng.normal(0, 0.01, (3000, 30))  # across, vertical
    radii = cross_section_radii(_line() + noise)
    np.testing.assert_allclose(radii[:, 0], 0.02, rtol=0.1)
    assert np.all(radii[:, 1] < 0.002)


def test_cross_section_basis_is_orthonormal_and_across_the_path():
    rng = np.random.default_rng(3)
    t = np.linspace(0, np.pi, 40)
    helix = np.stack([np.cos(t), np.sin(t), 0.3 * t], 1)
    centers, basis, covs = cross_sections(helix + rng.normal(0, 1e-3, (50, 40, 3)))
    gram = np.einsum("nak,nbk->nab", basis, basis)
    np.testing.assert_allclose(gram, np.broadcast_to(np.eye(2), gram.shape), atol=1e-9)
    tangent = np.gradient(centers, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    assert np.abs(np.einsum("nak,nk->na", basis, tangent)).max() < 1e-9
    assert covs.shape == (40, 2, 2)


def test_tube_rings_lie_on_the_ellipses_and_face_outward():
    rng = np.random.default_rng(4)
    samples = _line(20) + rng.normal(0, 0.01, (4000, 20, 3))
    vertices, faces = tube(samples, n_sigma=2.0, segments=16)
    assert vertices.shape == (20 * 16, 3) and faces.shape == (2 * 19 * 16, 3)
    assert faces.min() == 0 and faces.max() == len(vertices) - 1
    offsets = vertices.reshape(20, 16, 3) - samples.mean(0)[:, None, :]
    np.testing.assert_allclose(np.linalg.norm(offsets[..., 1:], axis=-1), 0.02, rtol=0.12)
    tri = vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = tri.mean(1) * [0, 1, 1]  # away from the x axis
    assert np.all(np.einsum("ij,ij->i", normal, outward) > 0)


def test_certain_paths_get_the_minimum_radius():
    samples = np.broadcast_to(_line(10), (5, 10, 3))
    vertices, _ = tube(samples, min_radius=0.004, segments=8)
    distance = np.linalg.norm(vertices.reshape(10, 8, 3)[..., 1:], axis=-1)
    np.testing.assert_allclose(distance, 0.004)


def test_polyline_tube_is_at_constant_distance_even_at_a_corner():
    points = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0.1, 0.1, 0.1]], float)
    vertices, faces = polyline_tube(points, radius=0.003, segments=6)
    rings = vertices.reshape(4, 6, 3)
    np.testing.assert_allclose(np.linalg.norm(rings - points[:, None], axis=-1), 0.003)
    assert faces.shape == (2 * 3 * 6, 3)


def test_polyline_tube_survives_repeated_points():
    points = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0.1]], float)
    vertices, _ = polyline_tube(points)
    assert np.all(np.isfinite(vertices))


@pytest.mark.parametrize(
    "kwargs, match",
    [({"points": np.zeros((1, 3))}, "points"), ({"radius": 0.0}, "radius"),
     ({"segments": 2}, "segments")],
)
def test_polyline_tube_errors(kwargs, match):
    args = {"points": np.zeros((3, 3)), **kwargs}
    with pytest.raises(ValueError, match=match):
        polyline_tube(**args)


def test_tube_errors():
    with pytest.raises(ValueError, match="samples"):
        tube(np.zeros((1, 5, 3)))
    with pytest.raises(ValueError, match="segments"):
        tube(np.zeros((2, 5, 3)), segments=2)
    with pytest.raises(ValueError, match="n_sigma"):
        tube(np.zeros((2, 5, 3)), n_sigma=0)


def test_task_colors_depend_on_the_set_not_the_order():
    a = task_colors(["up", "down", "left"])
    b = task_colors(["left", "up", "down"])
    assert a.keys() == b.keys()
    for name in a:
        np.testing.assert_array_equal(a[name], b[name])
    np.testing.assert_array_equal(a["down"], PALETTE[0])
    a["down"][0] = 9.0  # a copy: the palette is untouched
    assert PALETTE[0, 0] != 9.0

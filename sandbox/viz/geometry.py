"""Geometry of the prediction overlays, numpy only (testable without a browser).

- :func:`sample_joint_paths`: joint trajectories drawn from per-step Gaussians
  ``N(mean_i, cov_i)`` with an explicit generator;
- :func:`tube`: an uncertainty tube around the mean of sampled 3-D paths, whose
  cross-section at each step is the ``n_sigma`` ellipse of the samples' spread
  perpendicular to the path;
- :func:`cross_section_radii`: the semi-axes of those ellipses;
- :func:`polyline_tube`: a thin round tube along a path (WebGL lines are 1 px);
- :func:`task_colors`: a fixed colour per task name.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sandbox.validation import check_array, check_positive

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Task colours (RGBA), assigned to task names in sorted order.
PALETTE = np.array([
    [0.12, 0.47, 0.71, 1.0], [1.00, 0.50, 0.05, 1.0], [0.17, 0.63, 0.17, 1.0],
    [0.58, 0.40, 0.74, 1.0], [0.55, 0.34, 0.29, 1.0], [0.89, 0.47, 0.76, 1.0],
    [0.50, 0.50, 0.50, 1.0], [0.74, 0.74, 0.13, 1.0], [0.09, 0.75, 0.81, 1.0],
])


def task_colors(names: Sequence[str]) -> dict[str, FloatArray]:
    """RGBA colour (4,) per task name; stable for a given set of names (sorted order)."""
    return {name: PALETTE[i % len(PALETTE)].copy() for i, name in enumerate(sorted(names))}


def _psd_sqrt(covs: FloatArray) -> FloatArray:
    """Square roots ``L`` (..., d, d) with ``L L^T = cov`` for symmetric PSD ``covs``."""
    sym = 0.5 * (covs + np.swapaxes(covs, -1, -2))
    w, v = np.linalg.eigh(sym)
    return v * np.sqrt(np.clip(w, 0.0, None))[..., None, :]


def sample_joint_paths(
    means: ArrayLike, covs: ArrayLike, n_samples: int, rng: np.random.Generator
) -> FloatArray:
    """Draw joint trajectories from per-step Gaussians, independently per step.

    Parameters
    ----------
    means : array_like, shape (n, Q)
        Mean joint positions per step (rad).
    covs : array_like, shape (n, Q, Q)
        Symmetric positive semi-definite covariances per step (rad²).
    n_samples : int
        Number of trajectories, >= 1.
    rng : numpy.random.Generator
        Source of randomness.

    Returns
    -------
    ndarray, shape (n_samples, n, Q)
    """
    means = check_array(means, "means", 2)
    n, q = means.shape
    covs = check_array(covs, "covs", 3, shape=(n, q, q))
    if int(n_samples) != n_samples or n_samples < 1:
        raise ValueError(f"n_samples: expected an integer >= 1, got {n_samples!r}")
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng: expected a numpy.random.Generator, got {type(rng).__name__}")
    z = rng.standard_normal((int(n_samples), n, q))
    return means + np.einsum("nij,snj->sni", _psd_sqrt(covs), z)


def sample_paths(
    fk: Callable[[FloatArray], FloatArray],
    means: ArrayLike,
    covs: ArrayLike,
    n_samples: int,
    rng: np.random.Generator,
) -> FloatArray:
    """Positions (n_samples, n, 3) of ``fk`` applied to :func:`sample_joint_paths`' draws."""
    joints = sample_joint_paths(means, covs, n_samples, rng)
    return np.asarray(fk(joints), dtype=np.float64)


def _tangents(centers: FloatArray) -> FloatArray:
    """Unit tangents (n, 3) by central differences; still stretches inherit a neighbour's."""
    diff = np.gradient(centers, axis=0) if len(centers) > 1 else np.zeros_like(centers)
    norms = np.linalg.norm(diff, axis=1)
    out = np.zeros_like(centers)
    last = np.array([0.0, 0.0, 1.0])
    moving = np.flatnonzero(norms > 1e-9)
    if moving.size:
        last = diff[moving[0]] / norms[moving[0]]
    for i in range(len(centers)):
        if norms[i] > 1e-9:
            last = diff[i] / norms[i]
        out[i] = last
    return out


def _normal_frames(tangents: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Orthonormal (u, v) perpendicular to each tangent, transported along the path."""
    n = len(tangents)
    u, v = np.zeros((n, 3)), np.zeros((n, 3))
    t0 = tangents[0]
    seed = np.eye(3)[int(np.argmin(np.abs(t0)))]
    prev = seed - np.dot(seed, t0) * t0
    for i in range(n):
        t = tangents[i]
        cand = prev - np.dot(prev, t) * t
        if np.linalg.norm(cand) < 1e-6:
            seed = np.eye(3)[int(np.argmin(np.abs(t)))]
            cand = seed - np.dot(seed, t) * t
        u[i] = cand / np.linalg.norm(cand)
        v[i] = np.cross(t, u[i])
        prev = u[i]
    return u, v


def cross_sections(samples: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Mean path and, per step, a basis of the plane across the path and the spread in it.

    Parameters
    ----------
    samples : array_like, shape (s, n, 3)
        ``s`` sampled paths of ``n`` steps (m), s >= 2.

    Returns
    -------
    centers : ndarray, shape (n, 3)
        Mean path (m).
    basis : ndarray, shape (n, 2, 3)
        Unit vectors (u, v) perpendicular to the path at each step.
    covs : ndarray, shape (n, 2, 2)
        Covariance (m²) of the samples' deviations in that (u, v) plane.
    """
    samples = check_array(samples, "samples", 3, shape=(None, None, 3))
    if samples.shape[0] < 2 or samples.shape[1] < 1:
        raise ValueError(f"samples: expected at least 2 paths of 1 step, got {samples.shape}")
    centers = samples.mean(axis=0)
    u, v = _normal_frames(_tangents(centers))
    basis = np.stack([u, v], axis=1)
    coords = np.einsum("snk,nck->snc", samples - centers, basis)
    covs = np.einsum("sna,snb->nab", coords, coords) / (samples.shape[0] - 1)
    return centers, basis, covs


def cross_section_radii(samples: ArrayLike, n_sigma: float = 2.0) -> FloatArray:
    """Semi-axes (n, 2) m of the ``n_sigma`` spread ellipses across the path, largest first."""
    _, _, covs = cross_sections(samples)
    n_sigma = check_positive(n_sigma, "n_sigma")
    return n_sigma * np.sqrt(np.clip(np.linalg.eigvalsh(covs)[:, ::-1], 0.0, None))


def tube(
    samples: ArrayLike, *, n_sigma: float = 2.0, segments: int = 12, min_radius: float = 0.002
) -> tuple[FloatArray, IntArray]:
    """Triangle mesh of the ``n_sigma`` uncertainty tube around sampled paths.

    The ring at step i is ``c_i + n_sigma * [u_i v_i] L_i [cos θ, sin θ]`` with
    ``L_i L_i^T`` the samples' covariance across the path (:func:`cross_sections`),
    widened to at least ``min_radius`` so a certain prediction stays visible.

    Parameters
    ----------
    samples : array_like, shape (s, n, 3)
        Sampled paths (m), s >= 2.
    n_sigma : float
        Size of the ellipses in standard deviations.
    segments : int
        Vertices per ring, >= 3.
    min_radius : float
        Smallest semi-axis (m), >= 0.

    Returns
    -------
    vertices : ndarray, shape (n * segments, 3)
    faces : ndarray, shape (2 * (n - 1) * segments, 3)
        Triangles joining consecutive rings, outward-facing.
    """
    n_sigma = check_positive(n_sigma, "n_sigma")
    min_radius = check_positive(min_radius, "min_radius", allow_zero=True)
    if int(segments) != segments or segments < 3:
        raise ValueError(f"segments: expected an integer >= 3, got {segments!r}")
    centers, basis, covs = cross_sections(samples)
    w, vecs = np.linalg.eigh(covs)
    vecs[..., 1] *= np.sign(np.linalg.det(vecs))[:, None]  # keep (u, v) orientation: outward faces
    axes = np.maximum(n_sigma * np.sqrt(np.clip(w, 0.0, None)), min_radius)
    return _ring_mesh(centers, basis, vecs * axes[:, None, :], int(segments))


def polyline_tube(
    points: ArrayLike, radius: float = 0.003, segments: int = 8
) -> tuple[FloatArray, IntArray]:
    """Triangle mesh of a round tube of ``radius`` (m) along ``points`` (n, 3), n >= 2.

    WebGL draws lines one pixel wide whatever their width, so paths are drawn
    as thin tubes instead. Returns ``vertices`` (n * segments, 3) and ``faces``.
    """
    points = check_array(points, "points", 2, shape=(None, 3), min_len=2)
    radius = check_positive(radius, "radius")
    if int(segments) != segments or segments < 3:
        raise ValueError(f"segments: expected an integer >= 3, got {segments!r}")
    u, v = _normal_frames(_tangents(points))
    shape = np.broadcast_to(radius * np.eye(2), (len(points), 2, 2))
    return _ring_mesh(points, np.stack([u, v], axis=1), shape, int(segments))


def _ring_mesh(
    centers: FloatArray, basis: FloatArray, shape: FloatArray, segments: int
) -> tuple[FloatArray, IntArray]:
    """Rings ``c_i + [u_i v_i] shape_i [cos θ, sin θ]`` joined into a tube of triangles."""
    theta = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    circle = np.stack([np.cos(theta), np.sin(theta)], axis=1)  # (r, 2)
    plane = np.einsum("nab,rb->nra", shape, circle)  # (n, r, 2) in (u, v)
    vertices = centers[:, None, :] + np.einsum("nra,nak->nrk", plane, basis)
    n = len(centers)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(segments), indexing="ij")
    a = i * segments + j
    b = i * segments + (j + 1) % segments
    c, d = a + segments, b + segments
    faces = np.concatenate([np.stack([a, b, d], -1), np.stack([a, d, c], -1)], axis=1)
    return vertices.reshape(-1, 3), faces.reshape(-1, 3).astype(np.int64)

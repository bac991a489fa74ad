r"""Two-link inverse kinematics of the human arm: the elbow from shoulder, wrist and swivel.

Given the shoulder :math:`S`, the wrist :math:`W` and the segment lengths
:math:`a` (upper arm) and :math:`b` (forearm), the elbow lies on a circle
around the shoulder-wrist axis; the swivel angle :math:`\varphi` says where
(0: its lowest point, > 0: outward):

.. math::

    d = \|W - S\|, \quad n = (W - S)/d, \quad
    x = \frac{a^2 - b^2 + d^2}{2d}, \quad r = \sqrt{a^2 - x^2},

    E = S + x\,n + r\,(\cos\varphi\,u + \sin\varphi\,w),

with :math:`u` the downward direction orthogonal to :math:`n` (the backward
one, :math:`-\hat f`, where :math:`n` is vertical) and :math:`w = u \times n`,
which points outward for an arm pointing forward. Forward is
:math:`\hat f = \hat z \times \hat o` for the outward direction :math:`\hat o`
(away from the body's midline, toward the shoulder).

:math:`d` is clipped to :math:`[|a - b|, a + b]`: a wrist out of reach gives a
straight arm pointing at it (:math:`x = a`, :math:`r = 0`, so
:math:`E = S + a\,n`); one closer than :math:`|a - b|` a fully folded arm on
the same line. A wrist exactly at the shoulder takes :math:`n` straight down.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sandbox.validation import FloatArray, check_array, check_positive

UP = np.array([0.0, 0.0, 1.0])


def check_outward(outward: Sequence[float] | FloatArray) -> FloatArray:
    """Return ``outward`` as a float array after checking it is a horizontal unit vector (3,)."""
    out = np.asarray(outward, dtype=float)
    if out.shape != (3,) or not np.isfinite(out).all() or abs(np.linalg.norm(out) - 1.0) > 1e-9 \
            or abs(out @ UP) > 1e-9:
        raise ValueError(f"outward: expected a horizontal unit vector (3,), got {outward!r}")
    return out


def _rows(*arrays: FloatArray, names: Sequence[str]) -> list[FloatArray]:
    """The arrays as (T, 3) float rows, broadcast together ((3,) counts as one row)."""
    rows = [check_array(np.atleast_2d(a), name, 2, shape=(None, 3))
            for a, name in zip(arrays, names, strict=True)]
    return [np.array(r) for r in np.broadcast_arrays(*rows)]


def _axis(shoulder: FloatArray, hand: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Distance (T,) and unit direction (T, 3) from shoulder to hand (down where they meet)."""
    v = hand - shoulder
    d = np.linalg.norm(v, axis=1)
    n = np.where(d[:, None] > 1e-12, v / np.maximum(d, 1e-12)[:, None], -UP)
    return d, n


def swivel_frame(n: FloatArray, outward: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Unit vectors ``u`` (downward, orthogonal to ``n``) and ``w = u x n``, each (T, 3).

    Parameters
    ----------
    n : ndarray, shape (T, 3)
        Unit shoulder-to-wrist directions.
    outward : ndarray, shape (3,)
        Horizontal unit vector away from the body's midline.
    """
    u = -UP - (n @ -UP)[:, None] * n
    vertical = np.linalg.norm(u, axis=1) < 1e-9
    if vertical.any():
        back = -np.cross(UP, outward)
        u[vertical] = back - (n[vertical] @ back)[:, None] * n[vertical]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(u, n)


def elbow_positions(
    shoulder: FloatArray,
    hand: FloatArray,
    upper_arm: float,
    forearm: float,
    swivel: float | FloatArray,
    *,
    outward: Sequence[float] | FloatArray = (0.0, 1.0, 0.0),
) -> FloatArray:
    """Elbow positions (m) by two-link inverse kinematics (see the module docstring).

    Parameters
    ----------
    shoulder, hand : array_like, shape (T, 3) or (3,)
        Shoulder and wrist positions (m).
    upper_arm, forearm : float
        Segment lengths ``a`` and ``b`` (m, > 0).
    swivel : float or array_like, shape (T,)
        Swivel angle (rad): 0 puts the elbow at the lowest point of its circle,
        > 0 turns it outward.
    outward : array_like, shape (3,)
        Horizontal unit vector from the body's midline toward the shoulder
        (default +y: the tracked arm of the recordings, see
        :mod:`sandbox.data.synthetic.arm`).

    Returns
    -------
    ndarray, shape (T, 3)
        Elbows at ``a`` from the shoulder and ``b`` from the wrist when the
        wrist is reachable; otherwise on the shoulder-wrist line at ``a`` from
        the shoulder (straight arm when too far, folded arm when too close).
    """
    a, b = check_positive(upper_arm, "upper_arm"), check_positive(forearm, "forearm")
    S, W = _rows(shoulder, hand, names=("shoulder", "hand"))
    phi = check_array(np.atleast_1d(swivel), "swivel", 1)[:, None]
    S, W, phi = (np.array(v) for v in np.broadcast_arrays(S, W, phi))
    phi = phi[:, :1]
    d, n = _axis(S, W)
    dc = np.clip(d, max(abs(a - b), 1e-9), a + b)
    x = (a * a - b * b + dc * dc) / (2.0 * dc)  # law of cosines: the circle's centre along n
    r = np.sqrt(np.maximum(a * a - x * x, 0.0))  # and its radius
    u, w = swivel_frame(n, check_outward(outward))
    return S + x[:, None] * n + r[:, None] * (np.cos(phi) * u + np.sin(phi) * w)


def swivel_angle(
    shoulder: FloatArray,
    elbow: FloatArray,
    hand: FloatArray,
    *,
    outward: Sequence[float] | FloatArray = (0.0, 1.0, 0.0),
) -> FloatArray:
    """Swivel angle (rad) of the elbow around the shoulder-wrist axis, shape (T,).

    The inverse of :func:`elbow_positions`: 0 when the elbow is at the lowest
    point of its circle, positive outward, in (-pi, pi].

    Parameters
    ----------
    shoulder, elbow, hand : array_like, shape (T, 3) or (3,)
        Joint positions (m).
    outward : array_like, shape (3,)
        As in :func:`elbow_positions`.
    """
    S, E, W = _rows(shoulder, elbow, hand, names=("shoulder", "elbow", "hand"))
    _, n = _axis(S, W)
    u, w = swivel_frame(n, check_outward(outward))
    e = E - S
    return np.arctan2(np.sum(e * w, axis=1), np.sum(e * u, axis=1))

"""Clean (noise-free) human reach-to-handover motions of the left hand.

A reach is a smooth curve through via-points (a natural cubic spline with
chord-length knots, so its speed along the curve is nearly constant), timed
between ``t_on`` and ``t_off`` like a human reach: a primary submovement (a
skewed minimum-jerk profile over the first ``primary`` fraction of the reach,
covering ``1 - correction`` of the path and aiming ``aim`` metres off) and an
overlapping, slower corrective submovement that covers the rest and removes
the aiming error. The speed is bell-shaped with a long tail,
zero at both ends, and peaks at ~25 % of the reach like the recorded reaches.
Before ``t_on`` the hand is at the first point; after ``t_off`` it holds near
the last one, drifting slowly (``drift``: amplitude per axis, m). A *branch*
adds a smooth deviation that starts at ``t_div`` (diverging tasks), and
:func:`switch_paths` moves smoothly from one task's path to another's (a
change of intent).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from sandbox.data.synthetic.base import minimum_jerk, skewed_minimum_jerk
from sandbox.validation import FloatArray


@dataclass(frozen=True)
class Reach:
    """The geometry and timing of one clean reach.

    Attributes
    ----------
    points : ndarray, shape (K, 3)
        Start, via-points and end (m), K >= 2, in Baxter's base frame.
    t_on, t_off : float
        Start and end of the reach (s); ``t_on`` may be negative (the hand was
        already moving when the recording started).
    skew : float
        Warp of the minimum-jerk phase (see :func:`skewed_minimum_jerk`).
    primary, correction : float
        Duration fraction of the primary submovement, and the fraction of the
        path left to the corrective one (which starts at 0.75 * ``primary``).
    drift, drift_hz : ndarray, shape (3,), and float
        Amplitude (m) and frequency (Hz) of the slow drift while holding.
    branch : ndarray, shape (3,)
        Deviation (m) added from ``t_div`` to ``t_off`` (zeros: none).
    t_div : float
        Start of the branch (s).
    """

    points: FloatArray
    t_on: float
    t_off: float
    skew: float = 0.8
    primary: float = 1.0
    correction: float = 0.0
    aim: FloatArray = field(default_factory=lambda: np.zeros(3))
    drift: FloatArray = field(default_factory=lambda: np.zeros(3))
    drift_hz: float = 0.5
    branch: FloatArray = field(default_factory=lambda: np.zeros(3))
    t_div: float = 0.0

    @property
    def end(self) -> FloatArray:
        """Where the hand comes to rest (m), shape (3,)."""
        return self.points[-1] + self.branch


def spline_through(points: FloatArray, u: FloatArray) -> FloatArray:
    """Points of the natural cubic spline through ``points`` at path parameters ``u``.

    Parameters
    ----------
    points : ndarray, shape (K, 3)
        Points the curve passes through (m), K >= 2.
    u : ndarray, shape (T,)
        Path parameter in [0, 1] (0: first point, 1: last point).

    Returns
    -------
    ndarray, shape (T, 3)
        Positions (m).
    """
    if len(points) == 2:
        return points[0] + np.outer(u, points[1] - points[0])
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
    return CubicSpline(chord / chord[-1], points, bc_type="natural", axis=0)(u)


def submovements(reach: Reach, times: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Progress in [0, 1] of the primary and the corrective submovements at ``times``, (T,)."""
    tau = (times - reach.t_on) / (reach.t_off - reach.t_on)
    main = skewed_minimum_jerk(tau / reach.primary, reach.skew)
    start = 0.75 * reach.primary
    return main, minimum_jerk((tau - start) / (1.0 - start))


def reach_positions(reach: Reach, times: FloatArray) -> FloatArray:
    """Hand positions (m) of a clean reach at ``times`` (s), shape (T, 3)."""
    main, fix = submovements(reach, times)
    u = (1.0 - reach.correction) * main + reach.correction * fix
    path = spline_through(reach.points, u)
    if np.any(reach.aim):
        path = path + np.outer(np.clip(main - fix, 0.0, 1.0), reach.aim)
    if np.any(reach.drift):
        hold = times - reach.t_off
        wave = np.sin(2.0 * np.pi * reach.drift_hz * hold) * minimum_jerk(hold / 0.3)
        path = path + np.outer(wave, reach.drift)
    if np.any(reach.branch):
        w = minimum_jerk((times - reach.t_div) / (reach.t_off - reach.t_div))
        path = path + np.outer(w, reach.branch)
    return path


def switch_paths(
    path_a: FloatArray, path_b: FloatArray, times: FloatArray, t_switch: float, blend_s: float
) -> FloatArray:
    """Follow ``path_a`` until ``t_switch``, then move to ``path_b`` within ``blend_s`` seconds.

    Parameters
    ----------
    path_a, path_b : ndarray, shape (T, k)
        The two tasks' motions on the same ``times`` (hand positions in m, or
        joint angles in rad).
    times : ndarray, shape (T,)
        Sample times (s).
    t_switch : float
        Time (s) the intent changes.
    blend_s : float
        Duration (s) of the minimum-jerk transition (> 0).

    Returns
    -------
    ndarray, shape (T, k)
        The blended motion.
    """
    w = minimum_jerk((times - t_switch) / blend_s)[:, None]
    return (1.0 - w) * path_a + w * path_b
